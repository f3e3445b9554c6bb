"""make bench: the Python module's overhead and its threads (bench/results_python.json).

- step_overhead_us: phymul.step(model, data, 1) called n times against one call of
  phymul.step(model, data, n), per call: what crossing into Python costs per step, on the
  prostate study's scene (examples/prostate/50mL_rigid.yaml), one OpenMP thread.
- two_thread_speedup: two Python threads, each stepping its own model's Data, against the
  same steps in one thread (the GIL released while stepping: 2 when it is).
usage: PYTHONPATH=build/python /usr/bin/python3 bench/python_bench.py OUT.json
"""
import json
import os
import pathlib
import platform
import statistics
import sys
import threading
import time

os.environ["OMP_NUM_THREADS"] = "1"  # before the module loads OpenMP

import phymul  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]
SCENE = ROOT / "examples" / "prostate" / "50mL_rigid.yaml"
STEPS = 2000


def fresh():
    model = phymul.compile(phymul.load_scene(str(SCENE)))
    data = phymul.Data(model)
    phymul.step(model, data, n=200)  # past the start
    return model, data


def overhead(repeats=7):
    """Median over repeats of (n single calls - one call of n) / n, in microseconds."""
    model, data = fresh()
    samples, per_step = [], []
    for _ in range(repeats):
        start = time.perf_counter()
        phymul.step(model, data, n=STEPS)
        batched = time.perf_counter() - start
        start = time.perf_counter()
        for _ in range(STEPS):
            phymul.step(model, data, 1)
        single = time.perf_counter() - start
        samples.append((single - batched) / STEPS * 1e6)
        per_step.append(batched / STEPS * 1e6)
    return statistics.median(samples), statistics.median(per_step), model.nodes


def threads(repeats=5):
    """Median over repeats of (two runs one after the other) / (the same two at once)."""
    ratios = []
    for _ in range(repeats):
        pairs = [fresh(), fresh()]
        start = time.perf_counter()
        for model, data in pairs:
            phymul.step(model, data, n=STEPS)
        sequential = time.perf_counter() - start
        pairs = [fresh(), fresh()]
        workers = [threading.Thread(target=phymul.step, args=(m, d, STEPS)) for m, d in pairs]
        start = time.perf_counter()
        for w in workers:
            w.start()
        for w in workers:
            w.join()
        parallel = time.perf_counter() - start
        ratios.append(sequential / parallel)
    return statistics.median(ratios)


def cpu_model():
    try:
        for line in pathlib.Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.machine()


def main():
    out = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "bench" / "results_python.json"
    call_us, step_us, nodes = overhead()
    speedup = threads()
    result = {
        "scene": str(SCENE.relative_to(ROOT)),
        "nodes": nodes,
        "steps_per_sample": STEPS,
        "step_us": step_us,
        "step_overhead_us": call_us,
        "two_thread_speedup": speedup,
        "machine": cpu_model(),
        "cpus": os.cpu_count(),
        "python": platform.python_version(),
    }
    out.write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
