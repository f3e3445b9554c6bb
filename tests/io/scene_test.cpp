#include "phymul/scene.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "io/parameter_table.hpp"
#include "phymul/scene_io.hpp"

namespace phymul {
namespace {

using Kind = NodeSelector::Kind;
using Vec = Eigen::Vector3d;

const std::string kFullScene = R"(simulation:
  dt: 0.1 ms
  dt_safety: 0.8
  duration: 2 s
  integrator: newton-cotes
  mode: static
  gravity: [0, 0, -1 g0]
  damping: 5 1/s
  tolerance: 2 mN
  max_iterations: 5000
  load_steps: 4
  relaxation: fire
objects:
  - name: cube
    mesh:
      generator: box
      element: tetra
      size: [40 mm, 3 cm, 0.05]
      cells: [8, 6, 10]
      center: [1 cm, 0, -2 mm]
    material:
      stiffness: 50 N/m
      density: 1.05 g/cm^3
      frame: frame
      reaction: false
    volume_constraint: true
  - name: liver_1
    mesh:
      generator: ellipsoid
      radii: [2 cm, 1.5 cm, 15 mm]
      subdivisions: 3
      layers: 4
      surface: false
    material: {stiffness: 2 N/mm, mass: 250 g}
  - name: vessel
    mesh:
      generator: cylinder
      radius: 1 cm
      length: 4 cm
      around: 12
      along: 5
      rings: 3
    material: {stiffness: 0.1 kN/m, mass: 0.1}
  - name: Shell-2
    mesh: {generator: cylinder, surface: true, radius: 5 mm}
    material: {stiffness: 1, mass: 10 g}
loads:
  - type: force
    object: cube
    nodes: top
    force: [0, 0, -0.1 N]
  - type: force
    object: liver_1
    nodes: {sphere: {center: [0, 0, 2 cm], radius: 5 mm}}
    schedule:
      - {t: 0 s, value: [0, 0, 0]}
      - {t: 1 s, value: [0, 0, -100 mN]}
      - {t: 1500 ms, value: [1 N, 0, 0]}
constraints:
  - type: fixed
    object: cube
    nodes: bottom
  - type: displacement
    object: cube
    nodes: "7, 0-3"
    axes: z
    displacement: [0, 0, -5 mm]
  - type: displacement
    object: vessel
    nodes: [5, 2, 2]
    axes: xz
    schedule:
      - {t: 0, value: [0, 0, 0]}
      - t: 2 s
        value: [1 mm, 0, -2 mm]
  - type: fixed
    object: vessel
    nodes: {box: {min: [-1 cm, -1 cm, -2 cm], max: [1 cm, 1 cm, -19 mm]}}
  - type: fixed
    object: Shell-2
    nodes:
      half_space: {point: [0, 0, 1 cm], normal: [0, 3, 4]}
  - type: fixed
    object: liver_1
output:
  interval: 0.05 s
  vtk: false
)";

void expect_vec(const Vec& actual, const Vec& expected) {
  for (int i = 0; i < 3; ++i) EXPECT_DOUBLE_EQ(actual[i], expected[i]) << "component " << i;
}

void expect_loc(const SourceLoc& loc, int line, int column) {
  EXPECT_EQ(loc.file, "full.yaml");
  EXPECT_EQ(loc.line, line);
  EXPECT_EQ(loc.column, column);
}

TEST(SceneTest, FullSceneSimulation) {
  const Scene scene = parse_scene(kFullScene, "full.yaml");
  EXPECT_EQ(scene.file, "full.yaml");
  const auto& s = scene.simulation;
  ASSERT_TRUE(s.dt.has_value());
  EXPECT_DOUBLE_EQ(*s.dt, 1e-4);
  EXPECT_DOUBLE_EQ(s.dt_safety, 0.8);
  EXPECT_DOUBLE_EQ(s.duration, 2.0);
  EXPECT_EQ(s.integrator, Integrator::newton_cotes);
  EXPECT_EQ(s.mode, SolveMode::static_equilibrium);
  expect_vec(s.gravity, {0, 0, -9.80665});
  EXPECT_DOUBLE_EQ(s.damping, 5.0);
  EXPECT_DOUBLE_EQ(s.tolerance, 0.002);
  EXPECT_EQ(s.max_iterations, 5000);
  EXPECT_EQ(s.load_steps, 4);
  EXPECT_EQ(s.relaxation, Relaxation::fire);
  expect_loc(s.loc, 1, 1);
}

TEST(SceneTest, FullSceneObjects) {
  const Scene scene = parse_scene(kFullScene, "full.yaml");
  ASSERT_EQ(scene.objects.size(), 4u);

  const auto& cube = scene.objects[0];
  EXPECT_EQ(cube.name, "cube");
  expect_loc(cube.loc, 14, 5);
  EXPECT_EQ(cube.mesh.generator, "box");
  EXPECT_EQ(cube.mesh.element, CellType::tetra);
  expect_vec(cube.mesh.size, {0.04, 0.03, 0.05});
  EXPECT_EQ(cube.mesh.cells, (std::array<int, 3>{8, 6, 10}));
  expect_vec(cube.mesh.center, {0.01, 0, -0.002});
  expect_loc(cube.mesh.loc, 15, 5);
  EXPECT_DOUBLE_EQ(cube.material.stiffness.value(), 50.0);
  ASSERT_TRUE(cube.material.density.has_value());
  EXPECT_DOUBLE_EQ(*cube.material.density, 1050.0);
  EXPECT_FALSE(cube.material.mass.has_value());
  EXPECT_EQ(cube.material.frame, FrameMode::frame);
  EXPECT_FALSE(cube.material.reaction);
  expect_loc(cube.material.loc, 21, 5);
  EXPECT_TRUE(cube.volume_constraint);

  const auto& liver = scene.objects[1];
  EXPECT_EQ(liver.name, "liver_1");
  EXPECT_EQ(liver.mesh.generator, "ellipsoid");
  expect_vec(liver.mesh.radii, {0.02, 0.015, 0.015});
  EXPECT_EQ(liver.mesh.subdivisions, 3);
  EXPECT_EQ(liver.mesh.layers, 4);
  EXPECT_FALSE(liver.mesh.surface);
  EXPECT_DOUBLE_EQ(liver.material.stiffness.value(), 2000.0);
  EXPECT_FALSE(liver.material.density.has_value());
  EXPECT_DOUBLE_EQ(liver.material.mass.value_or(0), 0.25);
  EXPECT_EQ(liver.material.frame, FrameMode::polar);
  EXPECT_TRUE(liver.material.reaction);
  EXPECT_FALSE(liver.volume_constraint);

  const auto& vessel = scene.objects[2];
  EXPECT_EQ(vessel.mesh.generator, "cylinder");
  EXPECT_DOUBLE_EQ(vessel.mesh.radius, 0.01);
  EXPECT_DOUBLE_EQ(vessel.mesh.length, 0.04);
  EXPECT_EQ(vessel.mesh.around, 12);
  EXPECT_EQ(vessel.mesh.along, 5);
  EXPECT_EQ(vessel.mesh.rings, 3);
  EXPECT_FALSE(vessel.mesh.surface);
  EXPECT_DOUBLE_EQ(vessel.material.stiffness.value(), 100.0);
  EXPECT_DOUBLE_EQ(vessel.material.mass.value_or(0), 0.1);

  const auto& shell = scene.objects[3];
  EXPECT_EQ(shell.name, "Shell-2");
  EXPECT_TRUE(shell.mesh.surface);
  EXPECT_DOUBLE_EQ(shell.mesh.radius, 0.005);
  EXPECT_DOUBLE_EQ(shell.mesh.length, 0.02);
  EXPECT_EQ(shell.mesh.around, 16);
  EXPECT_EQ(shell.mesh.along, 4);
  EXPECT_DOUBLE_EQ(shell.material.stiffness.value(), 1.0);
  EXPECT_DOUBLE_EQ(shell.material.mass.value_or(0), 0.01);
}

TEST(SceneTest, FullSceneLoads) {
  const Scene scene = parse_scene(kFullScene, "full.yaml");
  ASSERT_EQ(scene.loads.size(), 2u);

  const auto& constant = scene.loads[0];
  EXPECT_EQ(constant.object, "cube");
  expect_loc(constant.loc, 48, 5);
  EXPECT_EQ(constant.nodes.kind, Kind::named);
  EXPECT_EQ(constant.nodes.name, "top");
  expect_loc(constant.nodes.loc, 50, 12);
  EXPECT_EQ(constant.force.times, std::vector<double>{0.0});
  ASSERT_EQ(constant.force.values.size(), 1u);
  expect_vec(constant.force.values[0], {0, 0, -0.1});

  const auto& scheduled = scene.loads[1];
  EXPECT_EQ(scheduled.object, "liver_1");
  EXPECT_EQ(scheduled.nodes.kind, Kind::sphere);
  expect_vec(scheduled.nodes.center, {0, 0, 0.02});
  EXPECT_DOUBLE_EQ(scheduled.nodes.radius, 0.005);
  EXPECT_EQ(scheduled.force.times, (std::vector<double>{0.0, 1.0, 1.5}));
  ASSERT_EQ(scheduled.force.values.size(), 3u);
  expect_vec(scheduled.force.values[0], {0, 0, 0});
  expect_vec(scheduled.force.values[1], {0, 0, -0.1});
  expect_vec(scheduled.force.values[2], {1, 0, 0});
}

TEST(SceneTest, FullSceneConstraints) {
  const Scene scene = parse_scene(kFullScene, "full.yaml");
  ASSERT_EQ(scene.constraints.size(), 6u);
  const auto& c = scene.constraints;

  EXPECT_EQ(c[0].kind, ConstraintSpec::Kind::fixed);
  EXPECT_EQ(c[0].object, "cube");
  EXPECT_EQ(c[0].nodes.kind, Kind::named);
  EXPECT_EQ(c[0].nodes.name, "bottom");
  EXPECT_EQ(c[0].axes, (std::array<bool, 3>{true, true, true}));
  EXPECT_EQ(c[0].displacement.times, std::vector<double>{0.0});
  expect_vec(c[0].displacement.values.at(0), {0, 0, 0});

  EXPECT_EQ(c[1].kind, ConstraintSpec::Kind::displacement);
  EXPECT_EQ(c[1].nodes.kind, Kind::indices);
  EXPECT_EQ(c[1].nodes.indices, (std::vector<int>{0, 1, 2, 3, 7}));
  EXPECT_EQ(c[1].axes, (std::array<bool, 3>{false, false, true}));
  EXPECT_EQ(c[1].displacement.times, std::vector<double>{0.0});
  expect_vec(c[1].displacement.values.at(0), {0, 0, -0.005});

  EXPECT_EQ(c[2].object, "vessel");
  EXPECT_EQ(c[2].nodes.kind, Kind::indices);
  EXPECT_EQ(c[2].nodes.indices, (std::vector<int>{2, 5}));
  EXPECT_EQ(c[2].axes, (std::array<bool, 3>{true, false, true}));
  EXPECT_EQ(c[2].displacement.times, (std::vector<double>{0.0, 2.0}));
  expect_vec(c[2].displacement.values.at(1), {0.001, 0, -0.002});

  EXPECT_EQ(c[3].nodes.kind, Kind::box);
  expect_vec(c[3].nodes.min, {-0.01, -0.01, -0.02});
  expect_vec(c[3].nodes.max, {0.01, 0.01, -0.019});

  EXPECT_EQ(c[4].object, "Shell-2");
  EXPECT_EQ(c[4].nodes.kind, Kind::half_space);
  expect_vec(c[4].nodes.point, {0, 0, 0.01});
  expect_vec(c[4].nodes.normal, {0, 0.6, 0.8});
  expect_loc(c[4].nodes.loc, 82, 7);

  EXPECT_EQ(c[5].object, "liver_1");
  EXPECT_EQ(c[5].nodes.kind, Kind::all);
  expect_loc(c[5].nodes.loc, 83, 5);
}

TEST(SceneTest, FullSceneOutput) {
  const Scene scene = parse_scene(kFullScene, "full.yaml");
  EXPECT_DOUBLE_EQ(scene.output.interval, 0.05);
  EXPECT_FALSE(scene.output.vtk);
  expect_loc(scene.output.loc, 85, 1);
}

const std::string kMinimalObject = R"(objects:
  - name: a
    mesh: {generator: GENERATOR}
    material: {stiffness: 1, mass: 1}
)";

