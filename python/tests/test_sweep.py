"""Parameter sweeps on a real Dask cluster: a `dask scheduler` and `dask worker` processes on
127.0.0.1, `phymul sweep` against them; results compared with serial runs, bit for bit."""
import contextlib
import csv
import json
import pathlib
import signal
import subprocess
import sys
import time

import pytest

import phymul
from conftest import EXAMPLES, cli, run_cli
from phymul.sweep import _plan, read_sweep

DASK = pathlib.Path(sys.executable).with_name("dask")
CUBE = EXAMPLES / "hanging_cube.yaml"


def wait_for(condition, seconds, what):
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(0.02)
    pytest.fail(f"timed out after {seconds} s waiting for {what}")


class DaskCluster:
    """A scheduler and `workers` worker processes (one thread each, no nanny: a killed worker
    stays dead), each in its own session so that no signal of the tests reaches them."""

    def __init__(self, directory):
        self.directory, self.processes, self.workers = directory, [], []
        self.scheduler_file = directory / "scheduler.json"
        self.address = None

    def start(self, workers):
        from distributed import Client

        self._start("scheduler", "scheduler", "--host", "127.0.0.1", "--port", "0",
                    "--no-dashboard", "--dashboard-address", "127.0.0.1:0",
                    "--scheduler-file", self.scheduler_file)
        self.address = wait_for(self._written_address, 60,
                                f"the scheduler ({self.directory}/*.log)")
        for k in range(workers):
            self.workers.append(self._start(
                f"worker{k}", "worker", self.address, "--nthreads", "1", "--no-nanny",
                "--host", "127.0.0.1", "--no-dashboard", "--dashboard-address", "127.0.0.1:0",
                "--memory-limit", "0", "--name", f"w{k}"))
        with Client(self.address, timeout="30s") as client:
            client.wait_for_workers(workers, timeout=60)

    def _written_address(self):
        try:
            return json.loads(self.scheduler_file.read_text())["address"]
        except (OSError, ValueError, KeyError):
            return None

    def _start(self, log, *args):
        with open(self.directory / f"{log}.log", "wb") as out:
            p = subprocess.Popen([str(DASK), *map(str, args)], stdout=out,
                                 stderr=subprocess.STDOUT, start_new_session=True)
        self.processes.append(p)
        return p

    def close(self):
        for p in reversed(self.processes):
            if p.poll() is None:
                p.terminate()
        for p in self.processes:
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


@contextlib.contextmanager
def dask_cluster(directory, workers=2):
    directory.mkdir(parents=True, exist_ok=True)
    cluster = DaskCluster(directory)
    try:
        cluster.start(workers)
        yield cluster
    finally:
        cluster.close()


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    with dask_cluster(tmp_path_factory.mktemp("dask"), workers=2) as c:
        yield c


def write_sweep(path, text):
    path.write_text(text.replace("CUBE", str(CUBE)))
    return path


def read_results(out):
    with open(out / "results.csv", newline="") as f:
        return list(csv.DictReader(f))


# Twelve samples of the hanging cube: 4 stiffnesses x 3 dampings, short runs.
GRID = """scene: CUBE
set:
  simulation.duration: DURATION
parameters:
  - path: objects[cube].material.stiffness
    range: {min: 100 N/m, max: 400 N/m, count: 4}
  - path: simulation.damping
    values: [3 1/s, 6 1/s, 12 1/s]
outputs:
  - steps
  - final_residual_force_N
  - monitor: kinetic_energy_J
  - monitor: volume_cube_m3
    of: max
"""


def serial_run(stiffness, damping, duration, out):
    scene = phymul.load_scene(str(CUBE))
    scene.simulation.duration = duration
    scene.objects["cube"].material.stiffness = stiffness
    scene.simulation.damping = damping
    return phymul.run(scene, out)


