// Mesh files: legacy VTK and Gmsh ASCII read back exactly what meshio wrote; physical groups
// become node sets; every damaged file names its line and what is wrong.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include "phymul/mesh_io.hpp"
#include "phymul/model.hpp"
#include "phymul/scene.hpp"
#include "phymul/scene_io.hpp"
#include "support/expected_messages.hpp"
#include "support/process.hpp"

namespace phymul {
namespace {

namespace fs = std::filesystem;
using testing::read_text;
using testing::run_command;
using testing::TempDir;

// meshio writes each cell type with random points and cells (every point used) in every
// format it has, and the exact reference: coordinates as float.hex, then the cells.
constexpr const char* kMeshioWriter = R"(import sys, numpy as np
try:
    import meshio
except ImportError:
    print('NO MESHIO'); sys.exit(0)
out = sys.argv[1]
rng = np.random.default_rng(7)
for name, k in [('tetra', 4), ('hexahedron', 8), ('wedge', 6), ('triangle', 3), ('quad', 4)]:
    npts, ncells = 50, 40
    pts = rng.uniform(-1, 1, (npts, 3)) * [0.037, 12.5, 1e-3]
    cells = rng.integers(0, npts, (ncells, k))
    cells.flat[:npts] = rng.permutation(npts)
    m = meshio.Mesh(pts, [(name, cells)])
    m.write(f'{out}/{name}.vtk', binary=False)
    m.write(f'{out}/{name}_42.vtk', file_format='vtk42', binary=False)
    m.write(f'{out}/{name}.msh', file_format='gmsh', binary=False)
    m.write(f'{out}/{name}_22.msh', file_format='gmsh22', binary=False)
    with open(f'{out}/{name}.txt', 'w') as f:
        f.write(f'{npts} {ncells} {k}\n')
        for p in pts: f.write(' '.join(float(v).hex() for v in p) + '\n')
        for c in cells: f.write(' '.join(map(str, c)) + '\n')
print('OK')
)";

struct Reference {
  std::vector<Vec3> points;
  std::vector<std::vector<int>> cells;
};

Reference read_reference(const fs::path& file) {
  std::ifstream in(file);
  size_t points = 0, cells = 0, k = 0;
  in >> points >> cells >> k;
  Reference r;
  r.points.resize(points);
  for (Vec3& p : r.points)
    for (int a = 0; a < 3; ++a) {
      std::string hex;
      in >> hex;
      p[a] = std::strtod(hex.c_str(), nullptr);
    }
  r.cells.assign(cells, std::vector<int>(k));
  for (auto& c : r.cells)
    for (int& i : c) in >> i;
  return r;
}

TEST(MeshFile, ReadsBackExactlyWhatMeshioWrote) {
  TempDir dir;
  std::ofstream(dir.path() / "write.py") << kMeshioWriter;
  const auto r = run_command("/usr/bin/python3 " + (dir.path() / "write.py").string() + " " +
                             dir.path().string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  if (r.output.find("NO MESHIO") != std::string::npos)
    GTEST_SKIP() << "SKIPPED LOUDLY: python3-meshio is not installed (make deps installs it)";
  const std::pair<const char*, CellType> kinds[] = {{"tetra", CellType::tetra},
                                                    {"hexahedron", CellType::hexa},
                                                    {"wedge", CellType::wedge},
                                                    {"triangle", CellType::triangle},
                                                    {"quad", CellType::quad}};
  int files = 0;
  for (const auto& [name, type] : kinds) {
    const Reference ref = read_reference(dir.path() / (std::string(name) + ".txt"));
    for (const char* suffix : {".vtk", "_42.vtk", ".msh", "_22.msh"}) {
      const fs::path file = dir.path() / (std::string(name) + suffix);
      if (!fs::exists(file)) continue;
      ++files;
      SCOPED_TRACE(file.filename().string());
      const Mesh mesh = read_mesh_file(file);
      ASSERT_EQ(mesh.points.size(), ref.points.size());
      for (size_t i = 0; i < ref.points.size(); ++i)
        ASSERT_EQ(mesh.points[i], ref.points[i]) << "point " << i;  // bit for bit
      ASSERT_EQ(mesh.cells.size(), ref.cells.size());
      for (size_t c = 0; c < ref.cells.size(); ++c) {
        ASSERT_EQ(mesh.cells[c].type, type);
        const auto nodes = mesh.cells[c].node_span();
        std::vector<int> expected = ref.cells[c];
        // meshio's wedge is Gmsh's prism (first triangle facing the second): it writes it to
        // VTK files reordered to VTK's wedge, as phymul reads Gmsh prisms.
        if (type == CellType::wedge)
          expected = {expected[0], expected[2], expected[1], expected[3], expected[5], expected[4]};
        ASSERT_EQ(std::vector<int>(nodes.begin(), nodes.end()), expected) << "cell " << c;
      }
    }
  }
  EXPECT_EQ(files, 20);
}

// A unit cell of each kind, valid in VTK's orientation once read.
constexpr const char* kPrismGmsh41 = R"($MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
2
2 7 "base plate"
3 9 "tissue"
$EndPhysicalNames
$Entities
0 0 1 1
4 0 0 0 1 1 0 1 7 0
5 0 0 0 1 1 1 1 9 1 4
$EndEntities
$Nodes
2 6 10 60
2 4 0 3
10
20
30
0 0 0
1 0 0
0 1 0
3 5 0 3
40
50
60
0 0 2
1 0 2
0 1 2
$EndNodes
$Elements
2 2 1 2
2 4 2 1
1 10 20 30
3 5 6 1
2 10 20 30 40 50 60
$EndElements
)";

TEST(MeshFile, GmshPrismsBecomeValidVtkWedgesAndPhysicalGroupsNodeSets) {
  const Mesh mesh = parse_gmsh_mesh(kPrismGmsh41, "prism.msh", 1000.0);  // in mm
  ASSERT_EQ(mesh.points.size(), 6u);
  EXPECT_EQ(mesh.points[3], Vec3(0, 0, 2) / 1000.0);
  ASSERT_EQ(mesh.cells.size(), 1u);  // the triangle only defines "base plate"
  EXPECT_EQ(mesh.cells[0].type, CellType::wedge);
  EXPECT_NO_THROW(validate(mesh));
  EXPECT_NEAR(cell_measure(mesh.points, mesh.cells[0]), 0.5 * 2 * 1e-9, 1e-24);  // m^3
  EXPECT_EQ(mesh.node_sets.at("base plate"), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(mesh.node_sets.at("tissue"), (std::vector<int>{0, 1, 2, 3, 4, 5}));
}

TEST(MeshFile, Gmsh22PhysicalTagsWithoutNamesAreNumbered) {
  const Mesh mesh = parse_gmsh_mesh(R"($MeshFormat
2.2 0 8
$EndMeshFormat
$Nodes
4
1 0 0 0
2 1 0 0
3 0 1 0
4 0 0 1
$EndNodes
$Elements
3
1 15 2 5 1 4
2 2 2 6 1 1 2 3
3 4 2 0 1 1 2 3 4
$EndElements
)",
                                    "t.msh");
  ASSERT_EQ(mesh.cells.size(), 1u);
  EXPECT_EQ(mesh.cells[0].type, CellType::tetra);
  EXPECT_GT(cell_measure(mesh.points, mesh.cells[0]), 0.0);
  EXPECT_EQ(mesh.node_sets.at("physical_5"), (std::vector<int>{3}));
  EXPECT_EQ(mesh.node_sets.at("physical_6"), (std::vector<int>{0, 1, 2}));
}

// Cut anywhere, a file is refused with a MeshFileError (never a crash), or, cut after its
// last needed token, reads as the whole.
TEST(MeshFile, EveryPrefixIsRefusedCleanlyOrReadsWhole) {
  const std::string vtk = read_text(testing::source_dir() / "examples/meshes/block.vtk");
  const std::string msh = read_text(testing::source_dir() / "examples/meshes/block.msh");
  for (const auto& [text, name] : {std::pair(vtk, "block.vtk"), std::pair(msh, "block.msh")}) {
    const Mesh whole = name[6] == 'v' ? parse_vtk_mesh(text, name) : parse_gmsh_mesh(text, name);
    for (size_t n = 0; n < text.size(); n += 7) {
      try {
        const std::string cut = text.substr(0, n);
        const Mesh m = name[6] == 'v' ? parse_vtk_mesh(cut, name) : parse_gmsh_mesh(cut, name);
        EXPECT_EQ(m.points.size(), whole.points.size()) << n;
        EXPECT_EQ(m.cells.size(), whole.cells.size()) << n;
      } catch (const MeshFileError& e) {
        EXPECT_EQ(e.file, name);
        EXPECT_FALSE(e.message.empty());
      }
    }
  }
}

// tests/data/bad_meshes: each file with its expected message (file:line:column: ...) in
// expected.txt as "file | message".
TEST(MeshFile, EveryBadMeshReportsItsExpectedMessage) {
  testing::expect_every_file_refused<MeshFileError>(
      testing::source_dir() / "tests/data/bad_meshes", [](const fs::path& p) { read_mesh_file(p); },
      10);
}

fs::path write(const TempDir& dir, const std::string& name, const std::string& text) {
  const fs::path p = dir.path() / name;
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
  return p;
}

TEST(MeshFileScene, PathIsRelativeToTheSceneAndUnitsScaleTheCoordinates) {
  const Scene scene = load_scene(testing::source_dir() / "examples/pressed_block.yaml");
  const Model model = compile_scene(scene);
  const Mesh mesh = read_mesh_file(testing::source_dir() / "examples/meshes/block.msh", 1000.0);
  ASSERT_EQ(model.node_count(), int(mesh.points.size()));
  for (size_t i = 0; i < mesh.points.size(); ++i) EXPECT_EQ(model.rest_position[i], mesh.points[i]);
  // The block is 40 x 40 x 20 mm.
  Vec3 lo = mesh.points[0], hi = mesh.points[0];
  for (const Vec3& p : mesh.points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  EXPECT_NEAR((hi - lo).x(), 0.040, 1e-15);
  EXPECT_NEAR((hi - lo).z(), 0.020, 1e-15);
}

TEST(MeshFileScene, ProblemsInTheFileNameItsLineAndTheObject) {
  TempDir dir;
  write(dir, "meshes/bad.vtk",
        "# vtk DataFile Version 4.2\nbad\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n"
        "0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 1 5\n4 0 1 2 7\nCELL_TYPES 1\n10\n");
  const fs::path scene = write(dir, "scene.yaml", R"(objects:
  - name: liver
    mesh: {file: meshes/bad.vtk}
    material: {stiffness: 10 N/m, density: 1000 kg/m^3}
)");
  try {
    compile_scene(load_scene(scene));
    FAIL() << "no SceneError";
  } catch (const SceneError& e) {
    ASSERT_EQ(e.diagnostics().size(), 1u);
    const std::string m = e.diagnostics()[0].str();
    EXPECT_NE(m.find("meshes/bad.vtk:8:1: node 3 of cell 0 is 7, outside the 4 points [0, 3] "
                     "(the mesh of object 'liver', "),
              std::string::npos)
        << m;
    EXPECT_NE(m.find("scene.yaml:2"), std::string::npos) << m;
  }
}

TEST(MeshFileScene, GeneratorKeysWithAFileAndUnitsWithoutOneAreRefused) {
  TempDir dir;
  const fs::path scene = write(dir, "scene.yaml", R"(objects:
  - name: a
    mesh: {file: a.vtk, size: [1, 1, 1]}
    material: {stiffness: 10 N/m, density: 1000 kg/m^3}
  - name: b
    mesh: {generator: box, units: mm}
    material: {stiffness: 10 N/m, density: 1000 kg/m^3}
  - name: c
    mesh: {generator: box, file: c.vtk}
    material: {stiffness: 10 N/m, density: 1000 kg/m^3}
  - name: d
    mesh: {units: mm}
    material: {stiffness: 10 N/m, density: 1000 kg/m^3}
)");
  try {
    load_scene(scene);
    FAIL() << "no SceneError";
  } catch (const SceneError& e) {
    std::string all;
    for (const auto& d : e.diagnostics()) all += d.str() + "\n";
    EXPECT_NE(all.find("scene.yaml:3:31: 'size' belongs to generated meshes; a mesh read from "
                       "'file' takes only 'units'"),
              std::string::npos)
        << all;
    EXPECT_NE(all.find("scene.yaml:6:35: 'units' applies only to a mesh read from 'file'"),
              std::string::npos)
        << all;
    EXPECT_NE(all.find("scene.yaml:9:28: give only one of 'generator' or 'file'"),
              std::string::npos)
        << all;
    EXPECT_NE(all.find("scene.yaml:12:5: one of 'generator' or 'file' is required"),
              std::string::npos)
        << all;
  }
}

}  // namespace
}  // namespace phymul
