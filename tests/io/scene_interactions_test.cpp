// Scene keys for pressure loads, rigid obstacles, contacts and volume schedules: what the
// reader fills in and what compile_scene builds from it.
#include <gtest/gtest.h>

#include <fstream>

#include "phymul/model.hpp"
#include "phymul/scene.hpp"
#include "phymul/scene_io.hpp"
#include "support/process.hpp"

namespace phymul {
namespace {

const std::string kScene = R"(simulation: {duration: 1 s}
objects:
  - name: block
    mesh: {generator: box, size: [4 cm, 4 cm, 2 cm], cells: [8, 8, 4]}
    material: {stiffness: 20 N/m, density: 1000 kg/m^3}
  - name: bladder
    mesh: {generator: ellipsoid, radii: [3 cm, 3 cm, 3 cm], surface: true, center: [0, 0, 10 cm]}
    material: {stiffness: 20 N/m, mass: 50 g}
    volume_constraint: true
    target_volume: [{t: 0, value: 100 mL}, {t: 1 s, value: 300 mL}]
loads:
  - type: pressure
    object: block
    pressure_schedule: [{t: 0, value: 0}, {t: 0.5 s, value: 2 kPa}]
    cylinder: {point: [0, 0, 0], axis: [0, 0, 2], radius: 1 cm}
    nodes: {half_space: {point: [0, 0, -1 cm], normal: [0, 0, -1]}}
  - type: pressure
    object: bladder
    pressure: 30 mmHg
  - type: force
    object: block
    force: [0, 0, 1 mN]
obstacles:
  - name: probe
    shape: probe
    position: [0, 0, -2 cm]
    axis: [0, 0, 3]
    radius: 8 mm
    motion: [{t: 0, value: [0, 0, 0]}, {t: 1 s, value: [0, 0, 5 mm]}]
    objects: [block]
    friction: 0.2
  - shape: plane
    position: [0, 0, -5 cm]
    axis: [0, 0, 1]
  - shape: capsule
    position: [1 cm, 0, 0]
    axis: [0, 1, 0]
    radius: 2 mm
    length: 3 cm
    keep_inside: true
contacts:
  - objects: [block, bladder]
)";

TEST(SceneInteractions, ReaderFillsPressuresObstaclesContactsAndVolumeSchedules) {
  const Scene s = parse_scene(kScene, "scene.yaml");
  ASSERT_EQ(s.loads.size(), 1u);
  ASSERT_EQ(s.pressures.size(), 2u);
  const PressureSpec& probe_pressure = s.pressures[0];
  EXPECT_EQ(probe_pressure.object, "block");
  EXPECT_TRUE(probe_pressure.in_cylinder);
  EXPECT_EQ(probe_pressure.cylinder_axis, Eigen::Vector3d::UnitZ());  // normalised
  EXPECT_DOUBLE_EQ(probe_pressure.cylinder_radius, 0.01);
  EXPECT_DOUBLE_EQ(probe_pressure.pressure.at(0.25).x(), 1000.0);
  EXPECT_EQ(probe_pressure.nodes.kind, NodeSelector::Kind::half_space);
  EXPECT_NEAR(s.pressures[1].pressure.at(3.0).x(), 30 * 133.322387415, 1e-6);
  EXPECT_FALSE(s.pressures[1].in_cylinder);
  EXPECT_NEAR(s.objects[1].target_volume.at(0.5).x(), 200e-6, 1e-18);

  ASSERT_EQ(s.obstacles.size(), 3u);
  const ObstacleSpec& probe = s.obstacles[0];
  EXPECT_EQ(probe.name, "probe");
  EXPECT_EQ(probe.shape, ObstacleSpec::Shape::probe);
  EXPECT_EQ(probe.position, Eigen::Vector3d(0, 0, -0.02));
  EXPECT_EQ(probe.axis, Eigen::Vector3d::UnitZ());
  EXPECT_DOUBLE_EQ(probe.radius, 0.008);
  EXPECT_DOUBLE_EQ(probe.motion.at(0.5).z(), 0.0025);
  EXPECT_EQ(probe.objects, std::vector<std::string>{"block"});
  EXPECT_DOUBLE_EQ(probe.friction, 0.2);
  EXPECT_TRUE(s.obstacles[1].objects.empty());
  EXPECT_TRUE(s.obstacles[2].keep_inside);
  EXPECT_DOUBLE_EQ(s.obstacles[2].length, 0.03);
  ASSERT_EQ(s.contacts.size(), 1u);
  EXPECT_EQ(s.contacts[0].objects[1], "bladder");
}

TEST(SceneInteractions, CompileBuildsTheLoadsAndShapes) {
  const Scene s = parse_scene(kScene, "scene.yaml");
  const Model m = compile_scene(s);
  ASSERT_EQ(m.pressures.size(), 2u);
  // The bottom faces (z = -1 cm, all nodes selected by the half-space) whose rest centroid is
  // within 1 cm of the z axis: 5 mm cells, two triangles per quad.
  int expected = 0;
  for (const Triangle& t : m.components[0].boundary) {
    const Vec3 c = (m.rest_position[t[0]] + m.rest_position[t[1]] + m.rest_position[t[2]]) / 3;
    bool bottom = true;
    for (int i : t) bottom &= m.rest_position[i].z() <= -0.01;
    expected += bottom && c.head<2>().norm() <= 0.01;
  }
  EXPECT_GT(expected, 8);
  EXPECT_EQ(int(m.pressures[0].faces.size()), expected);
  EXPECT_EQ(m.pressures[1].faces.size(), m.components[1].boundary.size());

  ASSERT_EQ(m.obstacles.size(), 3u);
  const RigidObstacle& probe = m.obstacles[0];
  EXPECT_EQ(probe.shape, RigidObstacle::Shape::probe);
  EXPECT_EQ(probe.name, "probe");
  EXPECT_EQ(probe.nodes, m.components[0].nodes);  // the block only
  EXPECT_DOUBLE_EQ(probe.friction, 0.2);
  EXPECT_EQ(m.obstacles[1].name, "obstacle1");
  EXPECT_TRUE(m.obstacles[1].nodes.empty());  // all objects
  ASSERT_EQ(m.volumes.size(), 1u);
  EXPECT_NEAR(m.volumes[0].target_at(1.0), 300e-6, 1e-18);
}

TEST(SceneInteractions, CompileReportsPressuresThatCoverNothing) {
  const std::string scene = R"(objects:
  - name: block
    mesh: {generator: box, size: [4 cm, 4 cm, 2 cm], cells: [4, 4, 2]}
    material: {stiffness: 20 N/m, density: 1000 kg/m^3}
loads:
  - type: pressure
    object: block
    pressure: 1 kPa
    cylinder: {point: [1 m, 0, 0], axis: [0, 0, 1], radius: 1 cm}
)";
  try {
    compile_scene(parse_scene(scene, "p.yaml"));
    FAIL() << "no SceneError";
  } catch (const SceneError& e) {
    EXPECT_EQ(std::string(e.what()),
              "p.yaml:6:5: this pressure covers no boundary face of 'block' (a face counts when "
              "all its nodes are selected and its centroid is in the cylinder)");
  }
}