def test_a_12_sample_sweep_on_two_workers_equals_the_serial_runs(cluster, tmp_path):
    sweep_file = write_sweep(tmp_path / "sweep.yaml", GRID.replace("DURATION", "0.3 s"))
    code, output = run_cli("sweep", sweep_file, "-o", tmp_path / "out", "--scheduler",
                           cluster.address)
    assert code == 0, output
    assert "12 samples, 12 ok, 0 failed" in output
    rows = read_results(tmp_path / "out")
    assert [(float(r["objects[cube].material.stiffness"]), float(r["simulation.damping"]))
            for r in rows] == [(k, c) for k in (100.0, 200.0, 300.0, 400.0)
                               for c in (3.0, 6.0, 12.0)]
    assert {r["status"] for r in rows} == {"ok"}
    assert len({r["worker"] for r in rows}) == 2  # both workers took samples
    for k, row in enumerate(rows):
        serial = tmp_path / "serial" / str(k)
        report = serial_run(float(row["objects[cube].material.stiffness"]),
                            float(row["simulation.damping"]), 0.3, serial)
        monitors = phymul.read_monitors(serial)
        assert int(row["steps"]) == report["steps"] > 100
        assert float(row["final_residual_force_N"]) == report["final_residual_force_N"]
        assert float(row["kinetic_energy_J"]) == monitors["kinetic_energy_J"][-1] > 0
        assert float(row["max_volume_cube_m3"]) == monitors["volume_cube_m3"].max()
        sample = tmp_path / "out" / "samples" / row["sample"]
        assert (sample / "monitors.csv").read_bytes() == (serial / "monitors.csv").read_bytes()
        assert phymul.read_report(sample)["threads"] == 1  # one core per sample
        # The sample's scene is a scene file the program runs.
        assert run_cli("check", sample / "scene.yaml")[0] == 0
    # Stiffer cubes settle in more steps (a smaller stable step): the grid did vary.
    assert int(rows[9]["steps"]) > int(rows[0]["steps"])
    assert (tmp_path / "out" / "summary.png").stat().st_size > 10_000


