// Per-mesh `transform` (scale, rotate, translate) and `remesh` in scenes, against points placed
// by hand (Rodrigues' formula) and a run of a mesh file placed beforehand.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "phymul/meshing.hpp"
#include "phymul/model.hpp"
#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "support/process.hpp"

namespace phymul {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

fs::path write(const TempDir& dir, const std::string& name, const std::string& text) {
  const fs::path p = dir.path() / name;
  std::ofstream(p) << text;
  return p;
}

// One hexahedron with uneven corners, coordinates as written (any unit).
const std::vector<Vec3> kCorners{{0, 0, 0},  {12, 1, 0},  {13, 11, 1},  {1, 10, 0},
                                 {0, 1, 14}, {11, 0, 15}, {12, 12, 13}, {0, 11, 12}};

std::string hexa_vtk(const std::vector<Vec3>& points) {
  std::string text = "# vtk DataFile Version 4.2\nhexa\nASCII\nDATASET UNSTRUCTURED_GRID\n";
  text += fmt::format("POINTS {} double\n", points.size());
  for (const Vec3& p : points)
    text += fmt::format("{:.17g} {:.17g} {:.17g}\n", p.x(), p.y(), p.z());
  return text + "CELLS 1 9\n8 0 1 2 3 4 5 6 7\nCELL_TYPES 1\n12\n";
}

std::string scene_text(const std::string& mesh) {
  return fmt::format(R"(simulation: {{dt: 1 ms, duration: 20 ms, gravity: [0, 0, -9.81]}}
objects:
  - name: organ
    mesh: {}
    material: {{stiffness: 50 N/m, density: 1000 kg/m^3}}
constraints:
  - {{type: fixed, object: organ, nodes: "0-3"}}
)",
                     mesh);
}

// Rodrigues: v cos a + (k x v) sin a + k (k . v)(1 - cos a), k a unit axis.
Vec3 rotated(const Vec3& v, const Vec3& axis, double angle) {
  const Vec3 k = axis.normalized();
  return v * std::cos(angle) + k.cross(v) * std::sin(angle) + k * k.dot(v) * (1 - std::cos(angle));
}

TEST(MeshPlacement, TransformScalesThenRotatesThenTranslatesTheFilePoints) {
  TempDir dir;
  write(dir, "hexa.vtk", hexa_vtk(kCorners));
  const fs::path scene = write(
      dir, "scene.yaml",
      scene_text("{file: hexa.vtk, units: mm, transform: {scale: [2, 1, 0.5], rotate: {axis: [1, "
                 "2, 3], angle: 30 deg}, translate: [10 mm, -5 mm, 0.3 cm]}}"));
  const Model model = compile_scene(load_scene(scene));
  ASSERT_EQ(model.node_count(), 8);
  for (size_t i = 0; i < kCorners.size(); ++i) {
    const Vec3 scaled = kCorners[i].cwiseProduct(Vec3(2, 1, 0.5)) / 1000.0;
    const Vec3 expected = rotated(scaled, Vec3(1, 2, 3), M_PI / 6) + Vec3(0.010, -0.005, 0.003);
    EXPECT_LT((model.rest_position[i] - expected).norm(), 1e-12) << "point " << i;
  }
}

TEST(MeshPlacement, AQuarterTurnAboutZTakesXToYAndOneScaleServesAllAxes) {
  TempDir dir;
  write(dir, "hexa.vtk", hexa_vtk(kCorners));
  const fs::path scene = write(
      dir, "scene.yaml",
      scene_text("{file: hexa.vtk, units: mm, transform: {scale: 3, rotate: {axis: [0, 0, 2], "
                 "angle: 90 deg}}}"));
  const Model model = compile_scene(load_scene(scene));
  for (size_t i = 0; i < kCorners.size(); ++i) {
    const Vec3 p = 3.0 * kCorners[i] / 1000.0;
    EXPECT_LT((model.rest_position[i] - Vec3(-p.y(), p.x(), p.z())).norm(), 1e-15) << i;
  }
}

TEST(MeshPlacement, GeneratedMeshesArePlacedToo) {
  TempDir dir;
  const fs::path plain = write(dir, "plain.yaml", scene_text("{generator: box}"));
  const fs::path moved = write(
      dir, "moved.yaml", scene_text("{generator: box, transform: {translate: [1 cm, 0, 0]}}"));
  const Model a = compile_scene(load_scene(plain)), b = compile_scene(load_scene(moved));
  ASSERT_EQ(a.node_count(), b.node_count());
  for (int i = 0; i < a.node_count(); ++i)
    EXPECT_EQ(b.rest_position[size_t(i)], a.rest_position[size_t(i)] + Vec3(0.01, 0, 0));
}

