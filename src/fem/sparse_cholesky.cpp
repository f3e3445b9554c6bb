// Numeric phase of the supernodal Cholesky: multifrontal, in postorder. Each supernode
// assembles its frontal matrix from the matrix values and its children's update matrices
// (popped from a stack), factors its pivot block, and pushes its own update matrix.
#include "fem/sparse_cholesky.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <limits>

namespace phymul::fem {

namespace {

using DenseMap = Eigen::Map<Eigen::MatrixXd>;
using ConstDenseMap = Eigen::Map<const Eigen::MatrixXd>;

}  // namespace

// Adds the update matrices of the children (the top of the stack) into the front.
void SupernodalCholesky::extend_add(const Supernode& s, double* front) {
  const int* rows = row_index_.data() + s.row_offset;
  for (int i = 0; i < s.rows; ++i) local_[rows[i]] = i;
  for (int c = 0; c < s.children; ++c) {
    const Supernode& child = nodes_[stack_nodes_.back()];
    const int size = child.rows - child.columns;
    const int* child_rows = row_index_.data() + child.row_offset + child.columns;
    const double* update = stack_.data() + stack_offsets_.back();
    for (int j = 0; j < size; ++j) {
      double* column = front + std::size_t(s.rows) * local_[child_rows[j]];
      // Both row lists are sorted, so the lower triangle maps into the lower triangle.
      for (int i = j; i < size; ++i) column[local_[child_rows[i]]] += update[i + size * j];
    }
    stack_.resize(stack_offsets_.back());
    stack_offsets_.pop_back();
    stack_nodes_.pop_back();
  }
}

bool SupernodalCholesky::factor_front(const Supernode& s, double* front) {
  const int m = s.rows, k = s.columns;
  DenseMap f(front, m, m);
  Eigen::Ref<Eigen::MatrixXd> pivots(f.topLeftCorner(k, k));
  Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>, Eigen::Lower> llt(pivots);
  if (llt.info() != Eigen::Success) return false;
  for (int i = 0; i < k; ++i) {
    const double pivot = pivots(i, i) * pivots(i, i);
    pivot_min_ = std::min(pivot_min_, pivot);
    pivot_max_ = std::max(pivot_max_, pivot);
  }
  if (m > k) {
    auto below = f.bottomLeftCorner(m - k, k);
    pivots.triangularView<Eigen::Lower>().transpose().solveInPlace<Eigen::OnTheRight>(below);
    f.bottomRightCorner(m - k, m - k).selfadjointView<Eigen::Lower>().rankUpdate(below, -1.0);
  }
  DenseMap(values_.data() + s.value_offset, m, k) = f.leftCols(k);
  return true;
}

bool SupernodalCholesky::factorize(const SparseMatrix& lower) {
  front_.resize(std::size_t(max_front_) * max_front_);
  local_.resize(n_);
  stack_.clear();
  stack_offsets_.clear();
  stack_nodes_.clear();
  pivot_min_ = std::numeric_limits<double>::infinity();
  pivot_max_ = 0.0;
  const double* a = lower.valuePtr();
  for (std::size_t sn = 0; sn < nodes_.size(); ++sn) {
    const Supernode& s = nodes_[sn];
    double* front = front_.data();
    // Only the lower triangles of fronts and updates are ever read.
    for (int j = 0; j < s.rows; ++j)
      std::fill_n(front + std::size_t(s.rows) * j + j, s.rows - j, 0.0);
    for (int e = scatter_offset_[sn]; e < scatter_offset_[sn + 1]; ++e) {
      front[scatter_[e].offset] += a[scatter_[e].value];
    }
    extend_add(s, front);
    if (!factor_front(s, front)) return false;
    const int size = s.rows - s.columns;
    if (size == 0) continue;
    stack_offsets_.push_back(stack_.size());
    stack_nodes_.push_back(int(sn));
    stack_.resize(stack_.size() + std::size_t(size) * size);
    double* update = stack_.data() + stack_offsets_.back();
    for (int j = 0; j < size; ++j) {
      const double* from = front + std::size_t(s.rows) * (s.columns + j) + s.columns;
      std::copy(from + j, from + size, update + std::size_t(size) * j + j);
    }
  }
  return true;
}

Eigen::VectorXd SupernodalCholesky::solve(const Eigen::VectorXd& b) const {
  Eigen::VectorXd y(n_);
  for (int k = 0; k < n_; ++k) y[k] = b[order_[k]];
  Eigen::VectorXd t;
  for (const Supernode& s : nodes_) {  // L y = P b
    const int m = s.rows, k = s.columns;
    ConstDenseMap l(values_.data() + s.value_offset, m, k);
    auto x = y.segment(s.first, k);
    l.topRows(k).triangularView<Eigen::Lower>().solveInPlace(x);
    t.noalias() = l.bottomRows(m - k) * x;
    const int* rows = row_index_.data() + s.row_offset + k;
    for (int i = 0; i < m - k; ++i) y[rows[i]] -= t[i];
  }
  for (auto it = nodes_.rbegin(); it != nodes_.rend(); ++it) {  // L^T z = y
    const Supernode& s = *it;
    const int m = s.rows, k = s.columns;
    ConstDenseMap l(values_.data() + s.value_offset, m, k);
    t.resize(m - k);
    const int* rows = row_index_.data() + s.row_offset + k;
    for (int i = 0; i < m - k; ++i) t[i] = y[rows[i]];
    auto x = y.segment(s.first, k);
    x.noalias() -= l.bottomRows(m - k).transpose() * t;
    l.topRows(k).transpose().triangularView<Eigen::Upper>().solveInPlace(x);
  }
  Eigen::VectorXd out(n_);
  for (int k = 0; k < n_; ++k) out[order_[k]] = y[k];
  return out;
}

}  // namespace phymul::fem