Scene minimal(const std::string& generator) {
  std::string text = kMinimalObject;
  text.replace(text.find("GENERATOR"), 9, generator);
  return parse_scene(text, "minimal.yaml");
}

TEST(SceneTest, OmittedFieldsTakeTheDefaultsOfTheStructs) {
  const Scene scene = minimal("box");
  const SimulationSpec d;
  const auto& s = scene.simulation;
  EXPECT_EQ(s.dt, d.dt);
  EXPECT_FALSE(s.dt.has_value());  // auto
  EXPECT_EQ(s.dt_safety, d.dt_safety);
  EXPECT_EQ(s.duration, d.duration);
  EXPECT_EQ(s.integrator, Integrator::verlet);
  EXPECT_EQ(s.mode, SolveMode::dynamic);
  EXPECT_EQ(s.gravity, d.gravity);
  EXPECT_EQ(s.damping, d.damping);
  EXPECT_EQ(s.tolerance, d.tolerance);
  EXPECT_EQ(s.max_iterations, d.max_iterations);
  EXPECT_EQ(s.load_steps, d.load_steps);
  EXPECT_EQ(s.relaxation, d.relaxation);
  EXPECT_EQ(s.loc.line, 0);  // no simulation section

  ASSERT_EQ(scene.objects.size(), 1u);
  const MaterialSpec m;
  const auto& material = scene.objects[0].material;
  EXPECT_FALSE(material.density.has_value());
  EXPECT_EQ(material.frame, FrameMode::polar);
  EXPECT_EQ(material.reaction, m.reaction);
  EXPECT_EQ(scene.objects[0].volume_constraint, ObjectSpec{}.volume_constraint);
  EXPECT_TRUE(scene.loads.empty());
  EXPECT_TRUE(scene.constraints.empty());
  EXPECT_EQ(scene.output.interval, OutputSpec{}.interval);
  EXPECT_EQ(scene.output.vtk, OutputSpec{}.vtk);
}

