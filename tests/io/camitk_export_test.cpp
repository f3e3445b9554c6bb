// `phymul export-pml` and back (camitk.hpp): a scene with several objects, node sets, fixed
// and prescribed nodes, forces and a pressure written as PML and LML, read back as a scene
// with the same nodes, cells, node sets and loads, and run to the same result.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "phymul/camitk.hpp"
#include "phymul/model.hpp"
#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "support/process.hpp"

namespace phymul {
namespace {

namespace fs = std::filesystem;

const char* kSimulation = "simulation: {dt: 1e-4 s, duration: 0.01 s}\n";
const char* kObjects[2] = {
    "  - name: block\n    material: {stiffness: 50 N/m, density: 1000 kg/m^3}\n",
    "  - name: cap\n    material: {stiffness: 30 N/m, density: 1000 kg/m^3}\n"};

// Two boxes (hexahedra, tetrahedra), one held at its base and pressed, one loaded by a force
// that turns (split into one LML load per axis) and a pressure.
std::string original_scene() {
  return std::string(kSimulation) + "objects:\n" + kObjects[0] +
         "    mesh: {generator: box, size: [20 mm, 20 mm, 10 mm], cells: [2, 2, 1], "
         "center: [0, 0, 5 mm]}\n" +
         kObjects[1] +
         "    mesh: {generator: box, element: tetra, size: [10 mm, 10 mm, 10 mm], cells: [1, 1, "
         "2], center: [0, 0, 30 mm]}\n"
         "constraints:\n"
         "  - {type: fixed, object: block, nodes: bottom}\n"
         "  - type: displacement\n    object: block\n    nodes: top\n    axes: z\n"
         "    schedule: [{t: 0 s, value: [0, 0, 0]}, {t: 0.01 s, value: [0, 0, -1 mm]}]\n"
         "  - {type: fixed, object: cap, nodes: bottom}\n"
         "loads:\n"
         "  - type: force\n    object: cap\n    nodes: top\n"
         "    schedule: [{t: 0 s, value: [0, 0, 0]}, {t: 0.005 s, value: [0.01 N, 0, -0.02 N]},"
         " {t: 0.01 s, value: [0, 0.01 N, 0]}]\n"
         "  - type: pressure\n    object: block\n    nodes: right\n"
         "    pressure_schedule: [{t: 0 s, value: 0 Pa}, {t: 0.01 s, value: 200 Pa}]\n";
}

std::string exported_scene(const std::string& stem) {
  std::string s = std::string(kSimulation) + "objects:\n";
  for (int i = 0; i < 2; ++i)
    s += std::string(kObjects[i]) + "    mesh: {file: out/" + stem +
         ".pml, component: " + (i == 0 ? "block" : "cap") + ", units: mm}\n";
  return s + "lml: out/" + stem + ".lml\n";
}

void write(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

struct RoundTrip {
  testing::TempDir dir;
  Scene original, back;
  PmlExport exported;
  RoundTrip() {
    write(dir.path() / "scene.yaml", original_scene());
    original = load_scene(dir.path() / "scene.yaml");
    exported = export_pml(original, dir.path() / "out");
    write(dir.path() / "back.yaml", exported_scene("scene"));
    back = load_scene(dir.path() / "back.yaml");
  }
};

// Positions in mm and back: within a few units of the last place.
void expect_same_points(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i)
    EXPECT_LE((a[i] - b[i]).norm(), 1e-12 * 0.04) << "node " << i;
}

TEST(CamitkExport, RoundTripKeepsNodesCellsAndNodeSets) {
  RoundTrip r;
  EXPECT_TRUE(fs::exists(r.exported.pml) && fs::exists(r.exported.lml));
  for (size_t o = 0; o < 2; ++o) {
    const Mesh a = make_mesh(r.original.objects[o].mesh), b = make_mesh(r.back.objects[o].mesh);
    expect_same_points(a.points, b.points);
    ASSERT_EQ(a.cells.size(), b.cells.size());
    for (size_t c = 0; c < a.cells.size(); ++c) {
      EXPECT_EQ(a.cells[c].type, b.cells[c].type);
      EXPECT_EQ(a.cells[c].nodes, b.cells[c].nodes) << "cell " << c;
    }
    EXPECT_EQ(a.node_sets, b.node_sets);
  }
  // Object after object from atom 0, as the generated meshes have no atom indices.
  EXPECT_EQ(r.back.objects[1].mesh.atom_ids.front(),
            int(make_mesh(r.original.objects[0].mesh).points.size()));
}

// The loads of a model at time t: per node, the force and the prescribed displacement on each
// axis (NaN where free); per face, the pressure.
struct LoadsAt {
  std::vector<Vec3> force, displacement;
  std::map<std::array<int, 3>, double> pressure;
};

LoadsAt loads_at(const Model& m, double t) {
  LoadsAt l;
  l.force.assign(size_t(m.node_count()), Vec3::Zero());
  l.displacement.assign(size_t(m.node_count()), Vec3::Constant(std::nan("")));
  for (const AppliedForce& f : m.forces)
    for (int n : f.nodes) l.force[size_t(n)] += f.force.at(t);
  for (const PrescribedDisplacement& p : m.prescribed)
    for (int n : p.nodes)
      for (int k = 0; k < 3; ++k)
        if (p.axes[size_t(k)]) l.displacement[size_t(n)][k] = p.displacement.at(t)[k];
  for (const PressureLoad& p : m.pressures)
    for (const Triangle& f : p.faces) l.pressure[f] += p.pressure.at(t).x();
  return l;
}

TEST(CamitkExport, RoundTripKeepsFixedPrescribedForcesAndPressures) {
  RoundTrip r;
  const Model a = compile_scene(r.original), b = compile_scene(r.back);
  EXPECT_EQ(b.forces.size(), 3u);  // the turning force, one load per axis
  for (double t : {0.0, 0.0025, 0.005, 0.0075, 0.01, 0.02}) {
    const LoadsAt la = loads_at(a, t), lb = loads_at(b, t);
    for (size_t n = 0; n < la.force.size(); ++n) {
      EXPECT_LE((la.force[n] - lb.force[n]).norm(), 1e-15) << "t " << t << " node " << n;
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(std::isnan(la.displacement[n][k]), std::isnan(lb.displacement[n][k]));
        if (!std::isnan(la.displacement[n][k])) {
          EXPECT_NEAR(la.displacement[n][k], lb.displacement[n][k], 1e-15);
        }
      }
    }
    ASSERT_EQ(la.pressure.size(), lb.pressure.size());
    for (const auto& [face, p] : la.pressure) EXPECT_NEAR(lb.pressure.at(face), p, 1e-12);
  }
}

TEST(CamitkExport, ARunFromPmlAndLmlEqualsTheYamlScene) {
  RoundTrip r;
  Simulator a(compile_scene(r.original)), b(compile_scene(r.back));
  ASSERT_EQ(a.dt(), b.dt());
  for (int i = 0; i < 100; ++i) a.step(), b.step();
  double largest = 0.0, moved = 0.0;
  for (size_t n = 0; n < a.data().x.size(); ++n) {
    largest = std::max(largest, (a.data().x[n] - b.data().x[n]).norm());
    moved = std::max(moved, (a.data().x[n] - a.model().rest_position[n]).norm());
  }
  EXPECT_GT(moved, 5e-4);  // the top pressed by 1 mm: something happened
  EXPECT_LE(largest, 1e-12);
}

TEST(CamitkExport, NotesSayWhatLmlCannotExpress) {
  testing::TempDir dir;
  std::string text = original_scene();
  text.replace(text.find("constraints:\n"), 13,
               "constraints:\n  - {type: spring, object: cap, nodes: top, stiffness: 5 N/m}\n");
  write(dir.path() / "s.yaml", text);
  const PmlExport e = export_pml(load_scene(dir.path() / "s.yaml"), dir.path() / "out");
  std::string all;
  for (const std::string& n : e.notes) all += n + "\n";
  EXPECT_NE(all.find("spring constraints cannot be said in PML or LML"), std::string::npos) << all;
  EXPECT_NE(all.find("materials are not written"), std::string::npos) << all;
}

TEST(CamitkScene, AnLmlLoadOnAnAtomNoObjectHoldsNamesTheLine) {
  RoundTrip r;
  write(r.dir.path() / "out/bad.lml",
        "<loads>\n<load xsi:type=\"Force\">\n<appliedTo>2,999</appliedTo>\n<valueEvent "
        "date=\"0\" value=\"1\"/>\n<direction x=\"0\" y=\"0\" z=\"1\"/>\n</load>\n</loads>\n");
  std::string text = exported_scene("scene");
  text.replace(text.find("out/scene.lml"), 13, "out/bad.lml");
  write(r.dir.path() / "bad.yaml", text);
  try {
    load_scene(r.dir.path() / "bad.yaml");
    FAIL() << "atom 999 accepted";
  } catch (const SceneError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("out/bad.lml:2: the Force load applies to atom 999, which no object "
                        "holds"),
              std::string::npos)
        << what;
  }
}

TEST(CamitkScene, ComponentOnAnotherFileAndLmlWithoutPmlAreRefused) {
  testing::TempDir dir;
  write(dir.path() / "l.lml", "<loads/>");
  write(dir.path() / "s.yaml", std::string(kSimulation) + "objects:\n" + kObjects[0] +
                                   "    mesh: {generator: box}\nlml: l.lml\n");
  try {
    load_scene(dir.path() / "s.yaml");
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("s.yaml:6:6: 'lml' loads atoms of a CamiTK PML file"),
              std::string::npos)
        << e.what();
  }
  write(dir.path() / "v.yaml", std::string(kSimulation) + "objects:\n" + kObjects[0] +
                                   "    mesh: {file: m.vtk, component: Tet}\n");
  try {
    load_scene(dir.path() / "v.yaml");
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("v.yaml:5:5: 'component' applies only to a CamiTK PML "
                                         "file (.pml), not m.vtk"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace phymul
