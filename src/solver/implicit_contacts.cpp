#include "solver/implicit_contacts.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "model/block_cholesky.hpp"
#include "solver/implicit_needles.hpp"
#include "solver/implicit_pairs.hpp"
#include "solver/implicit_solve.hpp"

namespace phymul {
namespace {

// Most nodes in contact rows at once: columns of P^-1 kept per factor (each unknowns long).
constexpr int kMaxContactColumns = 512;
// Most contact rows (obstacles' and pairs') a solve takes: its dense system is this square.
constexpr int kMaxContactRows = 512;
// Most values the coupled factor's column cache holds (256 MB): 9 blocks' worth a node.
constexpr size_t kMostColumnValues = size_t(1) << 25;

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

// Values a coupled slot holds: the three columns of P^-1 at a block, each 3 blocks long.
size_t coupled_slot_size(const ImplicitSystem& s) { return 9 * size_t(s.coupled->blocks); }

// P^-1 at block b's axes into a free slot: one solve for each free axis (a held axis's
// column is never read).
void compute_coupled_columns(ImplicitSystem& s, int b) {
  const BlockFactor& f = *s.coupled;
  const size_t width = 3 * size_t(f.blocks);
  const int slot = s.columns_used[0]++;
  double* out = s.coupled_columns.get() + size_t(slot) * coupled_slot_size(s);
  for (int a = 0; a < 3; ++a) {
    if (s.block_unknown[size_t(b)][size_t(a)] < 0) continue;
    double* x = out + size_t(a) * width;
    std::fill(x, x + width, 0.0);
    x[3 * f.position[size_t(b)] + a] = 1.0;
    solve_blocks(f, x);
  }
  s.column_slot[0][size_t(b)] = slot;
}

// With the coupled factor: P^-1's column at node i's axis a, in the factor's order.
const double* coupled_column(const ImplicitSystem& s, int i, int a) {
  const int slot = s.column_slot[0][size_t(s.block_of_node[size_t(i)])];
  return s.coupled_columns.get() + size_t(slot) * coupled_slot_size(s) +
         size_t(a) * 3 * size_t(s.coupled->blocks);
}

// Calls visit(key) for each distinct key(node) >= 0 over the active rows' nodes (each key
// once), marking seen keys in `slot` by -2 and restoring them.
template <class Key, class Visit>
void each_missing(const ImplicitSystem& s, std::vector<int>& slot, Key key, Visit visit) {
  for (const ImplicitSystem::Contact& c : s.active)
    for (int k = 0; k < c.count; ++k)
      if (const int b = key(c.nodes[size_t(k)]); b >= 0 && slot[size_t(b)] == -1) {
        slot[size_t(b)] = -2;
        visit(b);
      }
  for (const ImplicitSystem::Contact& c : s.active)
    for (int k = 0; k < c.count; ++k)
      if (const int b = key(c.nodes[size_t(k)]); b >= 0 && slot[size_t(b)] == -2)
        slot[size_t(b)] = -1;
}

[[noreturn]] void too_many(const ImplicitSystem& s, int rows, int nodes) {
  throw std::runtime_error("the implicit step takes at most " + std::to_string(s.row_capacity) +
                           " contact rows over " + std::to_string(s.column_capacity) +
                           " nodes at once; " + std::to_string(rows) + " rows over " +
                           std::to_string(nodes) + " nodes touch now: use 'integrator: verlet'");
}

// P^-1's columns at the keys (blocks, or one axis's unknowns) the active rows need in a cache
// of `used` slots, computed by `compute`; a full cache starts again empty.
template <class Key, class Compute>
void ensure_cached(ImplicitSystem& s, std::vector<int>& slot, int& used, Key key, Compute compute) {
  int missing = 0;
  each_missing(s, slot, key, [&](int) { ++missing; });
  if (missing == 0) return;
  if (used + missing > s.column_capacity) {
    std::fill(slot.begin(), slot.end(), -1);
    used = 0;
    missing = 0;
    each_missing(s, slot, key, [&](int) { ++missing; });
    if (missing > s.column_capacity) too_many(s, int(s.active.size()), missing);
  }
  each_missing(s, slot, key, compute);
}

// Every active row's columns in the caches.
void ensure_columns(ImplicitSystem& s) {
  if (int(s.active.size()) > s.row_capacity) too_many(s, int(s.active.size()), 0);
  if (s.coupled) {
    ensure_cached(
        s, s.column_slot[0], s.columns_used[0], [&](int i) { return s.block_of_node[size_t(i)]; },
        [&](int b) { compute_coupled_columns(s, b); });
    return;
  }
  for (int o = 0; o < 3; ++o)
    if (s.owner[size_t(o)] == o)
      ensure_cached(
          s, s.column_slot[size_t(o)], s.columns_used[size_t(o)],
          [&](int i) { return s.unknown[size_t(o)][size_t(i)]; },
          [&](int u) { compute_column(s, o, u); });
}

}  // namespace

// The row's g . v over its nodes' free axes, v given per axis over the unknowns.
double along(const ImplicitSystem& s, const ImplicitSystem::Contact& c,
             const std::array<Eigen::VectorXd, 3>& v) {
  double sum = 0.0;
  for (int k = 0; k < c.count; ++k) {
    const int i = c.nodes[size_t(k)];
    double node = 0.0;
    for (int a = 0; a < 3; ++a)
      if (const int u = s.unknown[size_t(a)][size_t(i)]; u >= 0)
        node += c.push[a] * v[size_t(a)][u];
    sum += c.weights[size_t(k)] * node;
  }
  return sum;
}

namespace {

// push_c^T P^-1 push_d between node i of one row and node j of another, over the free axes,
// the coupled factor's axes coupled.
double coupled_coupling(const ImplicitSystem& s, const Eigen::Vector3d& pc, int i,
                        const Eigen::Vector3d& pd, int j) {
  const int bi = s.block_of_node[size_t(i)], bj = s.block_of_node[size_t(j)];
  if (bi < 0 || bj < 0) return 0.0;  // a node every axis of which is held
  const int at = 3 * s.coupled->position[size_t(bj)];
  double sum = 0.0;
  for (int a = 0; a < 3; ++a) {
    if (s.unknown[size_t(a)][size_t(i)] < 0) continue;
    const double* col = coupled_column(s, i, a);
    for (int b = 0; b < 3; ++b)
      if (s.unknown[size_t(b)][size_t(j)] >= 0) sum += pc[a] * pd[b] * col[at + b];
  }
  return sum;
}

// The same with the per-axis factors.
double axis_coupling(const ImplicitSystem& s, const Eigen::Vector3d& pc, int i,
                     const Eigen::Vector3d& pd, int j) {
  double sum = 0.0;
  for (int a = 0; a < 3; ++a) {
    const int u = s.unknown[size_t(a)][size_t(i)], w = s.unknown[size_t(a)][size_t(j)];
    if (u >= 0 && w >= 0) sum += pc[a] * pd[a] * column(s, a, u)[w];
  }
  return sum;
}

// g_c^T P^-1 g_d over the rows' nodes.
double coupling(const ImplicitSystem& s, const ImplicitSystem::Contact& c,
                const ImplicitSystem::Contact& d) {
  double sum = 0.0;
  for (int k = 0; k < c.count; ++k) {
    const int i = c.nodes[size_t(k)];
    for (int l = 0; l < d.count; ++l) {
      const int j = d.nodes[size_t(l)];
      const double w = c.weights[size_t(k)] * d.weights[size_t(l)];
      sum += w * (s.coupled ? coupled_coupling(s, c.push, i, d.push, j)
                            : axis_coupling(s, c.push, i, d.push, j));
    }
  }
  return sum;
}

}  // namespace

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

namespace {

double dot3(const std::array<Eigen::VectorXd, 3>& p, const std::array<Eigen::VectorXd, 3>& q) {
  return p[0].dot(q[0]) + p[1].dot(q[1]) + p[2].dot(q[2]);
}

// The coupled factor's column cache: slots for up to kMaxContactColumns blocks, within
// kMostColumnValues values; left uninitialised, so only the slots used are ever touched.
void prepare_coupled_columns(ImplicitSystem& s) {
  const int blocks = s.coupled->blocks;
  const size_t fit = kMostColumnValues / coupled_slot_size(s);
  s.column_capacity =
      int(std::max<size_t>(1, std::min({size_t(blocks), fit, size_t(kMaxContactColumns)})));
  s.column_slot[0].assign(size_t(blocks), -1);
  s.coupled_columns.reset(new double[size_t(s.column_capacity) * coupled_slot_size(s)]);
}

// The whole system of the volumes and every touching node, into s.system (row-major) and
// s.system_rhs.
void build_system(ImplicitSystem& s, int volumes, std::span<const double> volume_rate) {
  const int contacts = int(s.active.size()), n = volumes + contacts;
  double* S = s.system.data();
  for (int l = 0; l < volumes; ++l) {
    s.system_rhs[size_t(l)] = volume_rate[size_t(l)];
    for (int m = 0; m <= l; ++m)
      S[l * n + m] = S[m * n + l] = dot3(s.gradient[size_t(l)], s.solved_gradient[size_t(m)]);
  }
  for (int c = 0; c < contacts; ++c) {
    const ImplicitSystem::Contact& cc = s.active[size_t(c)];
    const int row = volumes + c;
    s.system_rhs[size_t(row)] = along(s, cc, s.correction) + cc.gap;  // push . dx = -gap
    for (int l = 0; l < volumes; ++l)
      S[row * n + l] = S[l * n + row] = along(s, cc, s.solved_gradient[size_t(l)]);
    for (int d = 0; d <= c; ++d)
      S[row * n + volumes + d] = S[(volumes + d) * n + row] = coupling(s, cc, s.active[size_t(d)]);
  }
}

// The multipliers of the volumes and the held contacts (0 for the released) into
// s.multiplier, from the system's rows and columns they take.
void solve_held(ImplicitSystem& s, int volumes) {
  const int contacts = int(s.active.size()), n = volumes + contacts;
  int m = 0;
  for (int r = 0; r < n; ++r)
    if (r < volumes || s.held[size_t(r - volumes)]) s.rows[size_t(m++)] = r;
  for (int i = 0; i < m; ++i) {
    const int r = s.rows[size_t(i)];
    s.rhs[size_t(i)] = s.system_rhs[size_t(r)];
    for (int j = 0; j < m; ++j)
      s.schur[size_t(i * m + j)] = s.system[size_t(r * n + s.rows[size_t(j)])];
  }
  solve_dense(s.schur.data(), s.rhs.data(), m);
  std::fill(s.multiplier.begin(), s.multiplier.begin() + n, 0.0);
  for (int i = 0; i < m; ++i) s.multiplier[size_t(s.rows[size_t(i)])] = s.rhs[size_t(i)];
}

// Solves with the held contacts and releases those that both the multiplier (the reaction
// -mu push tensile: mu > 0) and the residual (into >= 0: not pressed into the obstacle) let
// go; whether any was released. Either sign alone cycles: by the multiplier's alone the
// rigid probe's 50 mL run took 18 solves a step; the residual's lags the solve by one.
bool release_tensile(ImplicitSystem& s, int volumes) {
  solve_held(s, volumes);
  bool released = false;
  for (int c = 0; c < int(s.active.size()); ++c) {
    if (!s.held[size_t(c)]) continue;
    const ImplicitSystem::Contact& cc = s.active[size_t(c)];
    // A tangent row (friction) goes with its node's normal row, which comes before it.
    const bool release = cc.needle >= 0 ? false  // a needle holds both ways
                         : cc.normal_row >= 0
                             ? !s.held[size_t(cc.normal_row)]
                             : s.multiplier[size_t(volumes + c)] > 0.0 && cc.into >= 0.0;
    if (release) s.held[size_t(c)] = 0, released = true;
  }
  return released;
}

// correction -= mu P^-1 g over the row's nodes.
void subtract_column(ImplicitSystem& s, const ImplicitSystem::Contact& cc, double mu) {
  for (int k = 0; k < cc.count; ++k)
    for (int a = 0; a < 3; ++a) {
      const int i = cc.nodes[size_t(k)];
      const int u = s.unknown[size_t(a)][size_t(i)];
      if (u < 0 || cc.push[a] == 0.0) continue;
      const double scale = mu * cc.weights[size_t(k)] * cc.push[a];
      if (s.coupled) {
        const double* col = coupled_column(s, i, a);
        const BlockFactor& f = *s.coupled;
        for (int b = 0; b < f.blocks; ++b)
          for (int e = 0; e < 3; ++e)
            if (const int v = s.block_unknown[size_t(b)][size_t(e)]; v >= 0)
              s.correction[size_t(e)][v] -= scale * col[3 * f.position[size_t(b)] + e];
        continue;
      }
      const double* col = column(s, a, u);
      Eigen::VectorXd& out = s.correction[size_t(a)];
      for (int v = 0; v < int(out.size()); ++v) out[v] -= scale * col[v];
    }
}

}  // namespace

size_t pair_node_count(const Model& model) {
  size_t nodes = 0;
  for (const ContactPair& pair : model.contact_pairs)
    nodes += pair.nodes[0].size() + pair.nodes[1].size();
  return nodes;
}

void prepare_implicit_contacts(const Model& model, ImplicitSystem& s) {
  s.active.clear();
  s.coupled_columns.reset();
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
  const size_t pair_nodes = pair_node_count(model), needle_rows = needle_row_count(model);
  if (model.obstacles.empty() && pair_nodes == 0 && needle_rows == 0) return;
  if (s.coupled) {
    prepare_coupled_columns(s);
  } else {
    int most = 0;
    for (int a = 0; a < 3; ++a) most = std::max(most, s.unknowns[size_t(a)]);
    s.column_capacity = std::min(most, kMaxContactColumns);
    for (int a = 0; a < 3; ++a) {
      if (s.owner[size_t(a)] != a) continue;
      s.column_slot[size_t(a)].assign(size_t(s.unknowns[size_t(a)]), -1);
      s.columns[size_t(a)].resize(size_t(s.column_capacity) * size_t(s.unknowns[size_t(a)]));
    }
  }
  // A node on a rough obstacle may stick: two tangent rows beside its normal one.
  size_t obstacle_rows = 0;
  for (const RigidObstacle& o : model.obstacles)
    obstacle_rows += size_t(model.node_count()) * (o.friction > 0.0 ? 3 : 1);
  s.pair_rows.clear();
  if (pair_nodes > 0) prepare_pair_rows(model, s);
  // The needles' rows are fitted and recorded with the pairs'.
  if (needle_rows > 0) s.pair_rows.reserve(s.pair_rows.capacity() + needle_rows);
  s.row_capacity = int(std::min(obstacle_rows + s.pair_rows.capacity(), size_t(kMaxContactRows)));
  s.active.reserve(obstacle_rows + s.pair_rows.capacity());
  s.touching_gap.reserve(obstacle_rows);
  s.touching_obstacle.reserve(obstacle_rows);
  const size_t n = model.volumes.size() + size_t(s.row_capacity);
  s.schur.resize(n * n);
  s.rhs.resize(n);
  s.system.resize(n * n);
  s.system_rhs.resize(n);
  s.multiplier.resize(n);
  s.rows.resize(n);
  s.held.resize(size_t(s.row_capacity));
  s.held_by.assign(size_t(model.node_count()), -1);
  s.pair_held.assign(size_t(model.node_count()), -1);
  if (pair_nodes == 0 && needle_rows == 0) return;
  s.fit.resize(n * n);
  s.fit_rhs.resize(n);
  s.fit_rows.resize(n);
  s.pair_force.resize(s.pair_rows.capacity());
  s.touching.resize(s.pair_rows.capacity());
}

void constrain_to_contacts(const Model& model, ImplicitSystem& s,
                           std::span<const double> volume_rate) {
  ensure_columns(s);
  const int volumes = int(model.volumes.size()), contacts = int(s.active.size());
  build_system(s, volumes, volume_rate);
  std::fill(s.held.begin(), s.held.begin() + contacts, char(1));
  while (release_tensile(s, volumes)) {
  }
  // A node with several rows (faces at an edge, obstacles) stays held while any one is.
  for (const ImplicitSystem::Contact& cc : s.active)
    if (cc.needle < 0) (cc.pair >= 0 ? s.pair_held : s.held_by)[size_t(cc.nodes[0])] = -1;
  for (int c = 0; c < contacts; ++c)
    if (const ImplicitSystem::Contact& cc = s.active[size_t(c)];
        s.held[size_t(c)] && cc.normal_row < 0 && cc.needle < 0)
      (cc.pair >= 0 ? s.pair_held : s.held_by)[size_t(cc.nodes[0])] =
          cc.pair >= 0 ? cc.pair : cc.obstacle;
  for (int l = 0; l < volumes; ++l)
    for (int a = 0; a < 3; ++a)
      s.correction[size_t(a)] -= s.multiplier[size_t(l)] * s.solved_gradient[size_t(l)][size_t(a)];
  for (int c = 0; c < contacts; ++c)
    if (const double mu = s.multiplier[size_t(volumes + c)]; mu != 0.0)
      subtract_column(s, s.active[size_t(c)], mu);
}

}  // namespace phymul
