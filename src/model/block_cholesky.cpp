#include "model/block_cholesky.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCore>
#include <algorithm>
#include <stdexcept>
#include <utility>

namespace phymul {
namespace {

// Lower entries by (col, row), duplicates summed.
std::vector<BlockEntry> merged(std::vector<BlockEntry> entries) {
  std::sort(entries.begin(), entries.end(), [](const BlockEntry& a, const BlockEntry& b) {
    return a.col != b.col ? a.col < b.col : a.row < b.row;
  });
  std::vector<BlockEntry> out;
  for (const BlockEntry& e : entries)
    if (!out.empty() && out.back().row == e.row && out.back().col == e.col)
      out.back().value += e.value;
    else
      out.push_back(e);
  return out;
}

// Per block: its place in an approximate minimum degree order of the blocks' graph.
std::vector<int> minimum_degree_order(int blocks, const std::vector<std::pair<int, int>>& pairs) {
  std::vector<Eigen::Triplet<double>> pattern;
  for (int b = 0; b < blocks; ++b) pattern.emplace_back(b, b, 1.0);
  for (const auto& [p, q] : pairs) {
    pattern.emplace_back(p, q, 1.0);
    pattern.emplace_back(q, p, 1.0);
  }
  Eigen::SparseMatrix<double> graph(blocks, blocks);
  graph.setFromTriplets(pattern.begin(), pattern.end());
  return minimum_degree_positions(graph);
}

// The entries in the factor's order, lower triangle, by (col, row).
std::vector<BlockEntry> permuted(std::vector<BlockEntry> entries, const std::vector<int>& to) {
  for (BlockEntry& e : entries) {
    e.row = to[size_t(e.row)];
    e.col = to[size_t(e.col)];
    if (e.row < e.col) {
      std::swap(e.row, e.col);
      e.value.transposeInPlace();
    }
  }
  return merged(std::move(entries));
}

// The rows of L below the diagonal, column by column (f.start, f.row): column j's are A's
// below j (a_row[a_start[j]...]) and those of its children in the elimination tree, but j.
// Stops past `most`.
void analyse(const std::vector<int>& a_row, const std::vector<int>& a_start, size_t most,
             BlockFactor& f) {
  const int n = f.blocks;
  std::vector<std::vector<int>> children(static_cast<size_t>(n));
  std::vector<int> mark(size_t(n), -1), rows;
  f.start.assign(size_t(n) + 1, 0);
  f.row.clear();
  for (int j = 0; j < n; ++j) {
    rows.clear();
    auto add = [&](int i) {
      if (i > j && mark[size_t(i)] != j) {
        mark[size_t(i)] = j;
        rows.push_back(i);
      }
    };
    for (int e = a_start[size_t(j)]; e < a_start[size_t(j) + 1]; ++e) add(a_row[size_t(e)]);
    for (int c : children[size_t(j)])
      for (int e = f.start[size_t(c)]; e < f.start[size_t(c) + 1]; ++e) add(f.row[size_t(e)]);
    std::sort(rows.begin(), rows.end());
    if (!rows.empty()) children[size_t(rows.front())].push_back(j);
    f.row.insert(f.row.end(), rows.begin(), rows.end());
    f.start[size_t(j) + 1] = int(f.row.size());
    if (f.row.size() > most) return;
  }
}

// Per row i, the columns k < i with a block of L at (i, k), ascending (compressed rows).
void row_lists(const BlockFactor& f, std::vector<int>& start, std::vector<int>& column) {
  start.assign(size_t(f.blocks) + 1, 0);
  for (int i : f.row) ++start[size_t(i) + 1];
  for (int i = 0; i < f.blocks; ++i) start[size_t(i) + 1] += start[size_t(i)];
  std::vector<int> fill(start.begin(), start.end() - 1);
  column.resize(f.row.size());
  for (int k = 0; k < f.blocks; ++k)
    for (int e = f.start[size_t(k)]; e < f.start[size_t(k) + 1]; ++e)
      column[size_t(fill[size_t(f.row[size_t(e)])]++)] = k;
}

PaddedBlock padded(const Block3& b) {
  PaddedBlock p = PaddedBlock::Zero();
  p.topRows<3>() = b;
  return p;
}

// Subtracts from the sums of column j's rows the updates of column k, whose blocks from
// `first` on lie at or below row j (the first at row j: L_jk).
void update_from(const BlockFactor& f, int first, int end, std::vector<PaddedBlock>& sum) {
  const Block3 ljk_transpose = f.value[size_t(first)].topRows<3>().transpose();
  const PaddedBlock* __restrict value = f.value.data();
  const int* __restrict row = f.row.data();
  for (int e = first; e < end; ++e) sum[size_t(row[e])].noalias() -= value[e] * ljk_transpose;
}

// Left-looking: column j of L from A's and the updates of the columns k < j that reach row j.
void factorise_numeric(const std::vector<BlockEntry>& a, const std::vector<int>& a_start,
                       BlockFactor& f) {
  const int n = f.blocks;
  if (f.row_start.empty()) row_lists(f, f.row_start, f.row_column);
  f.next.assign(f.start.begin(), f.start.end() - 1);  // per column: its first row >= j
  f.sum.assign(size_t(n), PaddedBlock::Zero());
  std::vector<PaddedBlock>& sum = f.sum;
  f.value.assign(f.row.size(), PaddedBlock::Zero());
  f.inverse_diagonal.assign(size_t(n), PaddedBlock::Zero());
  f.inverse_transpose.assign(size_t(n), PaddedBlock::Zero());
  for (int j = 0; j < n; ++j) {
    sum[size_t(j)].setZero();
    for (int e = f.start[size_t(j)]; e < f.start[size_t(j) + 1]; ++e)
      sum[size_t(f.row[size_t(e)])].setZero();
    for (int e = a_start[size_t(j)]; e < a_start[size_t(j) + 1]; ++e)
      sum[size_t(a[size_t(e)].row)].topRows<3>() += a[size_t(e)].value;
    for (int r = f.row_start[size_t(j)]; r < f.row_start[size_t(j) + 1]; ++r) {
      const int k = f.row_column[size_t(r)];
      update_from(f, f.next[size_t(k)]++, f.start[size_t(k) + 1], sum);
    }
    const Eigen::LLT<Block3> diagonal(sum[size_t(j)].topRows<3>());
    if (diagonal.info() != Eigen::Success)
      throw std::runtime_error("the implicit step's matrix is not positive definite");
    const Block3 inverse = Block3(diagonal.matrixL()).inverse();
    f.inverse_diagonal[size_t(j)] = padded(inverse);
    f.inverse_transpose[size_t(j)] = padded(inverse.transpose());
    for (int e = f.start[size_t(j)]; e < f.start[size_t(j) + 1]; ++e)
      f.value[size_t(e)].noalias() = sum[size_t(f.row[size_t(e)])] * inverse.transpose();
  }
}

}  // namespace

std::vector<int> minimum_degree_positions(const Eigen::SparseMatrix<double>& symmetric) {
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> inverse;
  Eigen::AMDOrdering<int>()(symmetric, inverse);
  const Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> order = inverse.inverse();
  return {order.indices().data(), order.indices().data() + order.size()};
}

BlockFactor analyse_blocks(int blocks, const std::vector<std::pair<int, int>>& pairs, size_t most) {
  BlockFactor f;
  f.blocks = blocks;
  f.position = minimum_degree_order(blocks, pairs);
  std::vector<std::pair<int, int>> lower;  // (col, row) in the factor's order, row > col
  for (const auto& [p, q] : pairs) {
    const int r = f.position[size_t(p)], c = f.position[size_t(q)];
    if (r != c) lower.emplace_back(std::min(r, c), std::max(r, c));
  }
  std::sort(lower.begin(), lower.end());
  lower.erase(std::unique(lower.begin(), lower.end()), lower.end());
  std::vector<int> a_start(size_t(blocks) + 1, 0), a_row;
  for (const auto& [c, r] : lower) {
    ++a_start[size_t(c) + 1];
    a_row.push_back(r);
  }
  for (int j = 0; j < blocks; ++j) a_start[size_t(j) + 1] += a_start[size_t(j)];
  analyse(a_row, a_start, most, f);
  f.rhs.assign(size_t(blocks), Eigen::Vector4d::Zero());
  return f;
}

BlockAssembly assemble_blocks(const BlockFactor& f, std::vector<BlockEntry> entries) {
  BlockAssembly a;
  a.entry = permuted(std::move(entries), f.position);
  a.start.assign(size_t(f.blocks) + 1, 0);
  for (const BlockEntry& e : a.entry) ++a.start[size_t(e.col) + 1];
  for (int j = 0; j < f.blocks; ++j) a.start[size_t(j) + 1] += a.start[size_t(j)];
  return a;
}

BlockSlot block_slot(const BlockFactor& f, const BlockAssembly& a, int p, int q) {
  int r = f.position[size_t(p)], c = f.position[size_t(q)];
  const bool transposed = r < c;
  if (transposed) std::swap(r, c);
  const auto first = a.entry.begin() + a.start[size_t(c)],
             last = a.entry.begin() + a.start[size_t(c) + 1];
  const auto at =
      std::lower_bound(first, last, r, [](const BlockEntry& e, int row) { return e.row < row; });
  if (at == last || at->row != r) return {};
  return {int(at - a.entry.begin()), transposed};
}

void factorise_assembled(BlockFactor& f, const BlockAssembly& a) {
  factorise_numeric(a.entry, a.start, f);
}

void factorise_blocks(BlockFactor& f, std::vector<BlockEntry> entries) {
  factorise_assembled(f, assemble_blocks(f, std::move(entries)));
}

namespace {

// b v over four rows (the fourth 0): three broadcasts of v's entries times b's columns.
inline Eigen::Vector4d times(const PaddedBlock& b, const Eigen::Vector4d& v) {
  return b.col(0) * v[0] + b.col(1) * v[1] + b.col(2) * v[2];
}

// L y = x: column by column, each block's column a four-wide multiply-add into its row.
void forward(const BlockFactor& f, Eigen::Vector4d* __restrict y) {
  const int* __restrict start = f.start.data();
  const int* __restrict row = f.row.data();
  const PaddedBlock* __restrict value = f.value.data();
  for (int j = 0; j < f.blocks; ++j) {
    y[j] = times(f.inverse_diagonal[size_t(j)], y[j]);
    const double y0 = y[j][0], y1 = y[j][1], y2 = y[j][2];
    for (int e = start[j]; e < start[j + 1]; ++e)
      y[row[e]] -= value[e].col(0) * y0 + value[e].col(1) * y1 + value[e].col(2) * y2;
  }
}

// sum += b's columns times v, lane by lane.
void add_products(const PaddedBlock& b, const Eigen::Vector4d& v, PaddedBlock& sum) {
  for (int c = 0; c < 3; ++c) sum.col(c) += b.col(c).cwiseProduct(v);
}

// L^T x = y: per column, the products of its blocks' columns with their rows summed lane by
// lane in two interleaved sets (two chains of additions instead of one), then across.
void backward(const BlockFactor& f, Eigen::Vector4d* __restrict y) {
  const int* __restrict start = f.start.data();
  const int* __restrict row = f.row.data();
  const PaddedBlock* __restrict value = f.value.data();
  for (int j = f.blocks - 1; j >= 0; --j) {
    PaddedBlock even = PaddedBlock::Zero(), odd = PaddedBlock::Zero();
    int e = start[j];
    for (; e + 1 < start[j + 1]; e += 2) {
      add_products(value[e], y[row[e]], even);
      add_products(value[e + 1], y[row[e + 1]], odd);
    }
    if (e < start[j + 1]) add_products(value[e], y[row[e]], even);
    Eigen::Vector4d rest = y[j];
    rest.head<3>() -= (even + odd).colwise().sum().transpose();
    y[j] = times(f.inverse_transpose[size_t(j)], rest);
  }
}

}  // namespace

void solve_blocks(const BlockFactor& f, double* x) {
  Eigen::Vector4d* y = f.rhs.data();
  for (int j = 0; j < f.blocks; ++j) y[j] << x[3 * j], x[3 * j + 1], x[3 * j + 2], 0.0;
  forward(f, y);
  backward(f, y);
  for (int j = 0; j < f.blocks; ++j)
    for (int a = 0; a < 3; ++a) x[3 * j + a] = y[j][a];
}

}  // namespace phymul
