// Reference finite elements (DESIGN 5): total Lagrangian, large deformation, static Newton.
// The yardstick the shape-memory model is measured against, cross-checked with CalculiX.
#pragma once

#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "phymul/mesh.hpp"

namespace phymul::fem {

enum class Law {
  neo_hookean,  // compressible Neo-Hookean, W = mu/2 (I1bar - 3) + kappa/2 (J - 1)^2
  linear,       // small-strain linear elasticity (geometrically linear)
};

// How a linear hexahedron avoids volumetric locking near nu = 0.5 (src/fem/README.md).
enum class HexaElement {
  mean_dilatation,     // Q1/P0: one volume constraint per element (the default)
  incompatible_modes,  // Wilson's three bubble modes, full integration: CalculiX's C3D8I
};

struct Material {
  Law law = Law::neo_hookean;
  double young = 14.9e3;  // Pa
  double poisson = 0.499;
  HexaElement hexa = HexaElement::mean_dilatation;
};

// A prescribed displacement component (m) reached at the end of the load stepping.
struct Dirichlet {
  int node = 0;
  int axis = 0;  // 0 x, 1 y, 2 z
  double value = 0.0;
};

// Where a solve stands after a converged load step: everything its next load steps read, so
// that a solve given it (Problem::resume_from) goes on exactly as if it had never stopped (a
// run's checkpoint holds it). Vectors are over all dofs (3 per node) unless said otherwise.
struct SolveState {
  int load_steps_done = 0;
  int newton_iterations = 0;
  double load_factor = 0.0;
  std::vector<double> displacement;  // m
  // The last increment's second-order term, which the next predictor scales and adds (m), and
  // that increment's load factor (0: none).
  std::vector<double> curvature;
  double curvature_increment = 0.0;
  // The tangent the next predictor solves with (K_ff's values, the factorisation's input);
  // empty: it refactorises first.
  std::vector<double> factored_tangent;
  // The system as last evaluated, at `displacement`: energy (J), internal force (N), the
  // tangent's values (K_ff, K_fp), the incompatible modes' amplitudes (9 per such element).
  double energy = 0.0;
  std::vector<double> internal_force;
  std::vector<double> tangent_ff, tangent_fp;
  std::vector<double> mode_amplitudes;
};

// The equilibrium at the end of one load step (Problem::on_load_step).
struct LoadStepReport {
  int step = 0, steps = 0;                // 1-based
  const std::vector<Vec3>& displacement;  // m, per node
  const std::vector<Vec3>& reaction;      // N, per node (see Result)
  int newton_iterations = 0;              // so far
  double residual = 0.0;                  // N, largest free residual component
  const SolveState& state;                // to resume from
};

struct Problem {
  Mesh mesh;  // hexahedra or tetrahedra (linear), positions in m
  Material material;
  // Several materials (one per object of a scene): cell c is of materials[cell_material[c]];
  // when `materials` is empty every cell is of `material`.
  std::vector<Material> materials;
  std::vector<int> cell_material;
  std::vector<Dirichlet> prescribed;
  Vec3 body_force = Vec3::Zero();  // N/m^3 (e.g. density * gravity), scaled with the load
  std::vector<Vec3> nodal_force;   // N per node (dead loads), scaled with the load; empty: none
  int load_steps = 10;
  double tolerance = 1e-10;  // relative: |residual| <= tolerance * |reaction| (or 1e-12 N)
  // N: the largest free residual component must also be at most this (a scene's tolerance).
  double force_tolerance = std::numeric_limits<double>::infinity();
  int max_newton_iterations = 30;  // per load step
  // Called after each converged load step; returning false stops the solve there
  // (Result::stopped, e.g. on an interruption request).
  std::function<bool(const LoadStepReport&)> on_load_step;
  // Go on from this state of an earlier solve of the same problem (load steps done, Newton
  // iterations counted on), with the same results as the uninterrupted solve.
  std::optional<SolveState> resume_from;
};

struct Result {
  bool converged = false;
  std::string message;             // why not, when not converged
  std::vector<Vec3> displacement;  // m, per node
  std::vector<Vec3> reaction;      // N, per node: internal minus external force (non-zero
                                   // only on prescribed components at equilibrium)
  int newton_iterations = 0;       // total over all load steps
  double final_residual = 0.0;     // N, largest free residual component
  int load_steps_done = 0;         // converged load steps
  bool stopped = false;            // on_load_step asked to stop (converged stays false)
};

// Static equilibrium by Newton's method with load steps, a line search and a sparse direct
// solver. Nearly incompressible materials (nu -> 0.5) do not lock (see fem/README in the
// source for the formulation chosen). Throws std::invalid_argument for bad input.
Result solve_static(const Problem& problem);

}  // namespace phymul::fem
