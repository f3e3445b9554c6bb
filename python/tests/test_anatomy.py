"""The patient-anatomy examples (examples/anatomy), run by the program and read back with
pandas and meshio: a prostate meshed from its MRI segmentation under an endorectal probe, and a
bladder read from a fine, irregular STL surface and remeshed."""
import numpy as np
import pytest

from conftest import EXAMPLES, run_cli

pd = pytest.importorskip("pandas")
meshio = pytest.importorskip("meshio")


def run(tmp_path, name):
    out = tmp_path / name
    code, output = run_cli("run", EXAMPLES / "anatomy" / f"{name}.yaml", "-o", out, "-q")
    assert code == 0, output
    monitors = pd.read_csv(out / "monitors.csv")
    frames = sorted(p for p in out.glob(f"{name}_*.vtu")
                    if p.stem[len(name) + 1:].isdigit())  # not the obstacles' frames
    return monitors, meshio.read(frames[0]), meshio.read(frames[-1])


def test_the_mri_prostate_keeps_its_volume_and_the_probe_pushes_it_forward(tmp_path):
    monitors, first, last = run(tmp_path, "prostate_mri")
    volume = monitors["volume_prostate_m3"].to_numpy()
    # The gland's voxels are 47.30 mL; its smoothed surface encloses 1.5 % less (docs/anatomy.md).
    assert volume[0] == pytest.approx(47.30e-6, rel=0.03)
    assert np.abs(volume / volume[0] - 1).max() < 1e-9
    end = monitors.iloc[-1]
    assert end["contact_probe_y_N"] > 0.2  # the probe pushes forward (+y) ...
    assert end["contact_prostate_bladder_z_N"] < 0.0  # ... the bladder rests on the gland
    moved = last.points - first.points
    assert np.isfinite(last.points).all()
    assert moved[:, 1].max() > 3e-3  # 6 mm of probe travel: the back of the gland moves mm


def test_the_stl_bladder_is_remeshed_and_filled(tmp_path):
    monitors, first, last = run(tmp_path, "bladder_from_stl")
    triangles = first.cells_dict["triangle"]
    edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    lengths = np.linalg.norm(first.points[edges[:, 0]] - first.points[edges[:, 1]], axis=1)
    # 5120 triangles of 1 to 3 mm in the file; remeshed to 8 mm
    assert 200 < len(triangles) < 800
    assert lengths.mean() == pytest.approx(8e-3, rel=0.2)
    filled = monitors[monitors["time_s"] >= 0.8]["volume_bladder_m3"].to_numpy()
    assert filled == pytest.approx(250e-6, rel=1e-9)
    assert np.isfinite(last.points).all()
