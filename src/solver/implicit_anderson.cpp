#include "solver/implicit_anderson.hpp"

#include <Eigen/Dense>
#include <algorithm>

namespace phymul {
namespace {

// Iterates kept besides the newest: the least-squares problem's columns.
constexpr int kDepth = 5;
// Relative floor on the normal equations' diagonal (a history nearly dependent on itself).
constexpr double kRegular = 1e-12;

using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kDepth, kDepth>;
using SmallVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kDepth, 1>;

int slot(const ImplicitSystem::Anderson& a, int age) {  // age 0: the newest
  const int ring = a.depth + 1;
  return ((a.newest - age) % ring + ring) % ring;
}

// f at slot k, node i: g - x.
Eigen::Vector3d residual(const ImplicitSystem::Anderson& a, int k, size_t n, size_t i) {
  return a.g[size_t(k) * n + i] - a.x[size_t(k) * n + i];
}

}  // namespace

void prepare_anderson(const Model& model, ImplicitSystem& s) {
  ImplicitSystem::Anderson& a = s.anderson;
  const bool applies = model.contact_pairs.empty() && model.rigid_bodies.empty();
  a.depth = applies ? kDepth : 0;
  const size_t size = applies ? size_t(kDepth + 1) * size_t(model.node_count()) : 0;
  a.x.assign(size, Eigen::Vector3d::Zero());
  a.g.assign(size, Eigen::Vector3d::Zero());
  a.before.assign(applies ? size_t(model.node_count()) : 0, Eigen::Vector3d::Zero());
  restart_anderson(s);
}

void restart_anderson(ImplicitSystem& s) {
  s.anderson.count = 0;
  s.anderson.newest = -1;
}

bool anderson_mix(ImplicitSystem& s, std::span<const Eigen::Vector3d> before,
                  std::span<Eigen::Vector3d> x) {
  ImplicitSystem::Anderson& a = s.anderson;
  if (a.depth == 0) return false;
  const size_t n = x.size();
  a.newest = (a.newest + 1) % (a.depth + 1);
  a.count = std::min(a.count + 1, a.depth + 1);
  std::copy(before.begin(), before.end(), a.x.begin() + ptrdiff_t(size_t(a.newest) * n));
  std::copy(x.begin(), x.end(), a.g.begin() + ptrdiff_t(size_t(a.newest) * n));
  const int m = a.count - 1;  // columns: differences of consecutive iterates
  if (m == 0) return false;
  // Column j: f at age j minus f at age j + 1; normal equations of the least squares.
  Small normal = Small::Zero(m, m);
  SmallVector rhs = SmallVector::Zero(m);
  for (size_t i = 0; i < n; ++i) {
    Eigen::Vector3d f[kDepth + 1], df[kDepth];  // by age
    for (int j = 0; j <= m; ++j) f[j] = residual(a, slot(a, j), n, i);
    for (int j = 0; j < m; ++j) df[j] = f[j] - f[j + 1];
    for (int j = 0; j < m; ++j) {
      rhs[j] += df[j].dot(f[0]);
      for (int l = 0; l <= j; ++l) normal(j, l) += df[j].dot(df[l]);
    }
  }
  double largest = 0.0;
  for (int j = 0; j < m; ++j) largest = std::max(largest, normal(j, j));
  if (largest == 0.0) return false;
  for (int j = 0; j < m; ++j) {
    normal(j, j) += kRegular * largest;
    for (int l = 0; l < j; ++l) normal(l, j) = normal(j, l);
  }
  const SmallVector gamma = normal.ldlt().solve(rhs);
  for (size_t i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j)
      x[i] -= gamma[j] * (a.g[size_t(slot(a, j)) * n + i] - a.g[size_t(slot(a, j + 1)) * n + i]);
  return true;
}

}  // namespace phymul
