// The per-cell data of explicit finite elements (TLED), compiled once: reference gradients,
// volumes, hourglass vectors and the parallel plan (the pass: forces/explicit_fem.hpp).
#pragma once

#include <span>
#include <string>

#include "phymul/model.hpp"

namespace phymul {

// Reference data of every cell of `mesh` (hexahedra, or tetrahedra and wedges cut into
// tetrahedra by wedge_tetrahedra), whose node k is global node first_node + k. Throws
// std::invalid_argument on other cells or bad moduli.
ExplicitFem build_explicit_fem(const std::string& component, const Mesh& mesh, int first_node,
                               const MaterialSpec& material, std::span<const Vec3> rest);

// The cells' parallel plan; again after their node ids change (stitching).
void plan_explicit_fem(ExplicitFem& fem);

// Cell e's stiffness at rest, the exact Hessian there of its energy (one-point rule and
// hourglass), turned by `turn` (R K_ab R^T: the cell's stiffness where it has rotated by R):
// out[a * n + b] = K_ab, f_a = -sum_b K_ab u_b, n = fem.nodes_per_cell. With F = I + grad u,
// P linearises to mu (grad u + grad u^T) + (kappa - 2 mu / 3) tr(grad u) I.
void explicit_fem_cell_stiffness(const ExplicitFem& fem, int e, const Eigen::Matrix3d& turn,
                                 std::span<Eigen::Matrix3d> out);

// Gershgorin row sums (N/m) of the cells' stiffness at rest, added into row (per node).
void add_explicit_fem_rows(const ExplicitFem& fem, std::span<double> row);

}  // namespace phymul