void expect_same_mesh(const MeshSpec& actual, const MeshSpec& expected) {
  EXPECT_EQ(actual.element, expected.element);
  EXPECT_EQ(actual.surface, expected.surface);
  EXPECT_EQ(actual.size, expected.size);
  EXPECT_EQ(actual.cells, expected.cells);
  EXPECT_EQ(actual.radii, expected.radii);
  EXPECT_EQ(actual.subdivisions, expected.subdivisions);
  EXPECT_EQ(actual.layers, expected.layers);
  EXPECT_EQ(actual.radius, expected.radius);
  EXPECT_EQ(actual.length, expected.length);
  EXPECT_EQ(actual.around, expected.around);
  EXPECT_EQ(actual.along, expected.along);
  EXPECT_EQ(actual.rings, expected.rings);
  EXPECT_EQ(actual.center, expected.center);
}

TEST(SceneTest, OmittedMeshFieldsTakeTheDefaultsOfEveryGenerator) {
  for (const std::string generator : {"box", "ellipsoid", "cylinder"}) {
    SCOPED_TRACE(generator);
    const Scene scene = minimal(generator);
    EXPECT_EQ(scene.objects.at(0).mesh.generator, generator);
    expect_same_mesh(scene.objects.at(0).mesh, MeshSpec{});
  }
}

