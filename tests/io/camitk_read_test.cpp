// CamiTK PML and LML reading (camitk.hpp): sparse atom indices, every cell type in VTK's
// orientation, informative components as node sets, LML units and events, bad files.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <sstream>

#include "phymul/camitk.hpp"
#include "phymul/scene_io.hpp"
#include "support/expected_messages.hpp"
#include "support/process.hpp"

namespace phymul {
namespace {

namespace fs = std::filesystem;
using testing::read_text;

// Atoms with sparse indices (mm): a tetrahedron (10, 20, 35, 40), a hexahedron listed inside
// out as CamiTK allows (100-107), a wedge (200-205), a triangle and a quad (300-303); an
// informative face of the hexahedron and a cellRef to the tetrahedron.
const char* kModel = R"(<?xml version="1.0" encoding="UTF-8"?>
<physicalModel name="cells" nrOfAtoms="22" nrOfExclusiveComponents="5"
 nrOfInformativeComponents="2" nrOfCells="6">
<atoms><structuralComponent name="element list"><nrOfStructures value="22"/>
<atom><atomProperties index="10" x="0" y="0" z="0" mass="1"/></atom>
<atom><atomProperties index="20" x="10" y="0" z="0"/></atom>
<atom><atomProperties index="35" x="0" y="10" z="0"/></atom>
<atom><atomProperties index="40" x="0" y="0" z="10"/></atom>
<atom><atomProperties index="100" x="0" y="0" z="0"/></atom>
<atom><atomProperties index="101" x="0" y="0" z="10"/></atom>
<atom><atomProperties index="102" x="0" y="10" z="10"/></atom>
<atom><atomProperties index="103" x="0" y="10" z="0"/></atom>
<atom><atomProperties index="104" x="10" y="0" z="0"/></atom>
<atom><atomProperties index="105" x="10" y="0" z="10"/></atom>
<atom><atomProperties index="106" x="10" y="10" z="10"/></atom>
<atom><atomProperties index="107" x="10" y="10" z="0"/></atom>
<atom><atomProperties index="200" x="0" y="0" z="0"/></atom>
<atom><atomProperties index="201" x="10" y="0" z="0"/></atom>
<atom><atomProperties index="202" x="0" y="10" z="0"/></atom>
<atom><atomProperties index="203" x="0" y="0" z="10"/></atom>
<atom><atomProperties index="204" x="10" y="0" z="10"/></atom>
<atom><atomProperties index="205" x="0" y="10" z="10"/></atom>
<atom><atomProperties index="300" x="0" y="0" z="0"/></atom>
<atom><atomProperties index="301" x="10" y="0" z="0"/></atom>
<atom><atomProperties index="302" x="0" y="10" z="0"/></atom>
<atom><atomProperties index="303" x="10" y="10" z="0"/></atom>
</structuralComponent></atoms>
<exclusiveComponents><multiComponent name="Exclusive Components ">
<multiComponent name="Volumes">
<structuralComponent name="Tet" young="100" mode="WIREFRAME_AND_SURFACE">
<cell><cellProperties type="TETRAHEDRON" index="7"/>
<atomRef index="10"/><atomRef index="20"/><atomRef index="35"/><atomRef index="40"/></cell>
</structuralComponent>
<structuralComponent name="Hex"><nrOfStructures value="1"/>
<cell><cellProperties type="HEXAHEDRON"/>
<atomRef index="100"/><atomRef index="101"/><atomRef index="102"/><atomRef index="103"/>
<atomRef index="104"/><atomRef index="105"/><atomRef index="106"/><atomRef index="107"/></cell>
</structuralComponent>
<structuralComponent name="Wedge">
<cell><cellProperties type="WEDGE"/><atomRef index="200"/><atomRef index="201"/>
<atomRef index="202"/><atomRef index="203"/><atomRef index="204"/><atomRef index="205"/></cell>
</structuralComponent>
</multiComponent>
<structuralComponent name="Tri">
<cell><cellProperties type="TRIANGLE"/><atomRef index="300"/><atomRef index="301"/>
<atomRef index="302"/></cell></structuralComponent>
<structuralComponent name="Quad">
<cell><cellProperties type="QUAD"/><atomRef index="300"/><atomRef index="301"/>
<atomRef index="303"/><atomRef index="302"/></cell></structuralComponent>
</multiComponent></exclusiveComponents>
<informativeComponents><multiComponent name="Regions">
<structuralComponent name="Bottom Face">
<cell><cellProperties type="POLY_VERTEX"/><atomRef index="100"/><atomRef index="103"/>
<atomRef index="104"/><atomRef index="107"/></cell></structuralComponent>
<structuralComponent name="Tip"><cellRef index="7"/><atomRef index="300"/></structuralComponent>
</multiComponent></informativeComponents>
</physicalModel>
)";

Mesh object(const PmlModel& pml, const std::string& component, std::vector<int>* ids = nullptr) {
  return pml_object_mesh(pml, component, ids, "cells.pml");
}

TEST(Pml, SparseAtomIndicesBecomeNodesInFileOrder) {
  const PmlModel pml = parse_pml(kModel, "cells.pml", 1000.0);
  ASSERT_EQ(pml.atoms.size(), 22u);
  EXPECT_EQ(pml.atom_ids[2], 35);
  std::vector<int> ids;
  const Mesh tet = object(pml, "Tet", &ids);
  EXPECT_EQ(ids, (std::vector<int>{10, 20, 35, 40}));
  ASSERT_EQ(tet.points.size(), 4u);
  EXPECT_EQ(tet.points[1], Vec3(0.01, 0, 0));  // 10 mm, divided as the scene's units are
  ASSERT_EQ(tet.cells.size(), 1u);
  EXPECT_EQ(tet.cells[0].type, CellType::tetra);
  EXPECT_NEAR(cell_measure(tet.points, tet.cells[0]), 1e-6 / 6, 1e-18);
  EXPECT_NO_THROW(validate(tet));
}

TEST(Pml, AHexahedronListedInsideOutIsReorderedToAPositiveVolume) {
  const PmlModel pml = parse_pml(kModel, "cells.pml", 1000.0);
  const Mesh hex = object(pml, "Hex");
  ASSERT_EQ(hex.cells.size(), 1u);
  // Same edges as listed (0-1-2-3 and 4-5-6-7 faces, i with i+4), the faces swapped.
  const std::array<int, 8> expected{4, 5, 6, 7, 0, 1, 2, 3};
  EXPECT_TRUE(std::equal(expected.begin(), expected.end(), hex.cells[0].nodes.begin()));
  EXPECT_NEAR(cell_measure(hex.points, hex.cells[0]), 1e-6, 1e-18);
  EXPECT_NO_THROW(validate(hex));
  const Mesh wedge = object(pml, "Wedge");
  EXPECT_NEAR(cell_measure(wedge.points, wedge.cells[0]), 0.5e-6, 1e-18);
  EXPECT_NO_THROW(validate(wedge));
  ASSERT_FALSE(pml.notes.empty());
  EXPECT_NE(pml.notes[0].find("2 cells listed inside out"), std::string::npos) << pml.notes[0];
}

TEST(Pml, SurfaceCellsMultiComponentsAndInformativeNodeSets) {
  const PmlModel pml = parse_pml(kModel, "cells.pml", 1000.0);
  const Mesh tri = object(pml, "Tri"), quad = object(pml, "Quad");
  EXPECT_EQ(tri.cells[0].type, CellType::triangle);
  EXPECT_EQ(quad.cells[0].type, CellType::quad);
  EXPECT_TRUE(std::equal(quad.cells[0].nodes.begin(), quad.cells[0].nodes.begin() + 4,
                         std::array<int, 4>{0, 1, 3, 2}.begin()));
  const Mesh volumes = object(pml, "Volumes");  // the multiComponent: its three cells
  EXPECT_EQ(volumes.cells.size(), 3u);
  EXPECT_EQ(volumes.points.size(), 18u);
  const Mesh hex = object(pml, "Hex");
  ASSERT_TRUE(hex.node_sets.contains("Bottom_Face"));
  EXPECT_EQ(hex.node_sets.at("Bottom_Face"), (std::vector<int>{0, 3, 4, 7}));
  EXPECT_FALSE(hex.node_sets.contains("Tip"));  // none of its atoms
  const Mesh tet = object(pml, "Tet");
  EXPECT_EQ(tet.node_sets.at("Tip"), (std::vector<int>{0, 1, 2, 3}));        // by cellRef
  EXPECT_EQ(object(pml, "Tri").node_sets.at("Tip"), (std::vector<int>{0}));  // by atomRef
}

TEST(Pml, PropertiesNotReadAndWrongCountsAreNotesNamingThePlace) {
  std::string text = kModel;
  text.replace(text.find("nrOfCells=\"6\""), 13, "nrOfCells=\"9\"");
  const PmlModel pml = parse_pml(text, "cells.pml");
  std::string all;
  for (const std::string& n : pml.notes) all += n + "\n";
  EXPECT_NE(all.find("cells.pml:2:1: <physicalModel> nrOfCells says 9, the file holds 6"),
            std::string::npos)
      << all;
  EXPECT_NE(all.find("atom properties not read: mass"), std::string::npos) << all;
  EXPECT_NE(all.find("component properties not read: young"), std::string::npos) << all;
}

TEST(Pml, SeveralComponentsWithCellsNeedOneNamed) {
  const PmlModel pml = parse_pml(kModel, "cells.pml");
  try {
    object(pml, "");
    FAIL() << "no component chosen";
  } catch (const MeshFileError& e) {
    EXPECT_NE(std::string(e.what()).find("name one with 'component'"), std::string::npos);
  }
  EXPECT_THROW(object(pml, "Liver"), MeshFileError);
}

TEST(Lml, EventsDirectionsAndUnitsInSI) {
  const auto loads = parse_lml(R"(<?xml version="1.0"?>
<loads xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance">
<load xsi:type="Translation"><appliedTo>0-2,7</appliedTo>
<valueEvent date="1" value="2"/><valueEvent date="0" value="0"/>
<direction x="NULL" z="1"/><unit>mm</unit></load>
<load xsi:type="Force"><appliedTo>Bottom Face,*</appliedTo>
<valueEvent date="0" value="0.5"/><direction x="0" y="1" z="NULL"/><unit>kN</unit></load>
<load xsi:type="Pressure"><appliedTo>3</appliedTo><valueEvent date="0" value="7.5"/>
<unit>mmHg</unit></load>
</loads>)",
                               "loads.lml");
  ASSERT_EQ(loads.size(), 3u);
  const LmlLoad& t = loads[0];
  EXPECT_EQ(t.type, LmlLoad::Type::translation);
  EXPECT_EQ(t.atoms, (std::vector<int>{0, 1, 2, 7}));
  EXPECT_EQ(t.dates, (std::vector<double>{0, 1}));  // sorted, as CamiTK sorts them
  EXPECT_EQ(t.values, (std::vector<double>{0, 2.0 / 1000}));
  EXPECT_EQ(t.axes[0], LmlLoad::Axis::null);
  EXPECT_EQ(t.axes[1], LmlLoad::Axis::free);
  EXPECT_EQ(t.axes[2], LmlLoad::Axis::given);
  EXPECT_EQ(t.line, 3);
  EXPECT_EQ(loads[1].names, (std::vector<std::string>{"Bottom Face", "*"}));
  EXPECT_EQ(loads[1].values[0], 500.0);
  EXPECT_EQ(loads[2].values[0], 7.5 * 133.322387415);
  EXPECT_EQ(parse_lml("<loads><load xsi:type=\"Force\"><appliedTo>1</appliedTo><valueEvent "
                      "date=\"0\" value=\"2\"/><direction x=\"1\" y=\"0\" z=\"0\"/></load></loads>",
                      "default.lml")[0]
                .unit,
            "N");
}

