#include "solver/implicit_anderson.hpp"

#include <Eigen/Dense>
#include <algorithm>

#include "solver/implicit_friction.hpp"

namespace phymul {
namespace {

constexpr int kDepth = kAndersonDepth;
// Relative floor on the normal equations' diagonal (a history nearly dependent on itself).
constexpr double kRegular = 1e-12;

using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kDepth, kDepth>;
using SmallVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kDepth, 1>;
using Flat = Eigen::Map<const Eigen::VectorXd>;

int slot(const AndersonHistory& a, int age) {  // age 0: the newest column
  return ((a.newest - age) % kDepth + kDepth) % kDepth;
}

// Column k of a history array, the nodes' three values each in a row.
Flat column(const std::vector<Eigen::Vector3d>& c, int k, size_t n) {
  return Flat(c[size_t(k) * n].data(), Eigen::Index(3 * n));
}

// The difference of this iteration's residual f and image g from the last one's as the
// history's newest column, and its dot products with the others.
void push_column(AndersonHistory& a, const std::vector<Eigen::Vector3d>& f,
                 const std::vector<Eigen::Vector3d>& g, std::span<const Eigen::Vector3d> before,
                 std::span<const Eigen::Vector3d> x) {
  const size_t n = x.size();
  a.newest = (a.newest + 1) % kDepth;
  a.count = std::min(a.count + 1, kDepth);
  Eigen::Vector3d* df = a.df.data() + size_t(a.newest) * n;
  Eigen::Vector3d* dg = a.dg.data() + size_t(a.newest) * n;
  for (size_t i = 0; i < n; ++i) {
    df[i] = (x[i] - before[i]) - f[i];
    dg[i] = x[i] - g[i];
  }
  const Flat fresh = column(a.df, a.newest, n);
  for (int age = 0; age < a.count; ++age) {
    const int k = slot(a, age);
    a.gram[size_t(a.newest * kDepth + k)] = a.gram[size_t(k * kDepth + a.newest)] =
        fresh.dot(column(a.df, k, n));
  }
}

}  // namespace

void prepare_anderson(const Model& model, ImplicitSystem& s, AndersonHistory& history, double h) {
  ImplicitSystem::Anderson& a = s.anderson;
  const size_t n = size_t(model.node_count());
  const bool applies = history.df.size() == size_t(kDepth) * n && n > 0;
  a.before.assign(applies ? n : 0, Eigen::Vector3d::Zero());
  a.f.assign(applies ? n : 0, Eigen::Vector3d::Zero());
  a.g.assign(applies ? n : 0, Eigen::Vector3d::Zero());
  // Friction's and needles' stick and slip change the map between steps in ways the history
  // would carry over: the block on a moving rough floor stalled at 1e-7 N with it.
  a.carry = applies && !with_friction(model) && model.needles.empty();
  a.has_last = false;
  if (history.h != h) {  // taken for another step (or none): void
    restart_anderson(s, history);
    history.h = h;
    history.alpha = 1.0;
    history.held = -1;
  }
}

void restart_anderson(ImplicitSystem& s, AndersonHistory& history) {
  history.count = 0;
  history.newest = -1;
  s.anderson.has_last = false;
}

void begin_anderson_step(ImplicitSystem& s, AndersonHistory& history) {
  // Each step starts at alpha = 1: a history taken at a shorter share is another map's.
  if (s.anderson.carry && history.alpha == 1.0)
    s.anderson.has_last = false;
  else
    restart_anderson(s, history);
  history.alpha = 1.0;
}

bool anderson_mix(ImplicitSystem& s, AndersonHistory& history,
                  std::span<const Eigen::Vector3d> before, std::span<Eigen::Vector3d> x) {
  ImplicitSystem::Anderson& a = s.anderson;
  if (a.before.empty()) return false;
  const size_t n = x.size();
  if (a.has_last) push_column(history, a.f, a.g, before, x);
  for (size_t i = 0; i < n; ++i) a.f[i] = x[i] - before[i], a.g[i] = x[i];
  a.has_last = true;
  const int m = history.count;
  if (m == 0) return false;
  // gamma minimising |f - sum gamma_j df_j|, by its normal equations.
  const Flat f(a.f[0].data(), Eigen::Index(3 * n));
  Small normal(m, m);
  SmallVector rhs(m);
  double largest = 0.0;
  for (int j = 0; j < m; ++j) {
    rhs[j] = column(history.df, slot(history, j), n).dot(f);
    for (int l = 0; l < m; ++l)
      normal(j, l) = history.gram[size_t(slot(history, j) * kDepth + slot(history, l))];
    largest = std::max(largest, normal(j, j));
  }
  if (largest == 0.0) return false;
  for (int j = 0; j < m; ++j) normal(j, j) += kRegular * largest;
  const SmallVector gamma = normal.ldlt().solve(rhs);
  Eigen::Map<Eigen::VectorXd> out(x[0].data(), Eigen::Index(3 * n));
  for (int j = 0; j < m; ++j) out -= gamma[j] * column(history.dg, slot(history, j), n);
  return true;
}

}  // namespace phymul
