// Supernodal multifrontal sparse Cholesky (L L^T) for the symmetric positive definite
// tangent. Eigen's SimplicialLDLT works one column at a time (about 1.5 GFlop/s here, 2 s per
// factorisation of the 16^3 cube); grouping columns with identical structure into
// supernodes turns the work into dense blocks (Eigen's dense LLT, triangular solve and
// rank-k update), several times faster.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "fem/ordering.hpp"
#include "fem/system.hpp"

namespace phymul::fem {

class SupernodalCholesky {
 public:
  // Ordering and symbolic factorisation of the pattern of `lower` (compressed lower
  // triangle, diagonal present). Every later factorize() must use the same pattern. With the
  // node geometry the order is a nested dissection, otherwise minimum degree.
  void analyze(const SparseMatrix& lower, const NodeGeometry* geometry = nullptr);

  // Numeric factorisation; false when the matrix is not (numerically) positive definite.
  bool factorize(const SparseMatrix& lower);

  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;

  // Smallest over largest pivot (squared diagonal of L) of the last factorisation.
  double pivot_ratio() const { return pivot_max_ > 0.0 ? pivot_min_ / pivot_max_ : 0.0; }

 private:
  struct Supernode {
    int first = 0;                  // first (permuted) column
    int columns = 0;                // pivot columns
    int rows = 0;                   // rows of the front, pivots included
    int row_offset = 0;             // into row_index_
    std::int64_t value_offset = 0;  // into values_ (rows x columns, column-major)
    int children = 0;               // supernodes whose update goes into this one
  };
  struct ScatterEntry {
    int value = 0;   // index into the input's values
    int offset = 0;  // position in the front (column-major, rows x rows)
  };

  void build_supernodes(const std::vector<int>& parent, const std::vector<int>& counts);
  void build_rows(const std::vector<int>& row, const std::vector<int>& col);
  void build_scatter(const std::vector<int>& row, const std::vector<int>& col);
  bool factor_front(const Supernode& s, double* front);
  void extend_add(const Supernode& s, double* front);

  int n_ = 0;
  std::vector<int> order_;  // order_[k]: original index of the k-th eliminated unknown
  std::vector<int> column_supernode_;
  std::vector<Supernode> nodes_;
  std::vector<int> row_index_;
  std::vector<int> scatter_offset_;
  std::vector<ScatterEntry> scatter_;
  std::vector<double> values_;
  int max_front_ = 0;

  // Factorisation workspace.
  std::vector<double> front_;
  std::vector<double> stack_;
  std::vector<int> stack_nodes_;
  std::vector<std::size_t> stack_offsets_;
  std::vector<int> local_;
  double pivot_min_ = 0.0;
  double pivot_max_ = 0.0;
};

}  // namespace phymul::fem
