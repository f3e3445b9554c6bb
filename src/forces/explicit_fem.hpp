// Explicit finite elements (TLED): the per-cell data compiled once, then the internal forces
// of a step, as a force on the nodes like the shape memory's.
#pragma once

#include <span>

#include "phymul/model.hpp"

namespace phymul {

// Reference data of every cell of `mesh` (hexahedra, or tetrahedra and wedges cut into
// tetrahedra by wedge_tetrahedra), whose node k is global
// node first_node + k. Throws std::invalid_argument on other cells or bad moduli.
ExplicitFem build_explicit_fem(const std::string& component, const Mesh& mesh, int first_node,
                               const MaterialSpec& material, std::span<const Vec3> rest);

// The cells' parallel plan; again after their node ids change (stitching).
void plan_explicit_fem(ExplicitFem& fem);

// Adds the internal forces (N) to f; returns the strain energy (J), hourglass included, or
// NaN where a cell is inverted at x (J = det F <= 0 at its centre: the law has no meaning
// there, and its forces, finite, would not say so).
double add_explicit_fem_forces(const ExplicitFem& fem, std::span<const Vec3> rest,
                               std::span<const Vec3> x, std::span<Vec3> f);

// The first cell, in order, that is inverted at x (as above; J not finite too).
struct InvertedCell {
  int cell = -1;  // among fem's cells (a wedge is three); -1: none
  double J = 1.0;
  std::span<const int> nodes;  // its corners, global node ids
};
InvertedCell first_inverted_cell(const ExplicitFem& fem, std::span<const Vec3> rest,
                                 std::span<const Vec3> x);

// Gershgorin row sums (N/m) of the cells' stiffness at rest, added into row (per node).
void add_explicit_fem_rows(const ExplicitFem& fem, std::span<double> row);

}  // namespace phymul
