// Stiffness from Young's modulus: K = alpha * E * h for the local shape memory model, with h
// the mesh's mean rest edge length and alpha a dimensionless constant per mesh type,
// calibrated against the reference FEM (a bonded small-strain compression of a cube) and
// checked on a different load (a cantilever under gravity).
//
// Why a ratio of forces: with only prescribed displacements the shape-memory positions do
// not depend on K and every force scales with K, so one relaxation at any K gives the top
// force per unit K, and alpha = F_fem / (F_lsm(K = 1) * E * h).
#pragma once

#include <string>
#include <vector>

#include "phymul/mesh.hpp"
#include "phymul/model.hpp"

namespace phymul::calibration {

// Mean length (m) of the mesh's distinct edges (pairs of nodes sharing a cell edge), at rest.
// Throws std::invalid_argument for a mesh without edges.
double mean_edge_length(const Mesh& mesh);

struct Options {
  // Calibration load: a cube of `edge`, base fixed, top pushed down by strain * edge, both
  // without slip.
  double edge = 0.040;    // m
  double strain = 0.02;   // nominal compression
  double young = 14.9e3;  // Pa; the forces scale with it, alpha does not depend on it
  // FEM Poisson ratios. Linear tetrahedra lock near 0.5, so they get a compressible 0.45;
  // hexahedra (mean dilatation) take the nearly incompressible 0.499.
  double poisson_hexa = 0.499;
  double poisson_tetra = 0.45;
  // The shape-memory model with its volume constraint (how tissue is simulated): the K
  // calibrated is the K for that use, on both mesh types.
  bool volume_constraint = true;
  // Shape-memory equilibrium: largest residual nodal force relative to the load's nodal
  // force scale (compression: K * strain * h; cantilever: the heaviest node's weight).
  double tolerance = 1e-8;
  long max_iterations = 2000000;
  // Check load: a beam fixed at x- (all axes), under gravity along -z.
  Vec3 beam = Vec3(0.080, 0.020, 0.020);  // m
  double density = 1000.0;                // kg/m^3
  double gravity = 9.81;                  // m/s^2
  double beam_young = 0.5e6;  // Pa: Euler-Bernoulli tip deflection about 3.8 % of the length
  bool cantilever = true;     // also run the check load
};

// The calibration load on one mesh.
struct Compression {
  CellType type = CellType::hexa;
  int cells = 0;                  // cells per cube edge
  double h = 0.0;                 // m, mean edge length
  double poisson = 0.0;           // of the FEM
  double fem_force = 0.0;         // N, |top reaction| of the FEM
  double lsm_force_per_k = 0.0;   // N per N/m of K: |top reaction| of the shape memory
  double alpha = 0.0;             // fem_force / (lsm_force_per_k * E * h)
  double lsm_force = 0.0;         // N, |top reaction| relaxed again with K = alpha E h
  double force_rel_diff = 0.0;    // (lsm_force - fem_force) / fem_force
  double displacement_rms = 0.0;  // rms over nodes of |u_lsm - u_fem|, over the push
  double displacement_max = 0.0;  // largest |u_lsm - u_fem|, over the push
  long lsm_iterations = 0;
  int fem_newton_iterations = 0;
};

// The check load on one mesh, with K = alpha * E * h.
struct Cantilever {
  CellType type = CellType::hexa;
  int cells = 0;  // cells per `edge` of length (the beam's cells are of the cube's size)
  double alpha = 0.0;
  double h = 0.0;                    // m, mean edge length of the beam mesh
  double stiffness = 0.0;            // N/m
  double fem_tip = 0.0;              // m, mean downward displacement of the free end's nodes
  double lsm_tip = 0.0;              // m
  double euler_bernoulli_tip = 0.0;  // m, rho g A L^4 / (8 E I), for scale
  double tip_ratio = 0.0;            // lsm_tip / fem_tip
  double tip_rel_diff = 0.0;         // (lsm_tip - fem_tip) / fem_tip
  double displacement_rms = 0.0;     // rms over nodes of |u_lsm - u_fem|, over fem_tip
  double displacement_max = 0.0;     // largest |u_lsm - u_fem|, over fem_tip
  long lsm_iterations = 0;
};

struct Row {
  Compression compression;
  Cantilever cantilever;  // zero when Options::cantilever is false
};

struct Result {
  Options options;
  std::vector<Row> rows;  // per mesh type, per resolution
  double seconds = 0.0;
};

// cells: hexahedra per cube edge (the tetra mesh splits each into 6). Throws
// std::runtime_error when a solve does not converge.
Compression calibrate_compression(CellType type, int cells, const Options& options = {});
Cantilever check_cantilever(CellType type, int cells, double alpha, const Options& options = {});

// A shape-memory object's K from its Young's modulus, calibrated on the object itself: its
// mesh clamped at both ends along `axis` (the nodes within h/4 of the lowest and of the
// highest coordinate, at least the 4 extreme ones each) and compressed by `strain` of its
// extent, without slip; K makes the shape memory's force on the pushed nodes (with the
// volume constraint when the object has one) the FEM's (linear law, `material.young` and
// `material.poisson`; hexahedra with mean dilatation, tetrahedra and wedges cut into three).
// The record also compares the two displacement fields. Throws std::invalid_argument for a
// surface mesh or an object too thin along the axis, std::runtime_error when a solve fails.
StiffnessCalibration calibrate_object(const std::string& name, const Mesh& mesh,
                                      const MaterialSpec& material, bool volume_constraint,
                                      int axis = 2, double strain = 0.01);

// Every type at every resolution (cells per cube edge).
Result run(const std::vector<CellType>& types, const std::vector<int>& resolutions,
           const Options& options = {});

// The table for a terminal, and {"options": {...}, "rows": [{...}, ...]}.
std::string table(const Result& result);
std::string json(const Result& result);

}  // namespace phymul::calibration
