// A sparse symmetric positive definite matrix of 3x3 blocks (a node's three axes each),
// factorised L L^T block by block in a fill-reducing order (approximate minimum degree on the
// blocks' graph): the implicit step's coupled matrix (solver/implicit_step.cpp). Each block
// product is a 3x3 one, where a scalar factor of the same matrix would index every entry. L's
// blocks are kept over four rows, the fourth zero, so that each of their columns is one
// four-wide vector to load and multiply where a 3x3 block's take scalar loads: on the prostate
// scenes (40 800 blocks) a solve takes 0.075 ms instead of 0.108 and the factorisation 5.0 ms
// instead of 8.0.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <utility>
#include <vector>

namespace phymul {

using Block3 = Eigen::Matrix3d;
// A 3x3 block over four rows, the fourth zero.
using PaddedBlock = Eigen::Matrix<double, 4, 3>;

// The matrix's lower triangle and diagonal, by block: (row, col, value) with row >= col.
struct BlockEntry {
  int row = 0, col = 0;
  Block3 value = Block3::Zero();
};

struct BlockFactor {
  int blocks = 0;
  std::vector<int> position;  // per block: its place in the factor's order
  // Column j of L in the factor's order: the inverse of its diagonal block (lower
  // triangular) and that inverse's transpose, then its blocks below the diagonal at rows
  // row[e], e in [start[j], start[j + 1]).
  std::vector<PaddedBlock> inverse_diagonal, inverse_transpose;
  std::vector<int> start, row;
  std::vector<PaddedBlock> value;
  // The numeric factorisation's scratch: per row its columns (compressed rows), per column
  // its next row, the running sums; kept so that factorising again allocates nothing.
  std::vector<int> row_start, row_column, next;
  std::vector<PaddedBlock> sum;
  // solve_blocks' right-hand side, a block a four-wide vector: one solve at a time per
  // factor (each implicit workspace has its own factor).
  mutable std::vector<Eigen::Vector4d> rhs;
};

// Per row of a symmetric sparse matrix (both halves given), its place in Eigen's approximate
// minimum degree order: the fill-reducing order of the implicit step's factors.
std::vector<int> minimum_degree_positions(const Eigen::SparseMatrix<double>& symmetric);

// The order and L's structure for a matrix of `blocks` blocks coupled by `pairs` (either
// way round); stops once L holds more than `most` blocks below the diagonal (then its
// f.row.size() > most, and it cannot be factorised).
BlockFactor analyse_blocks(int blocks, const std::vector<std::pair<int, int>>& pairs, size_t most);

// L's values for the analysed structure from the matrix's lower entries (duplicates summed;
// each within the analysed pairs or on the diagonal). Throws std::runtime_error when the
// matrix is not positive definite.
void factorise_blocks(BlockFactor& f, std::vector<BlockEntry> entries);

// A matrix's lower entries in a factor's order, merged: by (col, row), duplicates summed;
// column j's at [start[j], start[j + 1]).
struct BlockAssembly {
  std::vector<BlockEntry> entry;
  std::vector<int> start;
};

// The lower entries (as factorise_blocks takes them) in f's order.
BlockAssembly assemble_blocks(const BlockFactor& f, std::vector<BlockEntry> entries);

// Where the matrix's block (p, q) (blocks before the order) sums in a: its index, and whether
// it is stored transposed (the order put q's row below p's); -1 where a has no such block.
struct BlockSlot {
  int index = -1;
  bool transposed = false;
};
BlockSlot block_slot(const BlockFactor& f, const BlockAssembly& a, int p, int q);

// L's values from an assembly in f's order; allocates nothing once f has been factorised.
void factorise_assembled(BlockFactor& f, const BlockAssembly& a);

// x = A^-1 x in place, x three values a block in the factor's order (block j's at x + 3 j).
// Allocates nothing; uses f.rhs.
void solve_blocks(const BlockFactor& f, double* x);

}  // namespace phymul