TEST(MeshPlacement, ARunOfThePlacedMeshIsTheRunOfTheFilePlacedBeforehand) {
  TempDir dir;
  write(dir, "hexa.vtk", hexa_vtk(kCorners));
  const Vec3 axis(0, 1, 1);
  std::vector<Vec3> placed;
  for (const Vec3& p : kCorners)
    placed.push_back(rotated(p.cwiseProduct(Vec3(1.5, 1.5, 1.5)), axis, -M_PI / 4) +
                     Vec3(20, 0, -7));
  write(dir, "placed.vtk", hexa_vtk(placed));
  const fs::path a = write(
      dir, "a.yaml",
      scene_text("{file: hexa.vtk, units: mm, transform: {scale: 1.5, rotate: {axis: [0, 1, 1], "
                 "angle: -45 deg}, translate: [20 mm, 0 mm, -7 mm]}}"));
  const fs::path b = write(dir, "b.yaml", scene_text("{file: placed.vtk, units: mm}"));
  const Model ma = compile_scene(load_scene(a)), mb = compile_scene(load_scene(b));
  Data da = make_data(ma), db = make_data(mb);
  for (int s = 0; s < 20; ++s) step(ma, da), step(mb, db);
  double moved = 0.0;
  for (size_t i = 0; i < da.x.size(); ++i) {
    EXPECT_LT((da.x[i] - db.x[i]).norm(), 1e-12) << "node " << i;
    moved = std::max(moved, (da.x[i] - ma.rest_position[i]).norm());
  }
  EXPECT_GT(moved, 1e-6);  // the free corners fell: the comparison saw a motion
}

// An OBJ of a sphere of radius 40 mm (subdivided icosahedron, ~2.6 mm edges), in mm.
std::string sphere_obj() {
  const Mesh m = make_ellipsoid_surface(Vec3::Constant(40.0), 4);
  std::string text;
  for (const Vec3& p : m.points)
    text += fmt::format("v {:.17g} {:.17g} {:.17g}\n", p.x(), p.y(), p.z());
  for (const Cell& c : m.cells)
    text += fmt::format("f {} {} {}\n", c.nodes[0] + 1, c.nodes[1] + 1, c.nodes[2] + 1);
  return text;
}

TEST(MeshPlacement, RemeshTakesTheSurfaceToTheEdgeAndNotesItsQuality) {
  TempDir dir;
  write(dir, "sphere.obj", sphere_obj());
  const fs::path scene = write(
      dir, "scene.yaml",
      scene_text("{file: sphere.obj, units: mm, remesh: 8 mm, transform: {translate: [0, 0, 1 "
                 "m]}}"));
  const Scene s = load_scene(scene);
  const Mesh& mesh = *s.objects[0].mesh.file_mesh;
  const SurfaceQuality q = surface_quality(mesh);
  EXPECT_NEAR(q.edge_mean, 0.008, 0.2 * 0.008);
  for (const Vec3& p : mesh.points) EXPECT_NEAR((p - Vec3(0, 0, 1)).norm(), 0.040, 1e-3);
  bool noted = false;
  for (const std::string& note : s.objects[0].mesh.file_notes)
    noted = noted || note.find("remeshed to 8 mm") != std::string::npos;
  EXPECT_TRUE(noted);
  // With `fill`, the remeshed surface is the boundary of the tetrahedra.
  const fs::path filled = write(dir, "filled.yaml",
                                scene_text("{file: sphere.obj, units: mm, remesh: 8 mm, fill: "
                                           "tetra, edge: 10 mm}"));
  const Scene f = load_scene(filled);
  const Mesh volume = make_mesh(f.objects[0].mesh);
  ASSERT_TRUE(volume.volumetric());
  double total = 0.0;
  for (const Cell& c : volume.cells) total += cell_measure(volume.points, c);
  // Inscribed in the sphere, short of it by at most 2/3 (edge / R)^2 (remesh_test.cpp).
  const double sphere = 4.0 / 3.0 * M_PI * std::pow(0.040, 3);
  EXPECT_LT(total, sphere);
  EXPECT_GT(total, sphere * (1.0 - 2.0 / 3.0 * std::pow(0.008 / 0.040, 2)));
  EXPECT_GT(volume.points.size(), mesh.points.size());
}

}  // namespace
}  // namespace phymul
