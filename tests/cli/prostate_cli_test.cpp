// `phymul prostate` from the command line, and the example scenes it writes.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "phymul/scene_io.hpp"
#include "phymul/studies/prostate.hpp"
#include "support/process.hpp"

namespace phymul {
namespace {

using testing::cli;
using testing::read_text;
using testing::run_command;
using testing::source_dir;
using testing::TempDir;

TEST(ProstateCli, WritesTheTableTheJsonAndTheSeries) {
  TempDir dir;
  const auto json = dir.path() / "p.json";
  const auto r = run_command(
      fmt::format("OMP_NUM_THREADS=1 '{}' prostate --fillings 50 --probe pressure --no-pictures "
                  "--no-real-time -q -o '{}' --json '{}'",
                  cli(), (dir.path() / "out").string(), json.string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("pressure"), std::string::npos) << r.output;
  const std::string text = read_text(json);
  EXPECT_EQ(text, read_text(dir.path() / "out" / "prostate.json"));
  for (const char* key : {"\"fillings\": [", "\"probe\": \"pressure\"",
                          "\"prostate_deformation_pct\": 1", "\"probe_force_n\": 1."})
    EXPECT_NE(text.find(key), std::string::npos) << key << " in " << text;
  const std::string volume = "\"bladder_volume_ml\": ";
  ASSERT_NE(text.find(volume), std::string::npos) << text;
  EXPECT_NEAR(std::stod(text.substr(text.find(volume) + volume.size())), 50.0, 1e-9) << text;
  EXPECT_EQ(text.find("nan"), std::string::npos);
  // The scene it ran, which `phymul run` takes, and the series of its equilibria.
  const auto scene = dir.path() / "out" / "50mL_pressure.yaml";
  EXPECT_EQ(run_command(fmt::format("'{}' check '{}'", cli(), scene.string())).exit_code, 0);
  const std::string pvd = read_text(dir.path() / "out" / "50mL_pressure.pvd");
  for (int k = 0; k < 5; ++k) {
    const std::string vtu = fmt::format("50mL_pressure_{}.vtu", k);
    EXPECT_NE(pvd.find(vtu), std::string::npos);
    EXPECT_TRUE(std::filesystem::exists(dir.path() / "out" / vtu));
  }
}

// The rigid probe is written beside each equilibrium, so that its pictures show it.
TEST(ProstateCli, RigidRunsWriteTheProbeBesideEachFrame) {
  TempDir dir;
  const auto r = run_command(
      fmt::format("OMP_NUM_THREADS=1 '{}' prostate --fillings 50 --probe rigid --no-pictures "
                  "--no-real-time -q -o '{}'",
                  cli(), (dir.path() / "out").string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (int k = 0; k < 5; ++k) {
    const auto probe = dir.path() / "out" / fmt::format("50mL_rigid_obstacles_{}.vtu", k);
    ASSERT_TRUE(std::filesystem::exists(probe)) << probe;
    EXPECT_NE(read_text(probe).find("Name=\"obstacle\""), std::string::npos);
  }
}

// --static-solver implicit: the same equilibria by the implicit static solver, said in the JSON.
TEST(ProstateCli, TheImplicitStaticSolverFindsTheSameDeformation) {
  TempDir dir;
  auto deformation = [&](const std::string& solver) {
    const auto json = dir.path() / (solver + ".json");
    const auto r = run_command(fmt::format(
        "OMP_NUM_THREADS=1 '{}' prostate --fillings 50 --probe pressure --static-solver {} "
        "--tolerance 1e-8 --no-pictures --no-real-time -q -o '{}' --json '{}'",
        cli(), solver, (dir.path() / solver).string(), json.string()));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    const std::string text = read_text(json);
    EXPECT_NE(text.find(fmt::format("\"static_solver\": \"{}\"", solver)), std::string::npos)
        << text;
    const std::string key = "\"prostate_deformation_pct\": ";
    const size_t at = text.find(key);
    return at == std::string::npos ? 0.0 : std::stod(text.substr(at + key.size()));
  };
  const double relaxed = deformation("relaxation"), implicit = deformation("implicit");
  EXPECT_GT(relaxed, 1.0);  // per cent
  EXPECT_NEAR(implicit, relaxed, 1e-5 * relaxed);
}

// --relaxation: FIRE (the default) and kinetic damping relax to the same equilibrium, said in
// the JSON and in the scene the run writes.
TEST(ProstateCli, FireAndKineticDampingFindTheSameDeformation) {
  TempDir dir;
  auto deformation = [&](const std::string& relaxation) {
    const auto json = dir.path() / (relaxation + ".json");
    const auto r = run_command(fmt::format(
        "OMP_NUM_THREADS=1 '{}' prostate --fillings 50 --probe pressure --relaxation {} "
        "--tolerance 1e-8 --no-pictures --no-real-time -q -o '{}' --json '{}'",
        cli(), relaxation, (dir.path() / relaxation).string(), json.string()));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    const std::string text = read_text(json);
    EXPECT_NE(text.find(fmt::format("\"relaxation\": \"{}\"", relaxation)), std::string::npos)
        << text;
    const std::string scene = read_text(dir.path() / relaxation / "50mL_pressure.yaml");
    EXPECT_NE(scene.find("relaxation: " + relaxation), std::string::npos) << scene;
    const std::string key = "\"prostate_deformation_pct\": ";
    const size_t at = text.find(key);
    return at == std::string::npos ? 0.0 : std::stod(text.substr(at + key.size()));
  };
  const double fire = deformation("fire"), kinetic = deformation("kinetic");
  EXPECT_GT(fire, 1.0);  // per cent
  EXPECT_NEAR(kinetic, fire, 1e-5 * fire);
}

// The paper's configuration by the implicit static solver, which takes the organs' contact
// pair: the prostate on 11.5 N/m side springs (docs/validation.md) finds both fillings'
// equilibria, the empty bladder's deformation the larger; hanging from a single stitched node
// at 400 mL there is none, and the run says so after its hundred steps instead of running on.
TEST(ProstateCli, InThePapersConfigurationTheImplicitSolverFindsEquilibriaOrSaysThereAreNone) {
  TempDir dir;
  const std::string paper = fmt::format(
      "OMP_NUM_THREADS=1 '{}' prostate --support bladder --support-stiffness 11.5 --probe rigid "
      "--static-solver implicit --no-pictures --no-real-time -q",
      cli());
  const auto json = dir.path() / "paper.json";
  const auto r = run_command(fmt::format("{} --fillings 50,400 -o '{}' --json '{}'", paper,
                                         (dir.path() / "paper").string(), json.string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string text = read_text(json);
  std::vector<double> deformation;
  const std::string key = "\"prostate_deformation_pct\": ";
  for (size_t at = text.find(key); at != std::string::npos; at = text.find(key, at + 1))
    deformation.push_back(std::stod(text.substr(at + key.size())));
  ASSERT_EQ(deformation.size(), 2u) << text;
  EXPECT_GT(deformation[0], 4.0);  // per cent, 50 mL
  EXPECT_GT(deformation[0], deformation[1]);
  const auto none = run_command(fmt::format("{} --fillings 400 --stitch-radius 5 -o '{}'", paper,
                                            (dir.path() / "none").string()));
  EXPECT_NE(none.exit_code, 0);
  EXPECT_NE(none.output.find("no equilibrium"), std::string::npos) << none.output;
  EXPECT_NE(none.output.find("after 100 iterations"), std::string::npos) << none.output;
}

TEST(ProstateCli, RefusesAFillingOutOfRange) {
  const auto r = run_command(fmt::format("'{}' prostate --fillings 2000 -q", cli()));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("--fillings"), std::string::npos) << r.output;
}

TEST(ProstateExamples, AreTheScenesTheStudyWrites) {
  for (const auto& [options, dir] :
       {std::pair{prostate::Options{}, "prostate"},
        std::pair{prostate::coarse_bladder(prostate::Options{}), "prostate/coarse"}})
    for (double ml : {50.0, 400.0})
      for (prostate::Probe probe : {prostate::Probe::pressure, prostate::Probe::rigid}) {
        // The rigid probe placed against the gravity equilibrium, in whole micrometres.
        const prostate::SceneSettings s = prostate::dynamic_scene(options, ml * 1e-6, probe);
        const auto file =
            source_dir() / "examples" / dir / (prostate::run_name(ml * 1e-6, probe) + ".yaml");
        EXPECT_EQ(read_text(file), prostate::scene_text(options, s)) << file;
        EXPECT_NO_THROW(compile_scene(load_scene(file))) << file;
      }
}

}  // namespace
}  // namespace phymul
