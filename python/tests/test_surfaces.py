"""Closed surfaces from STL, OBJ and PLY files written by meshio (a writer we did not write):
read, merged, checked, repaired, and simulated as an organ's boundary."""
import re

import numpy as np
import pytest

meshio = pytest.importorskip("meshio")

import phymul  # noqa: E402


def icosphere(radius, subdivisions=2):
    """Points (m) and outward triangles of a subdivided icosahedron."""
    t = (1 + 5 ** 0.5) / 2
    p = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
         (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    points = [np.array(q, float) / np.linalg.norm(q) for q in p]
    for _ in range(subdivisions):
        middle, faces = {}, []

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in middle:
                m = points[a] + points[b]
                points.append(m / np.linalg.norm(m))
                middle[key] = len(points) - 1
            return middle[key]

        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            faces += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = faces
    return radius * np.array(points), np.array(f, dtype=np.int64)


def write(tmp_path, name, points, triangles, **options):
    path = tmp_path / name
    meshio.write(path, meshio.Mesh(points, [("triangle", triangles)]), **options)
    return path


def volume(points, triangles):
    a, b, c = points[triangles[:, 0]], points[triangles[:, 1]], points[triangles[:, 2]]
    return np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0


FORMATS = [("ball_ascii.stl", {"binary": False}), ("ball_binary.stl", {"binary": True}),
           ("ball.obj", {}), ("ball_ascii.ply", {"binary": False}),
           ("ball_binary.ply", {"binary": True})]


@pytest.mark.parametrize("name,options", FORMATS)
def test_each_format_reads_back_the_surface_meshio_wrote(tmp_path, name, options):
    points, triangles = icosphere(20.0)  # mm
    mesh = phymul.read_mesh(str(write(tmp_path, name, points, triangles, **options)), 1000.0)
    assert mesh["points"].shape == (len(points), 3)  # STL's repeated corners merged
    got = mesh["cells"]["triangle"]
    assert got.shape == triangles.shape
    # The same points (STL stores float32) and the same triangles, up to renumbering.
    tolerance = 1e-6 * 0.02 if name.endswith(".stl") else 1e-12
    order = [np.argmin(np.linalg.norm(points / 1000.0 - q, axis=1)) for q in mesh["points"]]
    np.testing.assert_allclose(mesh["points"], points[order] / 1000.0, atol=tolerance)
    renamed = {tuple(sorted(np.array(order)[t])) for t in got}
    assert renamed == {tuple(sorted(t)) for t in triangles}
    assert volume(mesh["points"], got) == pytest.approx(volume(points, triangles) / 1e9, rel=1e-5)
    if name.endswith(".stl"):
        assert any("repeated vertices merged" in n for n in mesh["notes"])


def test_a_surface_turned_inside_out_or_partly_flipped_is_repaired_and_said_so(tmp_path):
    points, triangles = icosphere(0.02)
    inside_out = triangles[:, [0, 2, 1]]
    mesh = phymul.read_mesh(str(write(tmp_path, "in.obj", points, inside_out)))
    assert any("inside out" in n for n in mesh["notes"])
    assert volume(mesh["points"], mesh["cells"]["triangle"]) > 0
    partly = triangles.copy()
    partly[::7] = partly[::7][:, [0, 2, 1]]
    mesh = phymul.read_mesh(str(write(tmp_path, "partly.ply", points, partly)))
    flipped = len(range(0, len(triangles), 7))
    assert any(f"{flipped} triangles flipped" in n for n in mesh["notes"]), mesh["notes"]
    assert volume(mesh["points"], mesh["cells"]["triangle"]) == pytest.approx(
        volume(points, triangles), rel=1e-12)


def test_open_non_manifold_and_self_intersecting_surfaces_are_refused_by_name(tmp_path):
    points, triangles = icosphere(0.02)
    with pytest.raises(phymul.MeshFileError, match=r"edge \(\d+, \d+\) belongs to triangle \d+ "
                                                   r"only: the surface is not closed"):
        phymul.read_mesh(str(write(tmp_path, "open.stl", points, triangles[1:])))
    fin = np.vstack([points, [[0.05, 0.0, 0.0]]])
    a, b = triangles[0][:2]
    fins = np.vstack([triangles, [[a, b, len(points)]]])
    with pytest.raises(phymul.MeshFileError, match=r"is shared by 3 triangles"):
        phymul.read_mesh(str(write(tmp_path, "fin.obj", fin, fins)))
    two = np.vstack([points, points + [0.01, 0.0, 0.0]])
    both = np.vstack([triangles, triangles + len(points)])
    with pytest.raises(phymul.MeshFileError, match=r"triangles \d+ and \d+ intersect"):
        phymul.read_mesh(str(write(tmp_path, "two.ply", two, both)))
    (tmp_path / "ball.off").write_text("OFF\n")
    with pytest.raises(phymul.MeshFileError, match="unknown mesh file type '.off'"):
        phymul.read_mesh(str(tmp_path / "ball.off"))


def test_an_stl_surface_is_simulated_as_a_closed_organ(tmp_path):
    points, triangles = icosphere(20.0)
    write(tmp_path, "ball.stl", points, triangles, binary=True)
    scene_text = """
simulation: {dt: auto, duration: 0.2 s, gravity: [0, 0, -9.81 m/s^2], damping: 10 1/s}
objects:
  - name: ball
    mesh: {file: ball.stl, units: mm}
    material: {stiffness: 5 N/m, mass: 40 g}
    volume_constraint: true
constraints:
  - {type: fixed, object: ball, nodes: {half_space: {point: [0, 0, 15 mm], normal: [0, 0, 1]}}}
"""
    (tmp_path / "ball.yaml").write_text(scene_text)
    scene = phymul.load_scene(str(tmp_path / "ball.yaml"))
    model = phymul.compile(scene)
    data = phymul.Data(model)
    rest = phymul.component_volumes(model, data)[0]
    assert rest == pytest.approx(volume(points, triangles) / 1e9, rel=1e-5)
    phymul.step(model, data, n=200)
    assert data.positions[:, 2].min() < model.rest_positions[:, 2].min()  # it sags
    assert phymul.component_volumes(model, data)[0] == pytest.approx(rest, rel=1e-10)


def test_a_surface_filled_with_tetrahedra_keeps_its_boundary_and_volume(tmp_path):
    points, triangles = icosphere(20.0)  # mm
    write(tmp_path, "ball.stl", points, triangles, binary=True)
    (tmp_path / "ball.yaml").write_text("""
simulation: {duration: 0.1 s, gravity: [0, 0, -9.81 m/s^2], damping: 10 1/s}
objects:
  - name: ball
    mesh: {file: ball.stl, units: mm, fill: tetra, edge: 4 mm}
    material: {stiffness: 50 N/m, density: 1000 kg/m^3}
    volume_constraint: true
""")
    model = phymul.compile(phymul.load_scene(str(tmp_path / "ball.yaml")))
    ball = model.components["ball"]
    assert model.nodes > len(points)  # points inside
    stored = points.astype(np.float32).astype(float)  # what a binary STL holds
    enclosed = volume(stored, triangles) / 1e9
    # The tetrahedra fill exactly what the surface encloses: their masses sum to rho V.
    assert model.masses.sum() == pytest.approx(1000.0 * enclosed, rel=1e-9)
    assert len(ball["surface"]) == len(triangles)  # the boundary is the file's triangles
    data = phymul.Data(model)
    assert phymul.component_volumes(model, data)[0] == pytest.approx(enclosed, rel=1e-12)


def test_phymul_mesh_writes_a_volume_mesh_meshio_reads(tmp_path):
    from conftest import run_cli
    points, triangles = icosphere(20.0)
    write(tmp_path, "ball.obj", points, triangles)
    code, output = run_cli("mesh", tmp_path / "ball.obj", "-o", tmp_path / "ball.vtu",
                           "--edge", "5 mm", "--units", "mm")
    assert code == 0, output
    written = meshio.read(tmp_path / "ball.vtu")
    tetra = written.cells_dict["tetra"]
    np.testing.assert_array_equal(written.points[: len(points)], points)  # mm, surface first
    a, b, c, d = (written.points[tetra[:, k]] for k in range(4))
    six = np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a))
    assert np.all(six > 0)  # every tetrahedron positive
    assert six.sum() / 6 == pytest.approx(volume(points, triangles), rel=1e-9)
    angle = float(re.search(r"smallest dihedral angle ([0-9.]+)", output).group(1))
    assert angle > 5.0
    code, output = run_cli("mesh", tmp_path / "ball.obj", "-o", tmp_path / "x.vtu",
                           "--edge", "-1 mm")
    assert code == 1 and "'edge' must be > 0 m" in output
    write(tmp_path, "open.obj", points, triangles[1:])
    code, output = run_cli("mesh", tmp_path / "open.obj", "-o", tmp_path / "x.vtu",
                           "--edge", "5 mm", "--units", "mm")
    assert code == 1 and "is not closed" in output


def test_fill_needs_an_edge_and_a_closed_surface(tmp_path):
    (tmp_path / "no_edge.yaml").write_text("""
objects:
  - name: ball
    mesh: {file: ball.stl, fill: tetra}
    material: {stiffness: 50 N/m, density: 1000 kg/m^3}
""")
    with pytest.raises(phymul.SceneError) as caught:
        phymul.load_scene(str(tmp_path / "no_edge.yaml"))
    assert any("'fill' needs 'edge'" in line for line in caught.value.diagnostics)
