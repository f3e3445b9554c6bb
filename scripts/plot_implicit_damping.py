#!/usr/bin/env python3
"""Plots the implicit steps' numerical damping (docs/implicit.md) from the CSV that
build/bench/phymul_implicit_damping prints: the mechanical energy over time, velocity Verlet
beside backward Euler at several steps and iteration caps, one panel per scene.

Run: build/bench/phymul_implicit_damping examples > /tmp/damping.csv
     /usr/bin/python3 scripts/plot_implicit_damping.py /tmp/damping.csv docs/images/implicit_damping.png
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(source, target):
    runs = defaultdict(list)
    with open(source) as f:
        for row in csv.DictReader(f):
            key = (row["scene"], row["scheme"], float(row["dt_s"]), int(row["cap"]))
            runs[key].append((float(row["time_s"]), float(row["energy_J"])))
    scenes = sorted({k[0] for k in runs}, reverse=True)
    fig, axes = plt.subplots(1, len(scenes), figsize=(6 * len(scenes), 4.2))
    for ax, scene in zip(axes, scenes):
        for (name, scheme, dt, cap), points in sorted(runs.items()):
            if name != scene:
                continue
            label = (f"Verlet, dt {dt * 1e3:.3g} ms" if scheme == "verlet" else
                     f"implicit, dt {dt * 1e3:.3g} ms, " +
                     ("converged" if cap >= 1000 else f"{cap} iterations"))
            t, e = zip(*points)
            ax.plot(t, [1e3 * v for v in e], label=label,
                    linestyle="-" if scheme == "verlet" or cap >= 1000 else "--")
        ax.set_title(f"{scene.replace('_', ' ')} (no physical damping)")
        ax.set_xlabel("time (s)")
        ax.set_ylabel("mechanical energy (mJ)")
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(target, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
