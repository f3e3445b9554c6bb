// The Truth Cube validation (DESIGN 6): measured bead positions inside a silicone cube
// compressed between plates, compared with the shape-memory model and the reference FEM.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "phymul/mesh.hpp"

namespace phymul::truthcube {

constexpr int kLevels = 3;  // 5 %, 12.5 %, 18.25 % nominal strain
constexpr std::array<double, kLevels> kStrain{0.05, 0.125, 0.1825};
constexpr double kEdge = 0.080;  // m
// The paper's mean relative errors (%, equation 1), per level.
constexpr std::array<double, kLevels> kPaperPhymul{35.6, 21.5, 16.9};
constexpr std::array<double, kLevels> kPaperAnsys{33.8, 20.2, 16.8};

struct Bead {
  std::array<int, 3> index;              // i, j, k in 1..7 (k along z)
  Vec3 rest;                             // m, CT frame
  std::array<Vec3, kLevels> compressed;  // m, per level
};

// Reads the CSV of the Truth Cube (see data/truthcube/SOURCE.md); throws std::runtime_error
// naming the file, line and field for anything malformed.
std::vector<Bead> load_beads(const std::filesystem::path& csv);

// Where the cube sits in the data frame: base (fixed plate) on the side of layer k = 1 at
// larger z, compression plate at smaller z moving towards +z.
struct CubeFrame {
  Vec3 center;     // m
  double base_z;   // m, z of the fixed face
  double plate_z;  // m, z of the pushed face
};
CubeFrame locate_cube(const std::vector<Bead>& beads);

// Trilinear embedding of points in an axis-aligned hexahedral box grid: node ids and
// weights of the cell that contains each point.
struct Embedding {
  std::vector<std::array<int, 8>> nodes;
  std::vector<std::array<double, 8>> weights;
  std::vector<Vec3> apply(const std::vector<Vec3>& positions) const;
};
Embedding embed(const Mesh& box, const std::vector<Vec3>& points);

// Errors of simulated bead positions against the measured ones at one level.
struct Metrics {
  double mean_error_mm = 0, max_error_mm = 0;
  double mean_relative_error_pct = 0;             // the paper's equation (1), mean over beads
  double sum_ratio_pct = 0;                       // sum |err| / sum |measured displacement|
  double mean_relative_error_pct_translated = 0;  // after the best rigid translation
  double mean_error_mm_translated = 0;
};
Metrics compare(const std::vector<Bead>& beads, int level, const std::vector<Vec3>& simulated);

}  // namespace phymul::truthcube

#include "phymul/scene.hpp"

namespace phymul::truthcube {

struct StudyOptions {
  int cells = 8;  // hexahedra per edge
  FrameMode frame = FrameMode::polar;
  bool reaction = true;
  bool volume_constraint = true;  // shape-memory model
  bool sliding = false;           // plates let the faces slide (default: no slip)
  bool fem = true;                // also run the reference FEM
  double young = 14.9e3;  // Pa: the FEM's, and the shape memory's K (calibrate_object), on which
                          // its positions do not depend
  double poisson = 0.499;
  bool incompatible_modes = false;  // FEM hexahedra: Wilson's modes (C3D8I), not Q1/P0
  // Shape-memory equilibrium: largest residual force over K h (the force of a one-cell
  // displacement). On 8^3 cells, relaxing on from 1e-7 to 1e-9 moves no bead by more than
  // 0.15 um (measured), far below the 0.3 mm noise of the beads.
  double tolerance = 1e-7;
  // How the shape memory reaches each equilibrium: FIRE relaxation, or the implicit static
  // solver's local/global iterations (the same equilibria, in far fewer passes).
  StaticSolver solver = StaticSolver::relaxation;
};

struct LevelResult {
  int level = 0;
  std::string model;  // "lsm" or "fem"
  Metrics metrics;
  std::vector<Vec3> positions;  // m, mesh nodes
  std::vector<Vec3> beads;      // m, simulated bead positions
  double plate_force = 0.0;     // N; shape memory: at the K calibrated from young and poisson
  long iterations = 0;          // relaxation iterations (lsm) or Newton iterations (fem)
  double seconds = 0.0;         // wall time of this level's solve
};

struct Study {
  Mesh mesh;  // the cube in the data frame
  CubeFrame frame;
  std::vector<LevelResult> results;  // per model, per level
};

Study run_study(const std::vector<Bead>& beads, const StudyOptions& options);

}  // namespace phymul::truthcube

namespace phymul::truthcube {

// The table of DESIGN 6 beside the paper's figures (text for a terminal).
std::string table(const Study& study, const StudyOptions& options);
// {"levels": [{"strain": 0.05, "model": "lsm", "mean_error_mm": ...}, ...]}
std::string json(const Study& study, const StudyOptions& options);
// Into dir: truthcube_<model>_<level>.vtu (deformed mesh), beads_<model>_<level>.vtu
// (simulated beads with the measured positions and errors), beads.csv (every bead, level and
// model: for plots), truthcube.json. Files are written atomically.
void write_outputs(const Study& study, const std::vector<Bead>& beads, const StudyOptions& options,
                   const std::filesystem::path& dir);

}  // namespace phymul::truthcube