TEST(SceneTest, OmittedConstraintFieldsTakeTheirDefaults) {
  const Scene scene = parse_scene(kMinimalObject.substr(0, kMinimalObject.find("GENERATOR")) +
                                      "box}\n    material: {stiffness: 1, mass: 1}\n"
                                      "constraints:\n"
                                      "  - {type: displacement, object: a, displacement: [0, 0, "
                                      "1 mm]}\n",
                                  "c.yaml");
  ASSERT_EQ(scene.constraints.size(), 1u);
  EXPECT_EQ(scene.constraints[0].axes, (std::array<bool, 3>{true, true, true}));
  EXPECT_EQ(scene.constraints[0].nodes.kind, Kind::all);
}

NodeSelector selector(const std::string& nodes) {
  const Scene scene = parse_scene(
      "objects:\n  - {name: a, mesh: {generator: box}, material: {stiffness: 1, mass: 1}}\n"
      "constraints:\n  - type: fixed\n    object: a\n    nodes: " +
          nodes + "\n",
      "s.yaml");
  return scene.constraints.at(0).nodes;
}

TEST(SceneTest, SelectorForms) {
  EXPECT_EQ(selector("7").kind, Kind::indices);  // a lone integer is a one-index list
  EXPECT_EQ(selector("7").indices, std::vector<int>{7});
  EXPECT_EQ(selector("\"0 - 2 , 9\"").indices, (std::vector<int>{0, 1, 2, 9}));
  EXPECT_EQ(selector("3-3").indices, std::vector<int>{3});
  EXPECT_EQ(selector("[4, 1e1, 4]").indices, (std::vector<int>{4, 10}));
  EXPECT_EQ(selector("left").kind, Kind::named);
  EXPECT_EQ(selector("3d_top").name, "3d_top");
  EXPECT_EQ(selector("{half_space: {point: [0, 0, 0], normal: [-2, 0, 0]}}").normal, Vec(-1, 0, 0));
  EXPECT_EQ(selector("{half_space: {point: [0, 0, 0], normal: [0, 0, 1e-300]}}").normal,
            Vec(0, 0, 1));
}

