"""The prostate study's finding against the prostate's stiffness: the probe's deformation of
the prostate with an empty (50 mL) and a full (400 mL) bladder, for K from 400 to 1000 N/m
(the coarse bladder, rigid probe), plotted to stiffness_sweep.png.
usage: PYTHONPATH=build/python /usr/bin/python3 examples/python/stiffness_sweep.py [OUT_DIR] [--quick]
"""
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import phymul  # noqa: E402


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    out = pathlib.Path(args[0]) if args else pathlib.Path("results/python")
    out.mkdir(parents=True, exist_ok=True)
    stiffnesses = [400.0, 1000.0] if "--quick" in sys.argv else [400.0, 520.0, 640.0, 800.0, 1000.0]
    fillings = {"empty (50 mL)": 50e-6, "full (400 mL)": 400e-6}
    curves = {name: [] for name in fillings}
    for k in stiffnesses:
        table = phymul.prostate(fillings=list(fillings.values()), probes=["rigid"],
                                prostate_stiffness=k, coarse=True)
        for name, row in zip(fillings, table["fillings"]):
            curves[name].append(row["prostate_deformation_pct"])
        print(f"K = {k:6.0f} N/m: " + ", ".join(
            f"{name} {curve[-1]:.2f} %" for name, curve in curves.items()))
    figure, axes = plt.subplots(figsize=(7, 4))
    for name, curve in curves.items():
        axes.plot(stiffnesses, curve, marker="o", label=f"bladder {name}")
    axes.set_xlabel("prostate shape-memory stiffness K (N/m)")
    axes.set_ylabel("prostate deformation by the probe (% of height)")
    axes.legend()
    axes.grid(alpha=0.3)
    figure.tight_layout()
    figure.savefig(out / "stiffness_sweep.png", dpi=100)
    print(out / "stiffness_sweep.png")


if __name__ == "__main__":
    main()
