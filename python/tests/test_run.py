"""Runs from Python give the program's results bit for bit; frames and monitors read back."""
import json
import math

import meshio
import numpy as np
import pytest

import phymul
from conftest import EXAMPLES, run_cli

# Fields of report.json that measure the machine, not the simulation.
WALL = {"wall_time_s", "ns_per_node_per_step", "real_time_factor", "step_wall_time_s",
        "stepping_real_time_factor", "threads"}


def same_report(a, b):
    return {k: v for k, v in a.items() if k not in WALL} == {
        k: v for k, v in b.items() if k not in WALL}


@pytest.mark.parametrize("name", ["hanging_cube", "pressed_block", "probe"])
def test_phymul_run_writes_the_programs_files_byte_for_byte(tmp_path, name):
    scene_file = EXAMPLES / f"{name}.yaml"
    code, output = run_cli("run", scene_file, "-o", tmp_path / "cli")
    assert code == 0, output
    report = phymul.run(str(scene_file), tmp_path / "py")
    assert report["status"] == "completed"
    assert same_report(report, json.loads((tmp_path / "cli" / "report.json").read_text()))
    cli_files = sorted(p.name for p in (tmp_path / "cli").iterdir())
    assert cli_files == sorted(p.name for p in (tmp_path / "py").iterdir())
    for file in cli_files:
        if file != "report.json":
            assert (tmp_path / "cli" / file).read_bytes() == (tmp_path / "py" / file).read_bytes()
    monitors = phymul.read_monitors(tmp_path / "py")
    assert monitors["time_s"][-1] == pytest.approx(report["simulated_time_s"], rel=1e-12)
    assert phymul.read_report(tmp_path / "py")["steps"] == report["steps"]


def test_stepping_from_python_lands_on_the_programs_last_frame_bit_for_bit(tmp_path):
    scene_file = EXAMPLES / "hanging_cube.yaml"
    code, output = run_cli("run", scene_file, "-o", tmp_path)
    assert code == 0, output
    model = phymul.compile(phymul.load_scene(str(scene_file)))
    data = phymul.Data(model)
    # Whole steps up to the duration, as the program takes them.
    steps = math.ceil(model.duration / data.dt - 1e-9)
    data.dt = model.duration / steps
    phymul.step(model, data, n=steps)
    last = sorted(tmp_path.glob("hanging_cube_*.vtu"))[-1]
    written = meshio.read(last).points  # a reader we did not write
    assert np.array_equal(written, data.positions)
    assert np.max(np.abs(data.positions - model.rest_positions)) > 1e-3  # it did hang


def test_a_static_solve_matches_the_program(tmp_path):
    scene_file = EXAMPLES / "pressed_block.yaml"
    code, output = run_cli("run", scene_file, "-o", tmp_path)
    assert code == 0, output
    model = phymul.compile(phymul.load_scene(str(scene_file)))
    assert model.static
    data = phymul.Data(model)
    result = phymul.solve_static(model, data)
    report = json.loads((tmp_path / "report.json").read_text())
    assert result["converged"] and report["converged"]
    assert result["iterations"] == report["steps"]
    assert result["residual"] == report["final_residual_force_N"]
    last = sorted(tmp_path.glob("pressed_block_*.vtu"))[-1]
    assert np.array_equal(meshio.read(last).points, data.positions)


def test_an_edited_scene_runs_as_the_same_edit_in_a_file(tmp_path):
    text = (EXAMPLES / "hanging_cube.yaml").read_text()
    edited_file = tmp_path / "stiffer.yaml"
    edited_file.write_text(text.replace("stiffness: 200 N/m", "stiffness: 350 N/m"))
    code, output = run_cli("run", edited_file, "-o", tmp_path / "cli")
    assert code == 0, output
    scene = phymul.load_scene(str(EXAMPLES / "hanging_cube.yaml"))
    scene.objects["cube"].material.stiffness = "350 N/m"
    phymul.run(scene, tmp_path / "py")
    cli_frames = sorted((tmp_path / "cli").glob("stiffer_*.vtu"))
    py_frames = sorted((tmp_path / "py").glob("hanging_cube_*.vtu"))
    assert len(cli_frames) == len(py_frames) > 2
    for a, b in zip(cli_frames, py_frames):
        assert a.read_bytes() == b.read_bytes()


def test_the_result_writer_writes_frames_meshio_reads(tmp_path):
    model = phymul.compile(phymul.load_scene(str(EXAMPLES / "hanging_cube.yaml")))
    data = phymul.Data(model)
    writer = phymul.ResultWriter(model, str(tmp_path), "mine")
    for _ in range(3):
        phymul.step(model, data, n=10)
        writer.frame(data)
        writer.monitor(data)
    writer.finish(data)
    frames = sorted(tmp_path.glob("mine_*.vtu"))
    assert len(frames) == 3
    assert np.array_equal(meshio.read(frames[-1]).points, data.positions)
    monitors = phymul.read_monitors(tmp_path)
    assert len(monitors["time_s"]) == 3 and monitors["time_s"][-1] == data.time
    assert phymul.read_report(tmp_path)["steps"] == 30
    other = phymul.Data(phymul.compile(phymul.load_scene(str(EXAMPLES / "hanging_cube.yaml"))))
    with pytest.raises(ValueError, match="another Model"):
        writer.frame(other)
