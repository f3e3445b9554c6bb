// Reference finite elements (DESIGN 5): total Lagrangian, large deformation, static Newton.
// The yardstick the shape-memory model is measured against, cross-checked with CalculiX.
#pragma once

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

struct Problem {
  Mesh mesh;  // hexahedra or tetrahedra (linear), positions in m
  Material material;
  std::vector<Dirichlet> prescribed;
  Vec3 body_force = Vec3::Zero();  // N/m^3 (e.g. density * gravity), scaled with the load
  int load_steps = 10;
  double tolerance = 1e-10;        // relative: |residual| <= tolerance * |reaction| (or 1e-12 N)
  int max_newton_iterations = 30;  // per load step
};

struct Result {
  bool converged = false;
  std::string message;             // why not, when not converged
  std::vector<Vec3> displacement;  // m, per node
  std::vector<Vec3> reaction;      // N, per node: internal minus external force (non-zero
                                   // only on prescribed components at equilibrium)
  int newton_iterations = 0;       // total over all load steps
  double final_residual = 0.0;     // N, largest free residual component
};

// Static equilibrium by Newton's method with load steps, a line search and a sparse direct
// solver. Nearly incompressible materials (nu -> 0.5) do not lock (see fem/README in the
// source for the formulation chosen). Throws std::invalid_argument for bad input.
Result solve_static(const Problem& problem);

}  // namespace phymul::fem
