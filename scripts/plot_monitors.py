#!/usr/bin/python3
"""Plot a phymul monitors.csv (one row per monitored step) to a PNG picture.

usage: plot_monitors.py monitors.csv OUTPUT.png [--title TEXT]

The first column must be `time_s`; every other column gets its own subplot against time.
Column names end with their SI unit (`kinetic_energy_J`, `max_residual_force_N`, ...).
`volume_<name>_m3` columns are shown as the relative change V/V0 - 1, V0 being the first
value; residual forces use a log scale when their values are positive (zeros left out).

Exit status: 0 on success, 2 for a missing, empty or malformed file, 1 when plotting fails.
"""

import argparse
import csv
import math
import os
import sys

UNITS = {"s": "s", "J": "J", "N": "N", "m": "m", "m2": "m²", "m3": "m³", "Pa": "Pa",
         "W": "W", "kg": "kg", "1": ""}


class UsageError(Exception):
    """Bad input from the user: reported on one line, exit status 2."""


def parse_args(argv):
    parser = argparse.ArgumentParser(prog="plot_monitors.py",
                                     description="Plot a phymul monitors.csv to PNG.")
    parser.add_argument("csv", help="monitors.csv written by a phymul run")
    parser.add_argument("output", help="PNG file to write")
    parser.add_argument("--title", default=None, help="figure title (default: the file name)")
    return parser.parse_args(argv)


def to_float(text):
    try:
        return float(text)
    except ValueError:
        return math.nan


def read_columns(path):
    """(names, columns): the header and one list of floats per column; blanks become NaN."""
    if not os.path.isfile(path):
        raise UsageError(f"no such file: {path}")
    with open(path, newline="", encoding="utf-8") as handle:
        rows = [row for row in csv.reader(handle) if any(cell.strip() for cell in row)]
    if not rows:
        raise UsageError(f"{path} is empty (expected a header line starting with time_s)")
    names = [name.strip() for name in rows[0]]
    if names[0] != "time_s":
        raise UsageError(f"{path}: the first column is '{names[0]}', expected 'time_s'")
    if len(names) < 2:
        raise UsageError(f"{path} has no quantity besides time_s")
    data = rows[1:]
    if not data:
        raise UsageError(f"{path} has a header but no data rows")
    columns = [[] for _ in names]
    for line, row in enumerate(data, start=2):
        if len(row) != len(names):
            raise UsageError(f"{path}:{line}: {len(row)} fields, the header has {len(names)}")
        for column, cell in zip(columns, row):
            column.append(to_float(cell.strip()))
    return names, columns


def describe(name):
    """(axis label, kind) for a column name such as kinetic_energy_J or volume_liver_m3."""
    parts = name.split("_")
    if name.startswith("volume_") and name.endswith("_m3") and len(parts) >= 3:
        body = "_".join(parts[1:-1]) or "total"
        return f"volume {body}\nV/V₀ − 1", "volume"
    unit = UNITS.get(parts[-1]) if len(parts) > 1 else None
    words = " ".join(parts[:-1]) if unit is not None else " ".join(parts)
    label = f"{words} ({unit})" if unit else words
    kind = "residual" if "residual" in name else "plain"
    return label, kind


def plot(args):
    import matplotlib

    matplotlib.use("Agg")  # files only: no display under CI or ssh
    import matplotlib.pyplot as plt

    names, columns = read_columns(args.csv)
    out_dir = os.path.dirname(os.path.abspath(args.output))
    if not os.path.isdir(out_dir):
        raise UsageError(f"output directory does not exist: {out_dir}")

    time = columns[0]
    quantities = list(zip(names[1:], columns[1:]))
    count = len(quantities)
    ncols = 1 if count <= 4 else 2
    nrows = math.ceil(count / ncols)
    figure, axes = plt.subplots(nrows, ncols, sharex=True, squeeze=False,
                                figsize=(8 * ncols, 2.6 * nrows + 0.8))
    flat = [axis for row in axes for axis in row]
    for axis in flat[count:]:
        axis.set_visible(False)

    for axis, (name, values) in zip(flat, quantities):
        label, kind = describe(name)
        points = [(t, v) for t, v in zip(time, values) if math.isfinite(t) and math.isfinite(v)]
        if not points:
            axis.text(0.5, 0.5, f"{name}: no finite values", ha="center", va="center",
                      transform=axis.transAxes)
            axis.set_ylabel(label)
            continue
        ts = [t for t, _ in points]
        vs = [v for _, v in points]
        if kind == "volume":
            v0 = vs[0]
            if v0 != 0.0:
                vs = [v / v0 - 1.0 for v in vs]
                axis.axhline(0.0, color="0.6", linewidth=0.8)
            else:
                label = f"{name}\n(V₀ = 0: raw m³)"
        axis.plot(ts, vs, linewidth=1.4, marker="." if len(ts) <= 60 else None)
        # Residuals fall by orders of magnitude as a solve converges; only a log axis shows it.
        # Exact zeros (a body at rest) are left out of the log axis rather than forcing a
        # linear one; a negative value means the column is not a norm, so stay linear.
        if kind == "residual" and any(v > 0.0 for v in vs) and all(v >= 0.0 for v in vs):
            axis.set_yscale("log", nonpositive="mask")
        else:
            axis.ticklabel_format(axis="y", style="sci", scilimits=(-3, 4), useOffset=False)
        axis.set_ylabel(label)
        axis.grid(True, which="major", alpha=0.35)

    for column_index in range(ncols):
        bottom = [axes[r][column_index] for r in range(nrows) if r * ncols + column_index < count]
        if bottom:
            bottom[-1].set_xlabel("time (s)")
            bottom[-1].xaxis.set_tick_params(labelbottom=True)

    figure.suptitle(args.title if args.title is not None else os.path.basename(args.csv))
    figure.tight_layout()
    figure.savefig(args.output, dpi=120)
    plt.close(figure)


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    try:
        plot(args)
    except UsageError as error:
        print(f"plot_monitors.py: {error}", file=sys.stderr)
        return 2
    except ImportError as error:
        print(f"plot_monitors.py: {error}; install the Debian package python3-matplotlib "
              "(make deps-demo) and run with /usr/bin/python3", file=sys.stderr)
        return 1
    except Exception as error:  # noqa: BLE001  (one clear line instead of a traceback)
        print(f"plot_monitors.py: plotting {args.csv} failed: {error}", file=sys.stderr)
        return 1
    print(f"plot_monitors.py: wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
