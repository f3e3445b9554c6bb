"""Label images written by nibabel (a writer we did not write) meshed by `phymul mesh`: the
volume, the physical frame (sform, qform with qfac), no staircase across thick slices, gzip
and plain, both byte orders; and the real prostate segmentation of data/prostate_mri."""
import re

import numpy as np
import pytest

from conftest import SOURCE, run_cli

nib = pytest.importorskip("nibabel")
meshio = pytest.importorskip("meshio")

VOXEL = (0.6, 0.6, 4.0)  # mm: thick slices, as in prostate MRI
SEMI = np.array([18.0, 14.0, 16.0])  # mm, the ellipsoid's semi-axes along the grid's axes


def rotation(axis, degrees):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    a = np.radians(degrees)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(a) * k + (1 - np.cos(a)) * k @ k


def ellipsoid_image(rotate, translate):
    """uint8 labels (1 inside) of the ellipsoid centred at voxel (32.3, 30.7, 7.4), its axes
    the grid's; the affine rotates and translates the grid. Returns data, affine, centre and
    axes in the physical frame (mm)."""
    shape = (64, 60, 16)
    centre_ijk = np.array([32.3, 30.7, 7.4])
    i, j, k = np.meshgrid(*[np.arange(n) for n in shape], indexing="ij")
    local = (np.stack([i, j, k], -1) - centre_ijk) * VOXEL
    data = ((local / SEMI) ** 2).sum(-1) <= 1.0
    affine = np.eye(4)
    affine[:3, :3] = rotate @ np.diag(VOXEL)
    affine[:3, 3] = translate
    return data.astype(np.uint8), affine, affine[:3, :3] @ centre_ijk + translate, rotate


def write(tmp_path, name, image):
    path = tmp_path / name
    nib.save(image, str(path))
    return path


def mesh(path, *args):
    code, out = run_cli("mesh", path, "--labels", "1", *args)
    assert code == 0, out
    return out


def tetra_volume_centroid(points, tetras):
    a, b, c, d = (points[tetras[:, i]] for i in range(4))
    v = np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6.0
    return v, (v[:, None] * (a + b + c + d) / 4.0).sum(0) / v.sum()


def radial_deviation(points, centre, axes):
    """Distance (mm) along the ray from the centre between each point and the ellipsoid."""
    q = (points - centre) @ axes  # the ellipsoid's own frame
    rho = np.sqrt(((q / SEMI) ** 2).sum(1))
    return np.linalg.norm(q, axis=1) * (1.0 - 1.0 / rho)


def voxel_faces(data, affine):
    """Centres (mm) of the faces between a labelled voxel and a background one: the staircase."""
    centres = []
    for axis in range(3):
        index = np.argwhere(np.diff(data.astype(int), axis=axis) != 0).astype(float)
        index[:, axis] += 0.5
        centres.append(index)
    ijk = np.concatenate(centres)
    return ijk @ affine[:3, :3].T + affine[:3, 3]


def check_ellipsoid(tmp_path, path, data, affine, centre, axes):
    out = mesh(path, "--edge", "2 mm", "-o", tmp_path / "volume.vtu")
    volume = meshio.read(tmp_path / "volume.vtu")
    v, centroid = tetra_volume_centroid(volume.points, volume.cells_dict["tetra"])
    exact = 4.0 / 3.0 * np.pi * SEMI.prod()
    assert (v > 0).all()
    # 2 %: the voxels' own estimate of the volume is within 1 % here (centres inside), and the
    # surface's interpolation between 4 mm slices rounds the ends of the ellipsoid.
    assert v.sum() == pytest.approx(exact, rel=0.02)
    # A fifth of the in-plane voxel: the frame (rotation, translation, flips) is the file's.
    assert np.linalg.norm(centroid - centre) < 0.2 * VOXEL[0], centroid - centre
    voxels = float(re.search(r"voxels of .*?, ([\d.]+) mL", out).group(1))
    assert v.sum() / 1000.0 == pytest.approx(voxels, rel=0.02)
    # No staircase. The voxels' own boundary (their faces between label and background) is off
    # the ellipsoid by up to half a slice and more: the surface must stay within an eighth of a
    # slice (less than an in-plane voxel) for 95 % of its points, a quarter slice everywhere
    # (the poles, whose height the slices leave open), and a quarter of the staircase's error.
    mesh(path, "--edge", "2 mm", "--surface-only", "-o", tmp_path / "surface.vtu")
    surface = meshio.read(tmp_path / "surface.vtu")
    deviation = np.abs(radial_deviation(surface.points, centre, axes))
    stairs = np.abs(radial_deviation(voxel_faces(data, affine), centre, axes))
    assert np.percentile(deviation, 95) < VOXEL[2] / 8, np.percentile(deviation, 95)
    assert deviation.max() < VOXEL[2] / 4, deviation.max()
    assert np.percentile(deviation, 95) < np.percentile(stairs, 95) / 4
    return out


def test_an_ellipsoid_in_a_rotated_sform_frame_gzip(tmp_path):
    data, affine, centre, axes = ellipsoid_image(rotation([1, 2, 3], 35), [-40.0, 25.0, 60.0])
    image = nib.Nifti1Image(data, affine)
    image.set_sform(affine, code=1)
    image.set_qform(None, code=0)
    check_ellipsoid(tmp_path, write(tmp_path, "ball.nii.gz", image), data, affine, centre, axes)


def test_an_ellipsoid_with_only_a_qform_flipped_by_qfac_plain(tmp_path):
    flip = rotation([0, 1, 1], -20) @ np.diag([1.0, 1.0, -1.0])  # det -1: qfac -1
    data, affine, centre, axes = ellipsoid_image(flip, [12.0, -7.5, 3.25])
    image = nib.Nifti1Image(data, None)
    image.set_qform(affine, code=1)
    image.set_sform(None, code=0)
    assert image.header["pixdim"][0] == -1.0
    check_ellipsoid(tmp_path, write(tmp_path, "ball.nii", image), data, affine, centre, axes)


