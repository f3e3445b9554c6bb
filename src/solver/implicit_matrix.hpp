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
#include <utility>
#include <vector>

#include "model/block_cholesky.hpp"
#include "phymul/model.hpp"

namespace phymul {

// The blocks of the unknowns: per node its block (-1: every axis held), per block each
// axis's unknown (-1: held there, the block's identity row).
struct ImplicitBlocks {
  std::vector<int> of_node;
  std::vector<std::array<int, 3>> unknown;
};

// Per node, its doubled group (Model::doubled's row), -1 for a node in none.
std::vector<int> doubled_group_of_node(const Model& model);

// unknown: per axis, each node's unknown (ImplicitSystem::unknown).
ImplicitBlocks number_blocks(const Model& model, const std::array<std::vector<int>, 3>& unknown);

// The pairs of blocks P couples (each memory node's, every pair of the nodes it reads).
std::vector<std::pair<int, int>> coupled_pattern(const Model& model, const ImplicitBlocks& blocks);

// P's lower blocks for step h, held axes' rows and columns the identity's.
std::vector<BlockEntry> coupled_matrix(const Model& model, const ImplicitBlocks& blocks, double h);

}  // namespace phymul
