#!/usr/bin/python3
"""Plot a `phymul prostate` result: prostate deformation, centre displacement and probe force
against the bladder filling, one line per probe.

usage: plot_prostate.py PROSTATE.json OUTPUT.png
"""

import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    with open(sys.argv[1], encoding="utf-8") as f:
        rows = json.load(f)["fillings"]
    panels = [
        ("prostate_deformation_pct", "prostate height lost to the probe (%)"),
        ("centre_displacement_mm", "prostate centre displacement (mm)"),
        ("probe_force_n", "probe force (N)"),
    ]
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2))
    for probe, marker in (("pressure", "o"), ("rigid", "s")):
        mine = [r for r in rows if r["probe"] == probe]
        if not mine:
            continue
        filling = [r["target_volume_ml"] for r in mine]
        for ax, (key, label) in zip(axes, panels):
            ax.plot(filling, [r[key] for r in mine], marker=marker, label=f"{probe} probe")
            ax.set_xlabel("bladder filling (mL)")
            ax.set_ylabel(label)
            ax.grid(alpha=0.3)
    # The paper's two figures (about 10 % empty, 5 % full), for comparison only.
    axes[0].scatter([min(r["target_volume_ml"] for r in rows), max(r["target_volume_ml"] for r in rows)],
                    [10, 5], marker="x", color="k", label="paper, section 4 (about)")
    axes[0].legend()
    fig.suptitle("phymul prostate: endorectal probe against bladder filling")
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main())
