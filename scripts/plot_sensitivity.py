#!/usr/bin/env python3
"""The paper-configuration sensitivity (examples/sweeps/prostate_paper_sensitivity.yaml): from
the sweep's results.csv, a Markdown table on stdout (each variation's deformation with the
emptiest and the fullest bladder, their ratio against the paper's ~2, the probe force and the
stitched nodes) and a plot of the ratios.
Usage: plot_sensitivity.py RESULTS.csv OUT.png"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

PAPER_RATIO = 2.0  # about 10 % empty against 5 % full (Marchal et al.)
# column -> (label, SI to shown, unit)
SHOWN = {"bladder_stiffness": ("bladder wall K", 1.0, "N/m"),
         "stiffness": ("prostate K", 1.0, "N/m"),
         "stitch_radius": ("neck stitch radius", 1e3, "mm"),
         "support_stiffness": ("side springs", 1.0, "N/m"),
         "support": ("support", None, ""),
         "lift": ("rigid probe rise", 1e3, "mm"),
         "probe": ("probe", None, "")}


def variation(row):
    for column, (label, scale, unit) in SHOWN.items():
        value = row.get(column, "")
        if value not in ("", None):
            shown = value if scale is None else f"{float(value) * scale:g} {unit}"
            return f"{label} {shown}"
    return "baseline"


def solved(row):
    """How the row's equilibria were found, where a case sets it apart from the sweep's own."""
    if row.get("static_solver") != "relaxation":
        return ""
    how = "kinetic damping" if row.get("relaxation") == "kinetic" else "FIRE"
    tolerance = row.get("contact_tolerance", "")
    return f" ({how}, {float(tolerance):.0e} N)".replace("e-0", "e-") if tolerance else f" ({how})"


def main(results, out):
    with open(results, newline="") as f:
        rows = [r for r in csv.DictReader(f)]
    failed = [r for r in rows if r["status"] != "ok"]
    by = {}
    for r in rows:
        by.setdefault(variation(r) + solved(r), {})[round(float(r["filling"]) * 1e6)] = r
    names = ["baseline"] + sorted(n for n in by if n != "baseline")
    print("| variation | 50 mL | 400 mL | ratio (paper ~2) | probe force 50 / 400 mL | "
          "stitched nodes |")
    print("|---|---|---|---|---|---|")
    ratios = []
    for name in names:
        pair = by.get(name, {})
        if 50 not in pair or 400 not in pair:
            continue
        empty, full = pair[50], pair[400]
        if empty["status"] != "ok" or full["status"] != "ok":
            cells = [f"{float(r['prostate_deformation_pct']):.2f} %" if r["status"] == "ok"
                     else "no equilibrium" for r in (empty, full)]
            print(f"| {name} | {cells[0]} | {cells[1]} | — | — | {empty['stitched_nodes']} |")
            continue
        e, u = float(empty["prostate_deformation_pct"]), float(full["prostate_deformation_pct"])
        ratios.append((name, e / u))
        print(f"| {name} | {e:.2f} % | {u:.2f} % | {e / u:.2f} | "
              f"{float(empty['probe_force_n']):.3f} / {float(full['probe_force_n']):.3f} N | "
              f"{empty['stitched_nodes']} |")
    for r in failed:
        print(f"failed: {variation(r)} at {float(r['filling']) * 1e6:.0f} mL: {r['error']}",
              file=sys.stderr)
    fig, ax = plt.subplots(figsize=(8, 0.45 * len(ratios) + 1.5))
    labels = [n for n, _ in ratios]
    ax.barh(range(len(ratios)), [v for _, v in ratios],
            color=["tab:gray" if n == "baseline" else "tab:blue" for n in labels])
    ax.axvline(1.0, color="k", lw=0.8)
    ax.axvline(PAPER_RATIO, color="tab:red", ls="--", label="the paper (about 2)")
    ax.set_yticks(range(len(ratios)), labels)
    ax.invert_yaxis()
    ax.set_xlabel("prostate deformation, 50 mL bladder over 400 mL")
    ax.set_title("The paper's configuration: one parameter at a time")
    ax.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print(f"plot_sensitivity.py: wrote {out}", file=sys.stderr)
    return 0  # the failed cells are in the table: "no equilibrium"


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1], sys.argv[2]))
