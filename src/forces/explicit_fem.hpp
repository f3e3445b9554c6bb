// Explicit finite elements (TLED): the internal forces of a step, as a force on the nodes
// like the shape memory's (the per-cell data they read: model/explicit_fem_cells.hpp).
#pragma once

#include <span>

#include "phymul/model.hpp"

namespace phymul {

// Adds the internal forces (N) to f; returns the strain energy (J), hourglass included, or
// NaN where a cell is inverted at x (J = det F <= 0 at its centre: the law has no meaning
// there, and its forces, finite, would not say so).
// blocks: the energy of each block of fem.plan (scratch, plan.blocks() long).
double add_explicit_fem_forces(const ExplicitFem& fem, std::span<const Vec3> rest,
                               std::span<const Vec3> x, std::span<Vec3> f,
                               std::span<double> blocks);

// The pass's two kernels for hexahedra (fem.nodes_per_cell == 8), which it takes in turn:
// cell e alone (the reference), and cells e to e + 3 at once, lane by lane (the per-cell
// constants read across the four cells), their forces added cell by cell in order. Each adds
// into f and returns the energy (summed in cell order), NaN where a cell is inverted.
double add_hexahedron_forces(const ExplicitFem& fem, int e, std::span<const Vec3> rest,
                             std::span<const Vec3> x, std::span<Vec3> f);
double add_four_hexahedra_forces(const ExplicitFem& fem, int e, std::span<const Vec3> rest,
                                 std::span<const Vec3> x, std::span<Vec3> f);

// Each cell's rotation: that of its deformation gradient at its centre (the rotation R
// maximising tr(R^T F)), warm started from and written into rotation (one per cell).
void fit_cell_rotations(const ExplicitFem& fem, std::span<const Vec3> rest, std::span<const Vec3> x,
                        std::span<Eigen::Quaterniond> rotation);

// The first cell, in order, that is inverted at x (as above; J not finite too).
struct InvertedCell {
  int cell = -1;  // among fem's cells (a wedge is three); -1: none
  double J = 1.0;
  std::span<const int> nodes;  // its corners, global node ids
};
InvertedCell first_inverted_cell(const ExplicitFem& fem, std::span<const Vec3> rest,
                                 std::span<const Vec3> x);

}  // namespace phymul