def test_big_endian_int16_gives_the_same_mesh_as_little_endian_uint8(tmp_path):
    data, affine, _, _ = ellipsoid_image(rotation([0, 0, 1], 10), [1.0, 2.0, 3.0])
    little = nib.Nifti1Image(data, affine)
    header = nib.Nifti1Header(endianness=">")
    big = nib.Nifti1Image((data * 7).astype(">i2"), affine, header=header)
    assert big.header.endianness == ">"
    a = write(tmp_path, "little.nii.gz", little)
    b = write(tmp_path, "big.nii", big)
    mesh(a, "--edge", "3 mm", "--surface-only", "-o", tmp_path / "a.vtu")
    code, out = run_cli("mesh", b, "--labels", "7", "--edge", "3 mm", "--surface-only", "-o",
                        tmp_path / "b.vtu")
    assert code == 0, out
    np.testing.assert_array_equal(meshio.read(tmp_path / "a.vtu").points,
                                  meshio.read(tmp_path / "b.vtu").points)


def test_a_label_no_voxel_holds_is_refused_naming_the_labels_present(tmp_path):
    data, affine, _, _ = ellipsoid_image(np.eye(3), [0.0, 0.0, 0.0])
    path = write(tmp_path, "ball.nii.gz", nib.Nifti1Image(data, affine))
    code, out = run_cli("mesh", path, "--labels", "3,4", "--edge", "3 mm", "-o", tmp_path / "x.vtu")
    assert code == 1
    assert f"no voxel holds label 3 or 4: the image holds 0 ({(data == 0).sum()} voxels), " \
           f"1 ({(data == 1).sum()} voxels)" in out
    code, out = run_cli("mesh", path, "--edge", "3 mm", "-o", tmp_path / "x.vtu")
    assert code == 1 and "(--labels 1,2)" in out


def test_the_prostate_segmentation_makes_a_closed_positive_mesh_of_its_volume(tmp_path):
    path = SOURCE / "data" / "prostate_mri" / "prostate_00.nii.gz"
    code, out = run_cli("mesh", path, "--labels", "1,2", "--edge", "4 mm", "-o",
                        tmp_path / "prostate.vtu")
    assert code == 0, out
    image = nib.load(str(path))
    labels = np.asarray(image.dataobj)
    gland = np.isin(labels, [1, 2])
    voxel_ml = gland.sum() * abs(np.linalg.det(image.affine[:3, :3])) / 1000.0
    assert voxel_ml == pytest.approx(47.3, abs=0.05)  # data/prostate_mri/SOURCE.md
    volume = meshio.read(tmp_path / "prostate.vtu")
    tetras = volume.cells_dict["tetra"]
    v, centroid = tetra_volume_centroid(volume.points, tetras)
    assert (v > 0).all()
    # 3 %: the voxels overstate a rounded gland by their staircase, chiefly at its two ends.
    assert v.sum() / 1000.0 == pytest.approx(voxel_ml, rel=0.03)
    # The labelled voxels' centroid in the physical frame (nibabel's affine), within 1 mm.
    ijk = np.argwhere(gland)
    voxel_centroid = (image.affine[:3, :3] @ ijk.T).T.mean(0) + image.affine[:3, 3]
    assert np.linalg.norm(centroid - voxel_centroid) < 1.0
    # Closed: every face of the tetrahedra is shared by two of them or lies on the boundary,
    # and the boundary faces' edges are each shared by exactly two boundary faces.
    faces = np.sort(np.concatenate([tetras[:, [0, 1, 2]], tetras[:, [0, 1, 3]],
                                    tetras[:, [0, 2, 3]], tetras[:, [1, 2, 3]]]), axis=1)
    unique, count = np.unique(faces, axis=0, return_counts=True)
    assert count.max() == 2
    boundary = unique[count == 1]
    edges = np.sort(np.concatenate([boundary[:, [0, 1]], boundary[:, [1, 2]],
                                    boundary[:, [0, 2]]]), axis=1)
    assert (np.unique(edges, axis=0, return_counts=True)[1] == 2).all()
    assert re.search(r"smallest dihedral angle [\d.]+ degrees, largest radius-edge ratio", out)
    assert "against the voxels" in out


def test_a_scene_meshes_a_label_image_as_the_command_does(tmp_path):
    data, affine, _, _ = ellipsoid_image(rotation([1, 0, 0], 15), [5.0, 6.0, 7.0])
    write(tmp_path, "ball.nii.gz", nib.Nifti1Image(data, affine))
    (tmp_path / "ball.yaml").write_text("""
simulation: {duration: 0.01 s}
objects:
  - name: ball
    mesh: {file: ball.nii.gz, labels: [1], fill: tetra, edge: 3 mm}
    material: {stiffness: 50 N/m, density: 1000 kg/m^3}
""")
    code, out = run_cli("check", tmp_path / "ball.yaml")
    assert code == 0, out
    _, command = run_cli("mesh", tmp_path / "ball.nii.gz", "--labels", "1", "--edge", "3 mm",
                         "-o", tmp_path / "ball.vtu")
    tetrahedra = re.search(r"ball.vtu: (\d+) tetrahedra, (\d+) points", command)
    assert f"ok (1 objects, {tetrahedra.group(2)} nodes, {tetrahedra.group(1)} cells" in out
    surface = re.search(r"encloses ([\d.]+) mL", command).group(1)
    assert f"enclosing {surface} mL" in out