// The fuzz seeds (tests/data/camitk) as a scene: the hexahedron held at its bottom face and
// pressed on z only, a force on the tetrahedron's tip from 0.5 s, a pressure on the quad (a
// single quad makes no object that runs; compiling LML loads is camitk_export_test's).
TEST(CamitkScene, LmlLoadsBecomeConstraintsLoadsAndPressuresOfThePmlObjects) {
  const fs::path dir = testing::source_dir() / "tests/data/camitk";
  std::string text = "objects:\n";
  for (const char* c : {"Hex", "Tet", "Quad"})
    text += fmt::format(
        "  - name: {}\n    mesh: {{file: cells.pml, component: {}, units: mm}}\n"
        "    material: {{stiffness: 10 N/m, mass: 0.001 kg}}\n",
        c, c);
  const std::string name = (dir / "scene.yaml").string();  // never written: paths are its
  Scene scene = parse_scene(text + "lml: loads.lml\n", name);
  ASSERT_EQ(scene.constraints.size(), 2u);
  EXPECT_EQ(scene.constraints[0].kind, ConstraintSpec::Kind::fixed);
  EXPECT_EQ(scene.constraints[0].nodes.indices, (std::vector<int>{0, 3, 4, 7}));
  EXPECT_EQ(scene.constraints[1].kind, ConstraintSpec::Kind::displacement);
  EXPECT_EQ(scene.constraints[1].axes, (std::array<bool, 3>{false, false, true}));
  EXPECT_EQ(scene.constraints[1].displacement.at(1.0), Vec3(0, 0, -0.002));
  EXPECT_EQ(scene.constraints[1].nodes.loc.line, 11);
  ASSERT_EQ(scene.loads.size(), 1u);
  EXPECT_EQ(scene.loads[0].object, "Tet");
  EXPECT_EQ(scene.loads[0].nodes.indices, (std::vector<int>{3}));
  EXPECT_EQ(scene.loads[0].force.at(0.4), Vec3::Zero());  // CamiTK: nothing before its date
  EXPECT_EQ(scene.loads[0].force.at(0.5), Vec3(0, 0, -0.1));
  ASSERT_EQ(scene.pressures.size(), 1u);
  EXPECT_EQ(scene.pressures[0].pressure.at(1.0).x(), 1500.0);
  EXPECT_EQ(scene.pressures[0].nodes.indices, (std::vector<int>{0, 1, 2, 3}));
  prepare_scene(scene);  // once only
  EXPECT_EQ(scene.constraints.size(), 2u);
}

// expected.txt as "file | message".
TEST(CamitkFile, EveryBadFileReportsItsExpectedMessage) {
  testing::expect_every_file_refused<MeshFileError>(
      testing::source_dir() / "tests/data/bad_camitk",
      [](const fs::path& p) {
        if (p.extension() == ".lml")
          read_lml(p);
        else
          pml_object_mesh(read_pml(p), "", nullptr, p.string());
      },
      20);
}

}  // namespace
}  // namespace phymul
