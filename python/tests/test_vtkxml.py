"""VTK XML meshes (.vtu, .vtp) written by VTK's own writers in every data mode, compressor and
header type, and by meshio: phymul reads back exactly the points and cells that were written."""
import itertools

import numpy as np
import pytest

vtk_xml = pytest.importorskip("vtkmodules.vtkIOXML")
from vtkmodules.util.numpy_support import numpy_to_vtk  # noqa: E402
from vtkmodules.vtkCommonCore import VTK_DOUBLE, VTK_FLOAT, vtkPoints  # noqa: E402
from vtkmodules.vtkCommonDataModel import (  # noqa: E402
    vtkCellArray, vtkPolyData, vtkUnstructuredGrid)

import phymul  # noqa: E402
from test_surfaces import icosphere, volume  # noqa: E402

# VTK's cell types and node counts for the volume cells phymul reads.
CELLS = [(10, "tetra", 4), (12, "hexa", 8), (13, "wedge", 6)]


def grid_cells(rng, points):
    """Each volume cell type, every point used (a point without a cell is refused)."""
    cells, order, at = [], rng.permutation(points), 0
    for code, name, k in CELLS:
        for _ in range(5):  # consecutive runs of a shuffled order: distinct nodes, all used
            cells.append((code, name, order[np.arange(at, at + k) % points]))
            at += k
    used = np.unique(np.concatenate([c[2] for c in cells]))
    assert len(used) == points
    return cells


def vtk_points(points, float32):
    p = vtkPoints()
    p.SetDataType(VTK_FLOAT if float32 else VTK_DOUBLE)
    p.SetData(numpy_to_vtk(points.astype(np.float32 if float32 else np.float64), deep=True))
    return p


def write_vtk(writer, data, path, mode, zlib, header64):
    writer.SetInputData(data)
    writer.SetFileName(str(path))
    if mode == "ascii":
        writer.SetDataModeToAscii()
    elif mode == "binary":
        writer.SetDataModeToBinary()
    else:
        writer.SetDataModeToAppended()
        writer.SetEncodeAppendedData(mode == "appended-base64")
    if zlib:
        writer.SetCompressorTypeToZLib()
    else:
        writer.SetCompressorTypeToNone()
    if header64:
        writer.SetHeaderTypeToUInt64()
    else:
        writer.SetHeaderTypeToUInt32()
    assert writer.Write() == 1


MODES = list(itertools.product(["ascii", "binary", "appended-raw", "appended-base64"],
                               [False, True], [False, True], [False, True]))


def mode_id(m):
    return f"{m[0]}-{'zlib' if m[1] else 'none'}-{'u64' if m[2] else 'u32'}-" \
           f"{'f32' if m[3] else 'f64'}"


@pytest.mark.parametrize("mode,zlib,header64,float32", MODES, ids=map(mode_id, MODES))
def test_vtu_from_vtk_reads_back_exactly(tmp_path, mode, zlib, header64, float32):
    rng = np.random.default_rng(3)
    points = rng.uniform(-1, 1, (30, 3)) * [0.037, 12.5, 1e-3]
    cells = grid_cells(rng, len(points))
    grid = vtkUnstructuredGrid()
    grid.SetPoints(vtk_points(points, float32))
    for code, _, nodes in cells:
        grid.InsertNextCell(code, len(nodes), [int(i) for i in nodes])
    path = tmp_path / "grid.vtu"
    write_vtk(vtk_xml.vtkXMLUnstructuredGridWriter(), grid, path, mode, zlib, header64)
    text = path.read_bytes()
    assert (b'format="ascii"' in text) == (mode == "ascii")
    assert (b'encoding="base64"' in text) == (mode == "appended-base64")
    if mode != "ascii":
        assert (b"vtkZLibDataCompressor" in text) == zlib
    mesh = phymul.read_mesh(str(path))
    expected = points.astype(np.float32).astype(float) if float32 else points
    np.testing.assert_array_equal(mesh["points"], expected)  # bit for bit
    for _, name, _ in CELLS:
        np.testing.assert_array_equal(mesh["cells"][name],
                                      [c[2] for c in cells if c[1] == name])


@pytest.mark.parametrize("mode,zlib,header64,float32", MODES, ids=map(mode_id, MODES))
def test_vtp_surface_from_vtk_reads_back_exactly(tmp_path, mode, zlib, header64, float32):
    points, triangles = icosphere(20.0)  # mm, outward
    surface = vtkPolyData()
    surface.SetPoints(vtk_points(points, float32))
    polys = vtkCellArray()
    for t in triangles:
        polys.InsertNextCell(3, [int(i) for i in t])
    surface.SetPolys(polys)
    path = tmp_path / "ball.vtp"
    write_vtk(vtk_xml.vtkXMLPolyDataWriter(), surface, path, mode, zlib, header64)
    mesh = phymul.read_mesh(str(path), 1000.0)
    expected = points.astype(np.float32).astype(float) if float32 else points
    np.testing.assert_array_equal(mesh["points"], expected / 1000.0)
    np.testing.assert_array_equal(mesh["cells"]["triangle"], triangles)  # already outward
    assert mesh["notes"] == []


