// `phymul export-pml` as a user runs it: the files, the notes, and a scene reading them back
// that `phymul check` accepts with the PML's notes; a bad scene exits 1 at its place.
#include <gtest/gtest.h>

#include <fstream>

#include "support/process.hpp"

namespace phymul {
namespace {

using testing::cli;
using testing::run_command;

TEST(ExportPml, WritesPmlAndLmlWithNotesAndTheyCheckAsAScene) {
  testing::TempDir dir;
  std::ofstream(dir.path() / "s.yaml")
      << "simulation: {dt: 1e-4 s, duration: 0.01 s}\n"
         "objects:\n  - name: block\n"
         "    mesh: {generator: box, size: [20 mm, 20 mm, 10 mm], cells: [2, 2, 1]}\n"
         "    material: {stiffness: 50 N/m, density: 1000 kg/m^3}\n"
         "constraints:\n  - {type: fixed, object: block, nodes: bottom}\n"
         "  - {type: spring, object: block, nodes: top, stiffness: 3 N/m}\n"
         "loads:\n  - {type: force, object: block, nodes: top, force: [0, 0, -0.01 N]}\n";
  const std::string out = (dir.path() / "out").string();
  auto r = run_command(cli() + " export-pml " + (dir.path() / "s.yaml").string() + " -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("1 objects written to " + out + "/s.pml and " + out + "/s.lml"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("note: spring constraints cannot be said in PML or LML"),
            std::string::npos)
      << r.output;
  const std::string lml = testing::read_text(dir.path() / "out/s.lml");
  EXPECT_NE(lml.find("<appliedTo>9-17</appliedTo>"), std::string::npos) << lml;
  std::ofstream(dir.path() / "back.yaml")
      << "objects:\n  - name: block\n    mesh: {file: out/s.pml, units: mm}\n"
         "    material: {stiffness: 50 N/m, density: 1000 kg/m^3}\nlml: out/s.lml\n";
  r = run_command(cli() + " check " + (dir.path() / "back.yaml").string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(": ok (1 objects, 18 nodes, 4 cells"), std::string::npos) << r.output;
}

TEST(ExportPml, ABadSceneExitsOneAtItsPlace) {
  testing::TempDir dir;
  std::ofstream(dir.path() / "bad.yaml") << "objects:\n  - name: block\n    mesh: {file: no.pml}\n"
                                            "    material: {stiffness: 1 N/m, density: 1000}\n";
  const auto r = run_command(cli() + " export-pml " + (dir.path() / "bad.yaml").string() + " -o " +
                             (dir.path() / "out").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("no.pml: cannot open the PML file"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace phymul
