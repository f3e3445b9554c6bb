"""A probe pushed into a soft block by a Python controller, its force plotted live.

The scene's probe (examples/probe.yaml) is held still; the controller pushes it up 8 mm and
draws it back, and the force the block puts on it is plotted as the run goes (a window when
there is a display; the picture is saved to probe_force.png in any case).
usage: PYTHONPATH=build/python /usr/bin/python3 examples/python/probe_controller.py [OUT_DIR]
"""
import os
import pathlib
import sys

import matplotlib

if not os.environ.get("DISPLAY"):
    matplotlib.use("Agg")  # no window: only the picture
import matplotlib.pyplot as plt  # noqa: E402

import phymul  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
DEPTH, PUSH, HOLD = 0.008, 0.5, 0.8  # m; s to push; s when it starts to draw back


def probe_height(t):
    if t < PUSH:
        return DEPTH * t / PUSH
    if t < HOLD:
        return DEPTH
    return max(0.0, DEPTH * (1.0 - (t - HOLD) / PUSH))


def main():
    out = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else pathlib.Path("results/python")
    out.mkdir(parents=True, exist_ok=True)
    scene = phymul.load_scene(str(HERE.parent / "probe.yaml"))
    scene.obstacles["probe"].motion = [0, 0, 0]  # the controller drives it
    model = phymul.compile(scene)
    data = phymul.Data(model)
    times, forces = [], []

    def controller(model, data):
        data.move_obstacle("probe", [0, 0, probe_height(data.time + data.dt)])

    data.controller = controller
    figure, axes = plt.subplots(figsize=(7, 4))
    (line,) = axes.plot([], [], color="tab:blue")
    axes.set_xlabel("time (s)")
    axes.set_ylabel("force of the probe on the block, z (N)")
    axes.set_xlim(0, PUSH + HOLD + 0.2)
    steps = int(round((PUSH + HOLD + 0.2) / data.dt))
    chunk = max(1, steps // 100)
    for _ in range(0, steps, chunk):
        phymul.step(model, data, n=chunk)
        times.append(data.time)
        forces.append(data.obstacle_forces[0, 2])
        line.set_data(times, forces)
        axes.set_ylim(min(0.0, min(forces)) * 1.1, max(1e-3, max(forces)) * 1.1)
        if matplotlib.get_backend() != "agg":
            plt.pause(0.001)
    axes.set_title(f"probe pushed 8 mm by a Python controller; peak {max(forces):.3f} N")
    figure.tight_layout()
    figure.savefig(out / "probe_force.png", dpi=100)
    print(f"peak force {max(forces):.4f} N at {times[forces.index(max(forces))]:.3f} s; "
          f"{out / 'probe_force.png'}")


if __name__ == "__main__":
    main()
