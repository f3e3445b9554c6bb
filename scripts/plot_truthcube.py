#!/usr/bin/python3
"""Truth Cube: error per bead layer and level, for each model (reads beads.csv)."""
import argparse
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main():
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("beads_csv")
    p.add_argument("output_png")
    a = p.parse_args()
    try:
        d = np.genfromtxt(a.beads_csv, delimiter=",", names=True, dtype=None, encoding="utf-8")
    except OSError as e:
        print(f"plot_truthcube.py: cannot read {a.beads_csv}: {e}", file=sys.stderr)
        return 2
    if d.size == 0:
        print(f"plot_truthcube.py: {a.beads_csv} has no rows", file=sys.stderr)
        return 2
    models = sorted(set(d["model"]))
    strains = sorted(set(d["strain"]))
    fig, axes = plt.subplots(1, len(strains), figsize=(4.2 * len(strains), 4.2), sharey=True)
    axes = np.atleast_1d(axes)
    for ax, strain in zip(axes, strains):
        for model in models:
            rows = d[(d["model"] == model) & (d["strain"] == strain)]
            err = np.sqrt(sum((rows[f"simulated_{c}_m"] - rows[f"measured_{c}_m"]) ** 2
                              for c in "xyz")) * 1e3
            disp = np.sqrt(sum((rows[f"measured_{c}_m"] - rows[f"rest_{c}_m"]) ** 2
                               for c in "xyz")) * 1e3
            layers = sorted(set(rows["k"]))
            ax.plot(layers, [err[rows["k"] == k].mean() for k in layers], "o-",
                    label=f"{model}: mean error")
        ax.plot(layers, [disp[rows["k"] == k].mean() for k in layers], "k--",
                label="measured mean displacement")
        ax.set_title(f"{100 * strain:.4g} % compression")
        ax.set_xlabel("bead layer k (1: base, 7: plate)")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("mm")
    axes[-1].legend(fontsize=8)
    fig.suptitle("Truth Cube: simulated vs measured beads, per layer")
    fig.tight_layout()
    fig.savefig(a.output_png, dpi=110)
    print(f"plot_truthcube.py: wrote {a.output_png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
