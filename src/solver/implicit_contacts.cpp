#include "solver/implicit_contacts.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "solver/implicit_solve.hpp"

namespace phymul {
namespace {

// Most nodes touching obstacles at once: columns of P^-1 kept per factor (each unknowns long).
constexpr int kMaxContactColumns = 512;

// The column of P_a^-1 at unknown u, unknowns long, in the owner axis's cache (which must
// have it: ensure_columns).
const double* column(const ImplicitSystem& s, int a, int u) {
  const int o = s.owner[size_t(a)];
  return s.columns[size_t(o)].data() +
         size_t(s.column_slot[size_t(o)][size_t(u)]) * size_t(s.unknowns[size_t(o)]);
}

// P_o^-1 e_u into a free slot: one solve with one right-hand side.
void compute_column(ImplicitSystem& s, int o, int u) {
  const ImplicitFactor& f = *s.factor[size_t(o)];
  const int m = s.unknowns[size_t(o)];
  double* x = s.block.data();
  std::fill(x, x + m, 0.0);
  x[f.position[size_t(u)]] = 1.0;
  solve_block<1>(f, x, 1);
  const int slot = s.columns_used[size_t(o)]++;
  double* out = s.columns[size_t(o)].data() + size_t(slot) * size_t(m);
  for (int v = 0; v < m; ++v) out[v] = x[f.position[size_t(v)]];
  s.column_slot[size_t(o)][size_t(u)] = slot;
}

// Every active contact's columns in the caches; a full cache starts again empty.
void ensure_columns(ImplicitSystem& s) {
  if (int(s.active.size()) > s.column_capacity)
    throw std::runtime_error(
        "the implicit step holds at most " + std::to_string(s.column_capacity) +
        " nodes against obstacles at once; " + std::to_string(s.active.size()) +
        " touch now: use 'integrator: verlet'");
  for (int o = 0; o < 3; ++o) {
    if (s.owner[size_t(o)] != o) continue;
    std::vector<int>& slot = s.column_slot[size_t(o)];
    int missing = 0;
    for (const ImplicitSystem::Contact& c : s.active)
      if (const int u = s.unknown[size_t(o)][size_t(c.node)]; u >= 0 && slot[size_t(u)] < 0)
        ++missing;
    if (missing == 0) continue;
    if (s.columns_used[size_t(o)] + missing > s.column_capacity) {
      std::fill(slot.begin(), slot.end(), -1);
      s.columns_used[size_t(o)] = 0;
    }
    for (const ImplicitSystem::Contact& c : s.active)
      if (const int u = s.unknown[size_t(o)][size_t(c.node)]; u >= 0 && slot[size_t(u)] < 0)
        compute_column(s, o, u);
  }
}

// push . v over the node's free axes, v given per axis over the unknowns.
double along(const ImplicitSystem& s, const ImplicitSystem::Contact& c,
             const std::array<Eigen::VectorXd, 3>& v) {
  double sum = 0.0;
  for (int a = 0; a < 3; ++a)
    if (const int u = s.unknown[size_t(a)][size_t(c.node)]; u >= 0)
      sum += c.push[a] * v[size_t(a)][u];
  return sum;
}

// push_c^T P^-1 push_d over the free axes.
double coupling(const ImplicitSystem& s, const ImplicitSystem::Contact& c,
                const ImplicitSystem::Contact& d) {
  double sum = 0.0;
  for (int a = 0; a < 3; ++a) {
    const int u = s.unknown[size_t(a)][size_t(c.node)], w = s.unknown[size_t(a)][size_t(d.node)];
    if (u >= 0 && w >= 0) sum += c.push[a] * d.push[a] * column(s, a, u)[w];
  }
  return sum;
}

// S mu = rhs in place (S row-major n x n, symmetric positive semi-definite) by Cholesky; a
// row dependent on the earlier ones (a pivot at round-off) gets mu = 0.
void solve_dense(double* S, double* rhs, int n) {
  double largest = 0.0;
  for (int i = 0; i < n; ++i) largest = std::max(largest, S[i * n + i]);
  const double floor = 1e-12 * largest;
  for (int j = 0; j < n; ++j) {
    double d = S[j * n + j];
    for (int k = 0; k < j; ++k) d -= S[j * n + k] * S[j * n + k];
    const bool dependent = !(d > floor);
    S[j * n + j] = dependent ? 0.0 : std::sqrt(d);
    for (int i = j + 1; i < n; ++i) {
      double e = S[i * n + j];
      for (int k = 0; k < j; ++k) e -= S[i * n + k] * S[j * n + k];
      S[i * n + j] = dependent ? 0.0 : e / S[j * n + j];
    }
  }
  for (int i = 0; i < n; ++i) {  // L y = rhs
    double e = rhs[i];
    for (int k = 0; k < i; ++k) e -= S[i * n + k] * rhs[k];
    rhs[i] = S[i * n + i] > 0.0 ? e / S[i * n + i] : 0.0;
  }
  for (int i = n - 1; i >= 0; --i) {  // L^T mu = y
    double e = rhs[i];
    for (int k = i + 1; k < n; ++k) e -= S[k * n + i] * rhs[k];
    rhs[i] = S[i * n + i] > 0.0 ? e / S[i * n + i] : 0.0;
  }
}

double dot3(const std::array<Eigen::VectorXd, 3>& p, const std::array<Eigen::VectorXd, 3>& q) {
  return p[0].dot(q[0]) + p[1].dot(q[1]) + p[2].dot(q[2]);
}

}  // namespace

void prepare_implicit_contacts(const Model& model, ImplicitSystem& s) {
  s.active.clear();
  for (int a = 0; a < 3; ++a) {
    s.owner[size_t(a)] = a;
    for (int b = 0; b < a; ++b)
      if (s.factor[size_t(b)] == s.factor[size_t(a)]) {
        s.owner[size_t(a)] = s.owner[size_t(b)];
        break;
      }
    s.column_slot[size_t(a)].clear();
    s.columns[size_t(a)].clear();
    s.columns_used[size_t(a)] = 0;
  }
  if (model.obstacles.empty()) return;
  int most = 0;
  for (int a = 0; a < 3; ++a) most = std::max(most, s.unknowns[size_t(a)]);
  s.column_capacity = std::min(most, kMaxContactColumns);
  for (int a = 0; a < 3; ++a) {
    if (s.owner[size_t(a)] != a) continue;
    s.column_slot[size_t(a)].assign(size_t(s.unknowns[size_t(a)]), -1);
    s.columns[size_t(a)].resize(size_t(s.column_capacity) * size_t(s.unknowns[size_t(a)]));
  }
  s.active.reserve(size_t(model.node_count()));
  s.touching_gap.reserve(size_t(model.node_count()) * model.obstacles.size());
  const size_t n = model.volumes.size() + size_t(s.column_capacity);
  s.schur.resize(n * n);
  s.rhs.resize(n);
}

void constrain_to_contacts(const Model& model, ImplicitSystem& s,
                           std::span<const double> volume_rate) {
  ensure_columns(s);
  const int volumes = int(model.volumes.size()), contacts = int(s.active.size());
  const int n = volumes + contacts;
  double* S = s.schur.data();
  for (int l = 0; l < volumes; ++l) {
    s.rhs[size_t(l)] = volume_rate[size_t(l)];
    for (int m = 0; m <= l; ++m)
      S[l * n + m] = S[m * n + l] = dot3(s.gradient[size_t(l)], s.solved_gradient[size_t(m)]);
  }
  for (int c = 0; c < contacts; ++c) {
    const ImplicitSystem::Contact& cc = s.active[size_t(c)];
    const int row = volumes + c;
    s.rhs[size_t(row)] = along(s, cc, s.correction) + cc.gap;  // push . dx = -gap: onto it
    for (int l = 0; l < volumes; ++l)
      S[row * n + l] = S[l * n + row] = along(s, cc, s.solved_gradient[size_t(l)]);
    for (int d = 0; d <= c; ++d)
      S[row * n + volumes + d] = S[(volumes + d) * n + row] = coupling(s, cc, s.active[size_t(d)]);
  }
  solve_dense(S, s.rhs.data(), n);
  for (int l = 0; l < volumes; ++l)
    for (int a = 0; a < 3; ++a)
      s.correction[size_t(a)] -= s.rhs[size_t(l)] * s.solved_gradient[size_t(l)][size_t(a)];
  for (int c = 0; c < contacts; ++c) {
    const ImplicitSystem::Contact& cc = s.active[size_t(c)];
    const double mu = s.rhs[size_t(volumes + c)];
    for (int a = 0; a < 3; ++a) {
      const int u = s.unknown[size_t(a)][size_t(cc.node)];
      if (u < 0 || cc.push[a] == 0.0) continue;
      const double* col = column(s, a, u);
      Eigen::VectorXd& out = s.correction[size_t(a)];
      const double scale = mu * cc.push[a];
      for (int v = 0; v < int(out.size()); ++v) out[v] -= scale * col[v];
    }
  }
}

}  // namespace phymul
