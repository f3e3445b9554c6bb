// Symbolic phase of the supernodal Cholesky: fill-reducing order, elimination tree,
// postorder, column counts, supernodes, their row structures and the map that scatters the
// matrix values into the frontal matrices.
#include <Eigen/OrderingMethods>
#include <algorithm>
#include <stdexcept>

#include "fem/sparse_cholesky.hpp"

namespace phymul::fem {

namespace {

// Entries of the lower triangle under the order (row >= col, permuted), per value index.
struct PermutedEntries {
  std::vector<int> row;
  std::vector<int> col;
};

PermutedEntries permuted_entries(const SparseMatrix& lower, const std::vector<int>& order) {
  std::vector<int> inverse(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) inverse[order[k]] = int(k);
  PermutedEntries out;
  out.row.resize(lower.nonZeros());
  out.col.resize(lower.nonZeros());
  for (int j = 0; j < lower.outerSize(); ++j) {
    for (int v = lower.outerIndexPtr()[j]; v < lower.outerIndexPtr()[j + 1]; ++v) {
      const int a = inverse[lower.innerIndexPtr()[v]];
      const int b = inverse[j];
      out.row[v] = std::max(a, b);
      out.col[v] = std::min(a, b);
    }
  }
  return out;
}

// Strictly lower entries grouped by row: the columns of row k are idx[ptr[k] .. ptr[k+1]).
struct Rows {
  std::vector<int> ptr;
  std::vector<int> idx;
};

Rows rows_of(int n, const PermutedEntries& e) {
  Rows rows{std::vector<int>(n + 1, 0), {}};
  for (std::size_t v = 0; v < e.row.size(); ++v) {
    if (e.row[v] != e.col[v]) ++rows.ptr[e.row[v] + 1];
  }
  for (int k = 0; k < n; ++k) rows.ptr[k + 1] += rows.ptr[k];
  rows.idx.resize(rows.ptr[n]);
  std::vector<int> next(rows.ptr.begin(), rows.ptr.end() - 1);
  for (std::size_t v = 0; v < e.row.size(); ++v) {
    if (e.row[v] != e.col[v]) rows.idx[next[e.row[v]]++] = e.col[v];
  }
  return rows;
}

// Liu's algorithm with path compression.
std::vector<int> elimination_tree(int n, const Rows& rows) {
  std::vector<int> parent(n, -1), ancestor(n, -1);
  for (int k = 0; k < n; ++k) {
    for (int p = rows.ptr[k]; p < rows.ptr[k + 1]; ++p) {
      for (int i = rows.idx[p]; i != -1 && i < k;) {
        const int next = ancestor[i];
        ancestor[i] = k;
        if (next == -1) parent[i] = k;
        i = next;
      }
    }
  }
  return parent;
}

// post[k]: the node visited k-th by a depth-first postorder (children in increasing order).
std::vector<int> postorder(const std::vector<int>& parent) {
  const int n = int(parent.size());
  std::vector<int> head(n, -1), next(n, -1), post, stack;
  post.reserve(n);
  for (int j = n - 1; j >= 0; --j) {
    if (parent[j] == -1) continue;
    next[j] = head[parent[j]];
    head[parent[j]] = j;
  }
  for (int root = 0; root < n; ++root) {
    if (parent[root] != -1) continue;
    stack.push_back(root);
    while (!stack.empty()) {
      const int p = stack.back();
      const int child = head[p];
      if (child == -1) {
        stack.pop_back();
        post.push_back(p);
      } else {
        head[p] = next[child];
        stack.push_back(child);
      }
    }
  }
  return post;
}

// Entries per column of L (diagonal included), by walking each row subtree once.
std::vector<int> column_counts(int n, const Rows& rows, const std::vector<int>& parent) {
  std::vector<int> counts(n, 1), mark(n, -1);
  for (int k = 0; k < n; ++k) {
    mark[k] = k;
    for (int p = rows.ptr[k]; p < rows.ptr[k + 1]; ++p) {
      for (int j = rows.idx[p]; mark[j] != k; j = parent[j]) {
        mark[j] = k;
        ++counts[j];
      }
    }
  }
  return counts;
}

}  // namespace

void SupernodalCholesky::analyze(const SparseMatrix& lower, const NodeGeometry* geometry) {
  n_ = int(lower.cols());
  if (geometry != nullptr) {
    order_ = nested_dissection(lower, *geometry);
  } else {
    Eigen::AMDOrdering<int> amd;
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> amd_order;
    amd(lower, amd_order);
    order_.assign(amd_order.indices().data(), amd_order.indices().data() + n_);
  }

  // Postordering keeps every subtree, hence every supernode, contiguous, and makes the
  // multifrontal update matrices a stack.
  PermutedEntries entries = permuted_entries(lower, order_);
  const std::vector<int> post = postorder(elimination_tree(n_, rows_of(n_, entries)));
  std::vector<int> reordered(n_);
  for (int k = 0; k < n_; ++k) reordered[k] = order_[post[k]];
  order_ = std::move(reordered);

  entries = permuted_entries(lower, order_);
  const Rows rows = rows_of(n_, entries);
  const std::vector<int> parent = elimination_tree(n_, rows);
  build_supernodes(parent, column_counts(n_, rows, parent));
  build_rows(entries.row, entries.col);
  build_scatter(entries.row, entries.col);
}

// Fundamental supernodes: column j joins j - 1 when j is its parent, has no other child and
// the structure of L(:, j - 1) is that of L(:, j) plus the diagonal.
void SupernodalCholesky::build_supernodes(const std::vector<int>& parent,
                                          const std::vector<int>& counts) {
  std::vector<int> children(n_, 0);
  for (int j = 0; j < n_; ++j) {
    if (parent[j] != -1) ++children[parent[j]];
  }
  nodes_.clear();
  column_supernode_.assign(n_, -1);
  for (int j = 0; j < n_; ++j) {
    const bool joins =
        j > 0 && parent[j - 1] == j && children[j] == 1 && counts[j - 1] == counts[j] + 1;
    if (!joins) nodes_.push_back({j, 0, counts[j], 0, 0, 0});
    ++nodes_.back().columns;
    column_supernode_[j] = int(nodes_.size()) - 1;
  }
  std::int64_t values = 0;
  max_front_ = 0;
  for (Supernode& s : nodes_) {
    s.value_offset = values;
    values += std::int64_t(s.rows) * s.columns;
    max_front_ = std::max(max_front_, s.rows);
    const int up = parent[s.first + s.columns - 1];
    if (up != -1) ++nodes_[column_supernode_[up]].children;
  }
  values_.assign(values, 0.0);
}

// Rows of each front: its pivots, then the rows below them from the matrix and from the
// children's fronts, sorted.
void SupernodalCholesky::build_rows(const std::vector<int>& row, const std::vector<int>& col) {
  const int count = int(nodes_.size());
  std::vector<std::vector<int>> below_from_matrix(count);
  for (std::size_t v = 0; v < row.size(); ++v) {
    const Supernode& s = nodes_[column_supernode_[col[v]]];
    if (row[v] >= s.first + s.columns)
      below_from_matrix[column_supernode_[col[v]]].push_back(row[v]);
  }
  std::vector<std::vector<int>> child_lists(count);
  std::vector<int> mark(n_, -1);
  row_index_.clear();
  for (int s = 0; s < count; ++s) {
    Supernode& node = nodes_[s];
    const int last = node.first + node.columns - 1;
    std::vector<int> below;
    const auto add = [&](int r) {
      if (r > last && mark[r] != s) {
        mark[r] = s;
        below.push_back(r);
      }
    };
    for (int r : below_from_matrix[s]) add(r);
    for (int c : child_lists[s]) {
      const Supernode& child = nodes_[c];
      for (int i = child.columns; i < child.rows; ++i) add(row_index_[child.row_offset + i]);
    }
    std::sort(below.begin(), below.end());
    if (int(below.size()) + node.columns != node.rows) {
      throw std::logic_error("SupernodalCholesky: inconsistent symbolic factorisation");
    }
    node.row_offset = int(row_index_.size());
    for (int c = 0; c < node.columns; ++c) row_index_.push_back(node.first + c);
    row_index_.insert(row_index_.end(), below.begin(), below.end());
    if (!below.empty()) child_lists[column_supernode_[below.front()]].push_back(s);
  }
}

void SupernodalCholesky::build_scatter(const std::vector<int>& row, const std::vector<int>& col) {
  scatter_offset_.assign(nodes_.size() + 1, 0);
  for (int c : col) ++scatter_offset_[column_supernode_[c] + 1];
  for (std::size_t s = 0; s < nodes_.size(); ++s) scatter_offset_[s + 1] += scatter_offset_[s];
  scatter_.resize(row.size());
  std::vector<int> next(scatter_offset_.begin(), scatter_offset_.end() - 1);
  for (std::size_t v = 0; v < row.size(); ++v) {
    const int sn = column_supernode_[col[v]];
    const Supernode& s = nodes_[sn];
    const int* rows = row_index_.data() + s.row_offset;
    const int local_row = int(std::lower_bound(rows, rows + s.rows, row[v]) - rows);
    scatter_[next[sn]++] = {int(v), local_row + s.rows * (col[v] - s.first)};
  }
}

}  // namespace phymul::fem