TEST(SceneTest, ParseErrorsOfDifferentFieldsAreAllReported) {
  try {
    parse_scene("simulation: {duration: -1, dt_safety: 2}\nobjects: []\noutput: {interval: -1}\n",
                "three.yaml");
    FAIL() << "no SceneError";
  } catch (const SceneError& e) {
    ASSERT_EQ(e.diagnostics().size(), 4u) << e.what();
    EXPECT_EQ(e.diagnostics()[0].str(), "three.yaml:1:24: 'duration' must be > 0 s (got -1 s)");
  }
}

TEST(SceneTest, LoadSceneReadsTheFile) {
  const auto path = std::filesystem::temp_directory_path() / "phymul_scene_test_full.yaml";
  std::ofstream(path) << kFullScene;
  const Scene scene = load_scene(path);
  EXPECT_EQ(scene.file, path);
  EXPECT_EQ(scene.objects.size(), 4u);
  EXPECT_EQ(scene.simulation.loc.file, path.string());
  std::filesystem::remove(path);
}

// Built field by field: GCC 12 at -O3 warns falsely about nested aggregate temporaries.
Diagnostic diagnostic(const std::string& file, int line, int column, const std::string& message) {
  Diagnostic d;
  d.loc.file = file;
  d.loc.line = line;
  d.loc.column = column;
  d.message = message;
  return d;
}

TEST(SceneTest, DiagnosticStrOmitsUnknownParts) {
  EXPECT_EQ(diagnostic("a.yaml", 3, 7, "bad").str(), "a.yaml:3:7: bad");
  EXPECT_EQ(diagnostic("a.yaml", 3, 0, "bad").str(), "a.yaml:3: bad");
  EXPECT_EQ(diagnostic("a.yaml", 0, 0, "bad").str(), "a.yaml: bad");
  EXPECT_EQ(diagnostic("", 0, 0, "bad").str(), "bad");
}

TEST(SceneTest, SceneErrorWhatJoinsDiagnostics) {
  const SceneError error({diagnostic("a.yaml", 1, 2, "one"), diagnostic("a.yaml", 3, 4, "two")});
  EXPECT_STREQ(error.what(), "a.yaml:1:2: one\na.yaml:3:4: two");
  EXPECT_EQ(error.diagnostics().size(), 2u);
}

TEST(SceneTest, ReferenceMarkdownHasARowForEveryFieldOfTheTable) {
  const std::string markdown = scene_reference_markdown();
  EXPECT_NE(markdown.find("| field | type | unit | range | default | description |"),
            std::string::npos);
  for (const auto& section : io::section_table()) {
    const std::string heading =
        section.name == "scene" ? "## Top level" : "## `" + std::string(section.path) + "`";
    EXPECT_NE(markdown.find(heading + "\n"), std::string::npos) << heading;
  }
  for (const auto& parameter : io::parameter_table()) {
    const std::string row = "| `" + std::string(parameter.name) + "` |";
    EXPECT_NE(markdown.find(row), std::string::npos) << row;
    EXPECT_NE(markdown.find(std::string(parameter.doc)), std::string::npos) << parameter.name;
  }
  EXPECT_NE(markdown.find("| `dt` | quantity or `auto` | s | > 0 | `auto` |"), std::string::npos);
  EXPECT_NE(markdown.find(
                "| `integrator` | enum | — | `verlet`, `newton-cotes`, `implicit` | `verlet` |"),
            std::string::npos);
}

TEST(SceneTest, ReferenceMarkdownRowsHaveSixCells) {
  const std::string markdown = scene_reference_markdown();
  size_t rows = 0;
  for (size_t start = 0; start < markdown.size();) {
    const size_t end = markdown.find('\n', start);
    const std::string line = markdown.substr(start, end - start);
    start = end == std::string::npos ? markdown.size() : end + 1;
    if (line.rfind("| `", 0) != 0 || line.find("| dimension") == 0) continue;
    // Unescaped '|' separate cells; escaped ones are content.
    size_t bars = 0;
    for (size_t i = 0; i < line.size(); ++i)
      bars += line[i] == '|' && (i == 0 || line[i - 1] != '\\');
    if (bars == 4) continue;  // the three-column units table
    EXPECT_EQ(bars, 7u) << line;
    ++rows;
  }
  EXPECT_EQ(rows, io::parameter_table().size());
}

}  // namespace
}  // namespace phymul