def test_vtp_polygons_are_split_and_turned_outward(tmp_path):
    # A unit cube of six quads facing inward, written by VTK (appended, zlib).
    cube = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1],
                     [1, 1, 1], [0, 1, 1]], float)
    quads = [[0, 1, 2, 3], [4, 7, 6, 5], [0, 4, 5, 1], [1, 5, 6, 2], [2, 6, 7, 3], [3, 7, 4, 0]]
    surface = vtkPolyData()
    surface.SetPoints(vtk_points(cube, False))
    polys = vtkCellArray()
    for q in quads:
        polys.InsertNextCell(4, q)
    surface.SetPolys(polys)
    write_vtk(vtk_xml.vtkXMLPolyDataWriter(), surface, tmp_path / "cube.vtp", "appended-raw",
              True, True)
    mesh = phymul.read_mesh(str(tmp_path / "cube.vtp"))
    triangles = mesh["cells"]["triangle"]
    assert len(triangles) == 12
    assert volume(mesh["points"], triangles) == pytest.approx(1.0, rel=1e-15)
    assert any("inside out" in n for n in mesh["notes"]), mesh["notes"]


def test_vtp_lines_are_refused_by_name(tmp_path):
    surface = vtkPolyData()
    surface.SetPoints(vtk_points(np.eye(3), False))
    lines = vtkCellArray()
    lines.InsertNextCell(2, [0, 1])
    surface.SetLines(lines)
    write_vtk(vtk_xml.vtkXMLPolyDataWriter(), surface, tmp_path / "lines.vtp", "ascii", False,
              False)
    with pytest.raises(phymul.MeshFileError, match=r"lines.vtp:\d+:\d+: the file holds 1 lines: "
                                                   r"only polygons \(Polys\) make a closed"):
        phymul.read_mesh(str(tmp_path / "lines.vtp"))


MESHIO = [("ascii", {"binary": False}), ("zlib", {"binary": True, "compression": "zlib"}),
          ("raw", {"binary": True, "compression": None})]


@pytest.mark.parametrize("name,options", MESHIO, ids=[m[0] for m in MESHIO])
def test_vtu_from_meshio_reads_back_exactly(tmp_path, name, options):
    meshio = pytest.importorskip("meshio")
    rng = np.random.default_rng(5)
    points = rng.uniform(-1, 1, (40, 3)) * [0.037, 12.5, 1e-3]
    tetra = rng.integers(0, 40, (30, 4))
    tetra.flat[:40] = rng.permutation(40)
    path = tmp_path / f"{name}.vtu"
    meshio.write(path, meshio.Mesh(points, [("tetra", tetra)]), **options)
    mesh = phymul.read_mesh(str(path))
    # meshio's ASCII keeps 11 digits: the reference is what meshio itself reads back.
    written = meshio.read(path).points if name == "ascii" else points
    assert name == "ascii" or np.array_equal(meshio.read(path).points, points)
    np.testing.assert_array_equal(mesh["points"], written)
    np.testing.assert_array_equal(mesh["cells"]["tetra"], tetra)


def test_meshio_lzma_is_refused_clearly(tmp_path):
    meshio = pytest.importorskip("meshio")
    points, triangles = icosphere(0.02)
    meshio.write(tmp_path / "ball.vtu", meshio.Mesh(points, [("triangle", triangles)]),
                 compression="lzma")
    with pytest.raises(phymul.MeshFileError, match="compressor 'vtkLZMADataCompressor' is not "
                                                   "supported: expected vtkZLibDataCompressor"):
        phymul.read_mesh(str(tmp_path / "ball.vtu"))


def test_phymul_mesh_fills_a_vtp_surface_and_a_scene_reads_a_vtu(tmp_path):
    from conftest import run_cli
    points, triangles = icosphere(20.0)
    surface = vtkPolyData()
    surface.SetPoints(vtk_points(points, False))
    polys = vtkCellArray()
    for t in triangles:
        polys.InsertNextCell(3, [int(i) for i in t])
    surface.SetPolys(polys)
    write_vtk(vtk_xml.vtkXMLPolyDataWriter(), surface, tmp_path / "ball.vtp", "appended-raw",
              True, True)
    code, output = run_cli("mesh", tmp_path / "ball.vtp", "-o", tmp_path / "ball.vtu",
                           "--edge", "5 mm", "--units", "mm")
    assert code == 0, output
    # Our own binary-free .vtu, read back as a scene's mesh in mm.
    (tmp_path / "ball.yaml").write_text("""
objects:
  - name: ball
    mesh: {file: ball.vtu, units: mm}
    material: {stiffness: 50 N/m, density: 1000 kg/m^3}
""")
    model = phymul.compile(phymul.load_scene(str(tmp_path / "ball.yaml")))
    enclosed = volume(points, triangles) / 1e9
    assert model.masses.sum() == pytest.approx(1000.0 * enclosed, rel=1e-9)