TEST(SceneInteractions, MonitorsHaveTheContactForceOfEachObstacle) {
  testing::TempDir dir;
  const auto scene = dir.path() / "drop.yaml";
  std::ofstream(scene) << R"(simulation: {duration: 1 s, gravity: [0, 0, -9.81], damping: 30}
objects:
  - name: cube
    mesh: {generator: box, size: [2 cm, 2 cm, 2 cm], cells: [2, 2, 2], center: [0, 0, 1.05 cm]}
    material: {stiffness: 50 N/m, density: 1000 kg/m^3}
obstacles:
  - {name: floor, shape: plane, position: [0, 0, 0], axis: [0, 0, 1]}
)";
  const auto out = dir.path() / "out";
  const auto run =
      testing::run_command(testing::cli() + " run " + scene.string() + " -o " + out.string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  std::ifstream in(out / "monitors.csv");
  std::string header, line, last;
  std::getline(in, header);
  EXPECT_NE(header.find(",contact_floor_x_N,contact_floor_y_N,contact_floor_z_N"),
            std::string::npos)
      << header;
  while (std::getline(in, line)) last = line;
  // The last column: the floor carries the cube's weight once it has settled.
  const double fz = std::stod(last.substr(last.rfind(',') + 1));
  const double weight = 8e-6 * 1000 * 9.81;
  EXPECT_NEAR(fz, weight, 1e-5 * weight);
}

}  // namespace
}  // namespace phymul
