// The obstacles' surfaces written with the results: every vertex on the analytic shape the
// contact code enforces (constraints/contact.hpp, an independent description), the triangles
// facing outwards, the motion applied; and `phymul run` writes them as a series that meshio
// reads back, one frame per body frame.
#include "io/obstacle_surface.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "support/kernels.hpp"
#include "support/models.hpp"
#include "support/process.hpp"

namespace phymul {
namespace {

using Shape = RigidObstacle::Shape;

RigidObstacle shape(Shape s, const Vec3& point, const Vec3& axis, double radius, double length) {
  RigidObstacle o = testing::obstacle(s, point, axis, radius, length);
  o.motion = Schedule{{0.0, 1.0}, {Vec3::Zero(), Vec3(0.0, 0.01, 0.02)}};
  return o;
}

TEST(ObstacleSurface, VerticesLieOnTheShapesAndTrianglesFaceOutwards) {
  const std::vector<RigidObstacle> obstacles{
      shape(Shape::plane, Vec3(0, 0, -0.01), Vec3(0.2, 0.1, 1.0), 0.0, 0.0),
      shape(Shape::sphere, Vec3(0.03, 0, 0), Vec3::UnitZ(), 0.007, 0.0),
      shape(Shape::capsule, Vec3(-0.03, 0, 0), Vec3(1, 1, 0), 0.005, 0.02),
      shape(Shape::probe, Vec3(0, 0, -0.05), Vec3(0, 0.3, 1), 0.01, 0.02)};
  const double t = 0.5;  // half way along the motion
  std::vector<int> owner;
  const Mesh mesh =
      obstacle_surfaces(obstacles, {}, t, Vec3(-0.02, -0.02, 0.0), Vec3(0.02, 0.02, 0.03), owner);
  ASSERT_EQ(owner.size(), mesh.cells.size());
  std::vector<int> triangles(obstacles.size(), 0);
  for (size_t c = 0; c < mesh.cells.size(); ++c) {
    const RigidObstacle& o = obstacles[size_t(owner[c])];
    ++triangles[size_t(owner[c])];
    const Cell& cell = mesh.cells[c];
    ASSERT_EQ(cell.type, CellType::triangle);
    const Vec3 a = mesh.points[cell.nodes[0]], b = mesh.points[cell.nodes[1]],
               d = mesh.points[cell.nodes[2]];
    for (const Vec3& p : {a, b, d})
      ASSERT_LT(std::abs(obstacle_distance(o, p, t).distance), 1e-12) << "cell " << c;
    const Vec3 centroid = (a + b + d) / 3.0;
    const Vec3 normal = (b - a).cross(d - a);
    // The centroid of a chord triangle is just inside a curved shape: its outward normal
    // is that of the nearest surface point.
    EXPECT_GT(normal.dot(obstacle_distance(o, centroid, t).normal), 0.0) << "cell " << c;
  }
  for (size_t k = 0; k < obstacles.size(); ++k) EXPECT_GT(triangles[k], 0) << k;
  // The plane is a square patch about the box centre's projection, moved with the shape.
  const Vec3 moved = obstacles[0].point + Vec3(0.0, 0.005, 0.01);
  EXPECT_NEAR((mesh.points[0] - moved).dot(obstacles[0].axis), 0.0, 1e-15);
}

TEST(ObstacleSurface, RunWritesTheirSeriesBesideTheBody) {
  testing::TempDir dir;
  const auto scene = dir.path() / "press.yaml";
  std::ofstream(scene) << R"(simulation: {dt: auto, duration: 0.1 s, damping: 10 1/s}
objects:
  - name: tissue
    mesh: {generator: box, size: [4 cm, 4 cm, 2 cm], cells: [4, 4, 2]}
    material: {stiffness: 20 N/m, density: 1000 kg/m^3}
constraints:
  - {type: fixed, object: tissue, nodes: top}
obstacles:
  - name: probe
    shape: probe
    position: [0, 0, -1.8 cm]
    axis: [0, 0, 1]
    radius: 8 mm
    motion:
      - {t: 0 s, value: [0, 0, 0]}
      - {t: 0.1 s, value: [0, 0, 4 mm]}
output: {interval: 0.05 s}
)";
  const auto out = dir.path() / "out";
  const auto run = testing::run_command(testing::cli() + " run " + scene.string() + " -o " +
                                        out.string() + " --quiet");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto script = dir.path() / "read.py";
  std::ofstream(script) << R"(import os, sys, xml.etree.ElementTree as ET
import meshio, numpy as np
d = sys.argv[1]
def series(name):
    sets = ET.parse(os.path.join(d, name)).getroot().find('Collection').findall('DataSet')
    return [(float(s.get('timestep')), s.get('file')) for s in sets]
body, probe = series('press.pvd'), series('press_obstacles.pvd')
assert [t for t, _ in body] == [t for t, _ in probe], (body, probe)
tips = []
for t, f in probe:
    m = meshio.read(os.path.join(d, f))
    assert m.cells[0].type == 'triangle'
    assert set(np.ravel(m.cell_data['obstacle'][0]).tolist()) == {0}
    tips.append(float(m.points[:, 2].max()))
print(len(probe), ' '.join(str(z) for z in tips))
)";
  const auto read =
      testing::run_command("/usr/bin/python3 " + script.string() + " " + out.string());
  ASSERT_EQ(read.exit_code, 0) << read.output;
  std::istringstream in(read.output);
  int frames = 0;
  in >> frames;
  ASSERT_EQ(frames, 3);  // t = 0, 0.05, 0.1 s
  // The tip (its centre plus the radius along z) rises with the motion: -10, -8, -6 mm.
  for (int k = 0; k < frames; ++k) {
    double tip = 0.0;
    in >> tip;
    EXPECT_NEAR(tip, -0.010 + 0.002 * k, 1e-9) << k;
  }
}

}  // namespace
}  // namespace phymul
