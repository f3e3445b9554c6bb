// The implicit step's coupled matrix (solver/implicit_step.cpp): over blocks of a node's three
// axes (a doubled group one block),
//   P = M (1/h^2 + c/h) + sum_k K J_k^T J_k (+ the springs' k),
// J_k the derivative of memory node k's pull g + R c - x_i at the rest shape, through the
// centroid g and through the best-fit rotation R (DESIGN 2.1). There the pull is zero, so
// this is the shape memory's exact Hessian at rest, where the per-axis L = sum K A_k^T A_k
// leaves out what the rotation's derivative takes away: the iterations it saves are those
// the rotations' softness cost.
#pragma once

#include <array>
#include <span>
#include <utility>
#include <vector>

#include "model/block_cholesky.hpp"
#include "model/explicit_fem_cells.hpp"
#include "model/implicit_system.hpp"
#include "phymul/model.hpp"

namespace phymul {

// The blocks of the unknowns: per node its block (-1: every axis held), per block each
// axis's unknown (-1: held there, the block's identity row).
// A free rigid body has two blocks, after the nodes': its centre's motion and its turn.
struct ImplicitBlocks {
  std::vector<int> of_node;
  std::vector<std::array<int, 3>> unknown;
  std::vector<std::array<int, 2>> of_body;  // per rigid body: move and turn blocks (-1: driven)
  // Per node of a free body: d(x_node)/d(turn) at rest, -R0 [o]x (o: the node's offset in the
  // body's principal frame, R0 that frame's rest orientation; the turn in the body's frame).
  std::vector<Block3> arm;
};

// An active fibre's segment: its nodes, its unit direction at rest, its stiffness (N/m) and
// its bundle's largest contraction.
struct FibreSegment {
  std::array<int, 2> nodes;
  Vec3 direction;
  double stiffness = 0.0, max_contraction = 0.0;
};

std::vector<FibreSegment> fibre_segments(const Model& model);

// The segment's stiffness in P: half a taut one's (k along it; across it the tension's T / l,
// k c at rest length and full activation). A tension-only segment is slack or taut, and the
// midpoint lets the iterations contract in either state, where a taut one's would stall on
// slack fibres and none would overshoot on taut ones.
Block3 fibre_stiffness(const FibreSegment& f);

// Per node, its doubled group (Model::doubled's row), -1 for a node in none.
std::vector<int> doubled_group_of_node(const Model& model);

// unknown: per axis, each node's unknown (ImplicitSystem::unknown); body: the rigid bodies'
// (ImplicitSystem::body).
ImplicitBlocks number_blocks(const Model& model, const std::array<std::vector<int>, 3>& unknown,
                             const std::vector<ImplicitSystem::Body>& body);

// The pairs of blocks P couples (each memory node's, every pair of the nodes it reads).
std::vector<std::pair<int, int>> coupled_pattern(const Model& model, const ImplicitBlocks& blocks);

// P's lower blocks for step h, held axes' rows and columns the identity's. The explicit
// finite-element cells' stiffness at rest is turned by their cell_rotation (Data's; empty: at
// rest). A free rigid body's
// node moves by dx = move + R (turn x o) (turn a rotation vector in the body's principal
// frame, o the node's offset there, R taken at rest): its terms reach the body's blocks
// through that map, and the body's mass and principal inertia are theirs. In the body's frame
// the inertia's block is exact at any orientation.
// cells: false leaves the finite-element cells out.
std::vector<BlockEntry> coupled_matrix(const Model& model, const ImplicitBlocks& blocks, double h,
                                       std::span<const Eigen::Quaterniond> cell_rotation = {},
                                       bool cells = true);

// Calls visit(fem, e, K) for each explicit finite-element cell, its stiffness at rest turned
// by its cell_rotation (empty: none), K[a * n + b] = K_ab (model/explicit_fem_cells.hpp).
template <class Visit>
void each_cell_stiffness(const Model& model, std::span<const Eigen::Quaterniond> cell_rotation,
                         Visit visit) {
  std::array<Block3, 64> k;
  size_t cell = 0;
  for (const ExplicitFem& fem : model.explicit_fem) {
    const int n = fem.nodes_per_cell;
    for (int e = 0; e < int(fem.volume.size()); ++e, ++cell) {
      const Block3 turn =
          cell_rotation.empty() ? Block3::Identity() : cell_rotation[cell].toRotationMatrix();
      explicit_fem_cell_stiffness(fem, e, turn, std::span(k).first(size_t(n * n)));
      visit(fem, e, std::span<const Block3>(k).first(size_t(n * n)));
    }
  }
}

// A block's rows (of block `row`) and columns (of block `col`) on held axes (unknown < 0) zero.
inline void hold_block_axes(const std::vector<std::array<int, 3>>& unknown, int row, int col,
                            Block3& value) {
  for (int a = 0; a < 3; ++a) {
    if (unknown[size_t(row)][size_t(a)] < 0) value.row(a).setZero();
    if (unknown[size_t(col)][size_t(a)] < 0) value.col(a).setZero();
  }
}

// Whether every node of every finite-element cell has its own block or none (held): none on
// a free rigid body, whose nodes reach P through its blocks.
bool cells_on_their_blocks(const Model& model, const ImplicitBlocks& blocks);

}  // namespace phymul
