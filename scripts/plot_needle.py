#!/usr/bin/python3
"""Plot a needle's insertion from a phymul monitors.csv: axial and lateral force against tip
depth, and the target's displacement and the tip-to-target distance against time.

usage: plot_needle.py monitors.csv OUTPUT.png [--needle NAME] [--title TEXT]

The columns read are needle_<NAME>_depth_m, _axial_force_N, _lateral_force_N and, with a
target, _target_distance_m and _target_displacement_m (docs/needles.md). NAME defaults to the
first needle of the file. Exit status: 0 on success, 2 for a missing or malformed file.
"""

import argparse
import csv
import sys


def read(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if len(rows) < 2:
        raise ValueError(f"{path}: no data rows")
    header, data = rows[0], rows[1:]
    return {name: [float(r[k]) for r in data] for k, name in enumerate(header)}


def main(argv):
    parser = argparse.ArgumentParser(prog="plot_needle.py", description=__doc__.split("\n")[0])
    parser.add_argument("csv")
    parser.add_argument("output")
    parser.add_argument("--needle", default=None)
    parser.add_argument("--title", default=None)
    args = parser.parse_args(argv)
    try:
        columns = read(args.csv)
    except (OSError, ValueError, IndexError) as e:
        print(f"plot_needle.py: {e}", file=sys.stderr)
        return 2
    needles = [c[len("needle_"):-len("_depth_m")] for c in columns
               if c.startswith("needle_") and c.endswith("_depth_m")]
    name = args.needle or (needles[0] if needles else None)
    if name not in needles:
        print(f"plot_needle.py: no needle '{name}' in {args.csv} (has: {needles})", file=sys.stderr)
        return 2
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    col = lambda what: columns.get(f"needle_{name}_{what}")
    depth_mm = [1e3 * d for d in col("depth_m")]
    target = col("target_distance_m") is not None
    fig, axes = plt.subplots(1, 2 if target else 1, figsize=(11 if target else 6, 4.2))
    axes = axes if target else [axes]
    axes[0].plot(depth_mm, col("axial_force_N"), label="axial (resisting insertion)")
    axes[0].plot(depth_mm, col("lateral_force_N"), label="lateral")
    axes[0].set_xlabel("tip depth (mm)")
    axes[0].set_ylabel("force on the needle (N)")
    axes[0].legend()
    axes[0].grid(alpha=0.3)
    if target:
        t = columns["time_s"]
        axes[1].plot(t, [1e3 * d for d in col("target_distance_m")], label="tip to target")
        axes[1].plot(t, [1e3 * d for d in col("target_displacement_m")],
                     label="target displacement")
        axes[1].set_xlabel("time (s)")
        axes[1].set_ylabel("mm")
        axes[1].legend()
        axes[1].grid(alpha=0.3)
    fig.suptitle(args.title or f"needle {name}")
    fig.tight_layout()
    fig.savefig(args.output, dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