def test_killing_a_worker_mid_sweep_still_completes_every_sample(tmp_path):
    with dask_cluster(tmp_path / "dask", workers=2) as c:
        sweep_file = write_sweep(tmp_path / "sweep.yaml", GRID.replace("DURATION", "2.5 s"))
        out = tmp_path / "out"
        sweep = subprocess.Popen([cli(), "sweep", sweep_file, "-o", out, "--scheduler", c.address],
                                 stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        finished = lambda: (out / "results.csv").exists() and sum(  # noqa: E731
            r["status"] == "ok" for r in read_results(out))
        done_before = wait_for(finished, 60, "the first finished sample")
        victim = c.workers[1]
        victim.send_signal(signal.SIGKILL)
        victim.wait(timeout=10)
        output, _ = sweep.communicate(timeout=120)
        assert done_before < 12, "the sweep ended before the worker was killed"
        assert sweep.returncode == 0, output
        rows = read_results(out)
        assert [r["status"] for r in rows] == ["ok"] * 12
        assert all((out / "samples" / r["sample"] / "report.json").exists() for r in rows)
        assert not list((out / "samples").glob(".*"))  # no partial attempt left behind


CASES = """scene: CUBE
set:
  simulation.duration: 0.2 s
cases:
  - objects[cube].material.stiffness: 200 N/m
  - objects[cube].material.stiffness: -50 N/m
  - objects[cube].material.stiffness: 300 N/m
    simulation.dt: 10 ms
  - objects[cube].material.stiffness: 400 N/m
  - objects[cube].material.stiffness: 250 N/m
    simulation.damping: 2 1/s
"""


def test_a_sample_with_an_invalid_value_fails_alone(cluster, tmp_path):
    sweep_file = write_sweep(tmp_path / "sweep.yaml", CASES)
    code, output = run_cli("sweep", sweep_file, "-o", tmp_path / "out", "--scheduler",
                           cluster.scheduler_file)  # the scheduler named by its file
    assert code == 2, output  # ran, with failed samples
    rows = read_results(tmp_path / "out")
    assert [r["status"] for r in rows] == ["ok", "failed", "failed", "ok", "ok"]
    # A parameter that only some cases set: the summary still plots what varies.
    assert float(rows[4]["simulation.damping"]) == 2.0 and rows[0]["simulation.damping"] == ""
    assert (tmp_path / "out" / "summary.png").exists()
    assert rows[1]["error"] == (
        f"{sweep_file}:6:39: objects[cube].material.stiffness = -50 N/m: 'stiffness' must be "
        "> 0 N/m (got -50 N/m)")
    assert not (tmp_path / "out" / "samples" / rows[1]["sample"]).exists()  # never ran
    # The third ran, and became unstable: its directory says so.
    assert rows[2]["error"].startswith("unstable: the simulation became unstable at t = ")
    assert phymul.read_report(tmp_path / "out" / "samples" / rows[2]["sample"])["status"] == \
        "unstable"
    assert rows[2]["simulation.dt"] == "0.01" and rows[0]["simulation.dt"] == ""
    assert int(rows[3]["steps"]) > int(rows[0]["steps"]) > 0
    assert f"sample {rows[1]['sample']} failed: " in output


def test_resume_after_an_interrupt_reruns_nothing_finished(cluster, tmp_path):
    sweep_file = write_sweep(tmp_path / "sweep.yaml", GRID.replace("DURATION", "0.5 s"))
    out = tmp_path / "out"
    code, output = run_cli("sweep", sweep_file, "-o", out, "--scheduler", cluster.address,
                           "--stop-after", 5)
    assert code == 130, output
    assert "--resume" in output
    rows = read_results(out)
    assert sum(r["status"] == "ok" for r in rows) == 5
    assert {r["status"] for r in rows} == {"ok", "pending"}
    time.sleep(1.0)  # tasks already running when it stopped finish on their workers
    finished = {p.parent.name: p.stat().st_mtime_ns
                for p in (out / "samples").glob("*/report.json")}
    assert 5 <= len(finished) < 12
    # Without --resume the directory is not overwritten.
    code, output = run_cli("sweep", sweep_file, "-o", out, "--scheduler", cluster.address)
    assert code == 1 and "results.csv exists" in output
    code, output = run_cli("sweep", sweep_file, "-o", out, "--scheduler", cluster.address,
                           "--resume")
    assert code == 0, output
    assert f"12 samples, 12 ok, 0 failed ({len(finished)} kept from before)" in output
    rows = read_results(out)
    assert [r["status"] for r in rows] == ["ok"] * 12
    for sample, mtime in finished.items():
        assert (out / "samples" / sample / "report.json").stat().st_mtime_ns == mtime
    assert len(list((out / "samples").glob("*/report.json"))) == 12


def test_ctrl_c_stops_the_sweep_and_keeps_what_finished(cluster, tmp_path):
    sweep_file = write_sweep(tmp_path / "sweep.yaml", GRID.replace("DURATION", "1.5 s"))
    out = tmp_path / "out"
    sweep = subprocess.Popen([cli(), "sweep", sweep_file, "-o", out, "--scheduler",
                              cluster.address], stdout=subprocess.PIPE,
                             stderr=subprocess.STDOUT, text=True)
    wait_for(lambda: (out / "results.csv").exists() and any(
        r["status"] == "ok" for r in read_results(out)), 60, "the first finished sample")
    sweep.send_signal(signal.SIGINT)  # the program became the Python sweep: same process
    output, _ = sweep.communicate(timeout=60)
    assert sweep.returncode == 130, output
    rows = read_results(out)
    assert 1 <= sum(r["status"] == "ok" for r in rows) < 12
    assert "interrupted" in output


def test_a_latin_hypercube_from_python_puts_one_sample_in_each_stratum(cluster, tmp_path):
    spec = {"scene": str(CUBE),
            "set": {"simulation.duration": "0.1 s"},
            "sampling": {"method": "latin-hypercube", "samples": 6, "seed": 7},
            "parameters": [
                {"path": "objects[cube].material.stiffness",
                 "range": {"min": "100 N/m", "max": "700 N/m"}},
                {"path": "simulation.damping", "range": {"min": 0, "max": 6}}],
            "outputs": ["steps"]}
    frame = phymul.sweep(spec, tmp_path / "a", scheduler=cluster.address)
    assert list(frame["status"]) == ["ok"] * 6
    stiffness = frame["objects[cube].material.stiffness"]
    assert sorted(int((k - 100) // 100) for k in stiffness) == [0, 1, 2, 3, 4, 5]
    assert sorted(int(c) for c in frame["simulation.damping"]) == [0, 1, 2, 3, 4, 5]
    again = phymul.sweep(spec, tmp_path / "b", scheduler=cluster.address)
    assert list(again["sample"]) == list(frame["sample"])  # the seed fixes the samples
    assert list(again["steps"]) == list(frame["steps"])


def test_a_prostate_study_sweep_gives_the_studys_own_figures(cluster, tmp_path):
    sweep_file = write_sweep(tmp_path / "sweep.yaml", """study: prostate
set: {coarse: true, filling: 100 mL}
parameters:
  - path: force
    values: [1 N, 2.5 N]
outputs: [prostate_deformation_pct, {study: probe_force_n, name: force_N}]
""")
    code, output = run_cli("sweep", sweep_file, "-o", tmp_path / "out", "--scheduler",
                           cluster.address)
    assert code == 0, output
    rows = read_results(tmp_path / "out")
    for row, force in zip(rows, ("1", "2.5")):
        json_file = tmp_path / f"study_{force}.json"
        code, text = run_cli("prostate", "--fillings", 100, "--probe", "pressure", "--force",
                             force, "--coarse-bladder", "--no-real-time", "--no-pictures", "-q",
                             "-o", tmp_path / f"study_{force}", "--json", json_file)
        assert code == 0, text
        figures = json.loads(json_file.read_text())["fillings"][0]
        assert float(row["prostate_deformation_pct"]) == figures["prostate_deformation_pct"]
        assert float(row["force_N"]) == figures["probe_force_n"]
    deformations = [float(r["prostate_deformation_pct"]) for r in rows]
    assert deformations[1] > 2 * deformations[0] > 0  # 2.5 times the force


def test_a_sweep_over_the_prostates_springs_in_the_papers_configuration(cluster, tmp_path):
    # --support bladder: the prostate hangs from the bladder; springs on its sides hold it
    # more the stiffer they are, so the rigid probe's rise deforms it more and the bladder's
    # top node holds less.
    sweep_file = write_sweep(tmp_path / "sweep.yaml", """study: prostate
set: {coarse: true, filling: 50 mL, probe: rigid, support: bladder}
parameters:
  - path: support_stiffness
    values: [2 N/m, 50 N/m]
outputs: [prostate_deformation_pct, hold_force_n, top_node_force_n]
""")
    code, output = run_cli("sweep", sweep_file, "-o", tmp_path / "out", "--scheduler",
                           cluster.address)
    assert code == 0, output
    soft, stiff = read_results(tmp_path / "out")
    assert float(stiff["prostate_deformation_pct"]) > float(soft["prostate_deformation_pct"])
    assert float(soft["top_node_force_n"]) > float(stiff["top_node_force_n"]) > 0


def test_a_local_cluster_runs_the_sweep_by_default(tmp_path):
    sweep_file = write_sweep(tmp_path / "sweep.yaml", """scene: CUBE
set: {simulation.duration: 0.1 s}
parameters:
  - path: simulation.damping
    values: [2, 4, 8]
outputs: [steps, {monitor: kinetic_energy_J}]
""")
    code, output = run_cli("sweep", sweep_file, "-o", tmp_path / "out", "--workers", 2)
    assert code == 0, output
    rows = read_results(tmp_path / "out")
    assert [r["status"] for r in rows] == ["ok"] * 3
    assert all(r["worker"].startswith("tcp://127.0.0.1:") for r in rows)
    energies = [float(r["kinetic_energy_J"]) for r in rows]
    assert energies[0] > energies[1] > energies[2] > 0  # more damping, less motion


def test_the_local_cluster_listens_on_127_0_0_1_only():
    import psutil

    from phymul.sweep import _Cluster

    me = psutil.Process()
    others = {p.pid for p in me.children(recursive=True)}  # the module's own cluster
    with _Cluster(None, 2) as client:
        assert len(client.scheduler_info()["workers"]) == 2
        processes = [me] + [p for p in me.children(recursive=True) if p.pid not in others]
        listening = [c.laddr for p in processes for c in p.connections(kind="inet")
                     if c.status == psutil.CONN_LISTEN]
    assert len(listening) >= 5  # the scheduler, its HTTP server, each worker and its nanny
    assert {a.ip for a in listening} == {"127.0.0.1"}


BAD = """scene: CUBE
sampling: {method: sobol, samples: 4}
parameters:
  - path: objects[cbe].material.stiffness
    range: {min: 100 N/m, max: 400 N/m}
  - path: simulation.damping
    range: {min: 6 1/s, max: 2 1/s}
  - path: simulation.duration
    values: [1 kg]
  - path: objects[cube].material.stifness
    values: [1]
outputs:
  - monitor: volume_cub_m3
"""


def test_sweep_file_errors_name_file_line_column_and_what_is_allowed(tmp_path):
    sweep_file = write_sweep(tmp_path / "bad.yaml", BAD)
    code, output = run_cli("sweep", sweep_file, "-o", tmp_path / "out")
    assert code == 1
    f = str(sweep_file)
    assert output.splitlines() == [
        f"{f}:2:11: sampling needs 'seed'",
        f"{f}:2:20: unknown sampling method 'sobol' (allowed: random, latin-hypercube)",
        f"{f}:4:11: unknown parameter path 'objects[cbe].material.stiffness' (known objects: "
        "cube); did you mean 'cube'?",
        f"{f}:7:12: empty range for 'simulation.damping': min 6.0 > max 2.0",
        f"{f}:9:14: simulation.duration = 1 kg: 'duration' expects a time (s, ms, min, ...), "
        "got 'kg'",
        f"{f}:10:11: unknown parameter path 'objects[cube].material.stifness': 'stifness' is "
        "not a field of an object's material you can vary (known: stiffness, young, poisson, "
        "calibration_axis, hourglass, law, hexa, density, mass, frame, reaction); did you mean "
        "'stiffness'?",
        f"{f}:13:14: 'volume_cub_m3' is not a column of this scene's monitors.csv (columns: "
        "time_s, kinetic_energy_J, shape_memory_energy_J, max_residual_force_N, "
        "volume_cube_m3); did you mean 'volume_cube_m3'?",
        "7 problem(s) found"]
    assert not (tmp_path / "out").exists()
    with pytest.raises(phymul.SceneError) as e:  # the same from Python
        phymul.sweep(str(sweep_file), tmp_path / "out")
    assert len(e.value.diagnostics) == 7


@pytest.mark.parametrize("text, message", [
    ("scene: CUBE\nparameters:\n  - path: simulation.damping\n    range: {min: 1, max: 2}\n",
     "4:12: range of 'simulation.damping' needs 'count'"),
    ("scene: CUBE\nparameters:\n  - path: simulation.damping\n", "3:5: parameter "
     "'simulation.damping' needs either values: [...] or range: {min, max, count}"),
    ("scene: CUBE\nparameters:\n  - path: obstacles[probe].radius\n    values: [1 mm]\n",
     "3:11: unknown parameter path 'obstacles[probe].radius' (known obstacles (by name): "
     "none)"),
    ("scene: CUBE\nparameters:\n  - path: simulation.duration\n    values: []\n",
     "4:13: the list of values of 'simulation.duration' is empty"),
    ("scene: CUBE\nparameters:\n  - path: objects[cube].target_volume[3]\n    values: [1 mL]\n",
     "3:11: 'objects[cube].target_volume[3]': the scene gives this schedule no events"),
    ("scene: CUBE\nparameters:\n  - path: constraints[cube].displacement\n    values: [1]\n",
     "3:11: unknown parameter path 'constraints[cube].displacement': constraints[cube] holds "
     "its nodes fixed"),
    ("scene: CUBE\nsampling: {method: random, samples: 3, seed: 1}\nparameters:\n  - path: "
     "simulation.damping\n    range: {min: 1, max: 2, count: 2}\n",
     "5:29: unknown key 'count' in range of 'simulation.damping' (allowed: min, max, scale)"),
    ("scene: nowhere.yaml\ncases: [{simulation.damping: 1}]\n",
     "1:8: cannot read the base scene"),
    ("study: prostate\nparameters:\n  - path: force\n    range: {min: 0.5 N, max: 500 N, "
     "count: 3}\n", "4:30: force = 500 N: 'force' must be in [0.001, 100] N (got 500 N)"),
])
def test_more_sweep_file_errors(tmp_path, text, message):
    sweep_file = write_sweep(tmp_path / "bad.yaml", text)
    with pytest.raises(phymul.SceneError) as e:
        phymul.sweep(str(sweep_file), tmp_path / "out")
    assert e.value.diagnostics[0].startswith(f"{sweep_file}:{message}"), e.value.diagnostics


def test_edited_scenes_keep_every_value_the_python_api_sets(tmp_path):
    """The sample's scene file holds exactly the edited scene: pressure schedules, obstacle
    motions, volumes, material swaps, read back by the scene parser."""
    prostate = EXAMPLES / "prostate" / "coarse"
    spec = {"scene": str(prostate / "50mL_pressure.yaml"),
            "cases": [{"loads[prostate].pressure[-1]": "5 kPa",
                       "objects[bladder].target_volume": "200 mL",
                       "objects[prostate].material.stiffness": "0.7 kN/m"}]}
    sample = _plan(read_sweep(spec), tmp_path)[0]
    edited = phymul.Scene.from_yaml(sample.task["scene"], str(tmp_path / "scene.yaml"))
    assert edited.pressures[0].pressure == [(0.0, 0.0), (0.2, 0.0), (1.0, 5000.0)]
    assert edited.objects["bladder"].target_volume == [(0.0, 2e-4)]
    assert edited.objects["prostate"].material.stiffness == 700.0
    rigid = {"scene": str(prostate / "50mL_rigid.yaml"),
             "cases": [{"obstacles[probe].motion[2]": [0, 0, "6 mm"],
                        "obstacles[probe].radius": "12 mm", "simulation.dt": "auto"}]}
    sample = _plan(read_sweep(rigid), tmp_path)[0]
    edited = phymul.Scene.from_yaml(sample.task["scene"], str(tmp_path / "scene.yaml"))
    assert edited.obstacles["probe"].motion[2] == (1.0, (0.0, 0.0, 0.006))
    assert edited.obstacles["probe"].radius == 0.012
