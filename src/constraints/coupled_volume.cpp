#include "constraints/coupled_volume.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "constraints/volume_gather.hpp"
#include "constraints/volume_lanes.hpp"
#include "model/finalize.hpp"

namespace phymul {
namespace {

constexpr int kMax = kMaxJointVolumes;
using Square = std::array<double, kMax * kMax>;  // row k, column l at [k * kMax + l]
using Column = std::array<double, kMax>;

// The position projections' chord iterations: relative volume errors and their most steps.
constexpr double kExact = 1e-13;      // the sweeps stopped at 1e-12
constexpr double kConverged = 1e-12;  // accepted where round-off stops the progress
constexpr int kMaxIterations = 20;

// A chord step's error `worst` after `previous`: on the targets.
bool landed(double worst, double previous) {
  return worst <= kExact || (worst <= kConverged && worst > 0.25 * previous);
}

// 1 on the axes a node is free to move along, 0 on those a position constraint holds.
Vec3 free_axes(const Vec3& inverse_mass) {
  return (inverse_mass.array() > 0.0).cast<double>().matrix();
}

// The scratch allocate_data sizes for a model with surfaces sharing nodes.
bool usable(const Model& model, const Workspace& w) {
  if (model.volumes.empty() || model.volumes.size() > size_t(kMax)) return false;
  if (w.joint.factor.size() != size_t(kMax * kMax) ||
      w.joint.scatter.size() != coupled_scatter_size(model.inverse_mass.size()) ||
      w.volumes.size() != model.volumes.size())
    return false;
  for (size_t k = 0; k < model.volumes.size(); ++k) {
    const size_t n = model.volumes[k].nodes.size();
    const VolumeCache& cache = w.volumes[k];
    if (cache.direction.size() != n || cache.gradient.size() != n || cache.gradient_at.size() != n)
      return false;
  }
  return true;
}

// 6 dV/dx of c at x into grad, zero on the nodes of every other surface (the products with
// their directions read there); returns 6 V. The factor 6 is taken out once by the callers.
// The triangles' scatter: for a constraint finalize did not index, and the pressures.
double six_gradient(const Model& model, const VolumeConstraint& c, std::span<const Vec3> x,
                    std::span<Vec3> grad) {
  for (const VolumeConstraint& other : model.volumes)
    for (int i : other.nodes) grad[i].setZero();
  double six_volume = 0.0;
  for (const Triangle& t : c.triangles) {
    const Vec3 &a = x[t[0]], &b = x[t[1]], &d = x[t[2]];
    const Vec3 bd = b.cross(d);
    grad[t[0]] += bd;
    grad[t[1]] += d.cross(a);
    grad[t[2]] += a.cross(b);
    six_volume += a.dot(bd);
  }
  return six_volume;
}

#ifdef PHYMUL_VOLUME_AVX2
// The scratch's first 32-byte boundary: node i's sum is the aligned register at 4 i.
double* scatter_slots(Workspace& w) {
  const auto address = reinterpret_cast<std::uintptr_t>(w.joint.scatter.data());
  return w.joint.scatter.data() + (32 - address % 32) % 32 / sizeof(double);
}

// 6 dV/dx of c summed at its nodes in the scratch, in the rotated lanes (z, x, y); returns
// 6 V. A triangle's three cross products take one register each: about half the
// instructions of the scalar scatter, no spills. A node's sum is one aligned register of its
// own (the cross products' fourth lane is 0): a load of it always finds the last store of it
// whole, which forwards; at the positions' 24-byte stride the stores overlapped the next
// node's and each such load waited for them to retire (a fifth of the step, Intel).
double rotated_six_gradient(Workspace& w, const VolumeConstraint& c, std::span<const Vec3> x) {
  double* __restrict sum = scatter_slots(w);
  const double* __restrict p = x.data()->data();
  for (int i : c.nodes) _mm256_store_pd(sum + 4 * size_t(i), _mm256_setzero_pd());
  __m256d volume = _mm256_setzero_pd();
  const __m256i three = three_lanes();
  for (const Triangle& t : c.triangles) {
    const size_t i0 = 3 * size_t(t[0]), i1 = 3 * size_t(t[1]), i2 = 3 * size_t(t[2]);
    const __m256d a = _mm256_maskload_pd(p + i0, three), b = _mm256_maskload_pd(p + i1, three),
                  d = _mm256_maskload_pd(p + i2, three);
    const __m256d ar = yzx(a), br = yzx(b), dr = yzx(d);
    const __m256d bd = _mm256_fmsub_pd(b, dr, _mm256_mul_pd(br, d));
    const __m256d da = _mm256_fmsub_pd(d, ar, _mm256_mul_pd(dr, a));
    const __m256d ab = _mm256_fmsub_pd(a, br, _mm256_mul_pd(ar, b));
    double* s0 = sum + 4 * size_t(t[0]);
    double* s1 = sum + 4 * size_t(t[1]);
    double* s2 = sum + 4 * size_t(t[2]);
    _mm256_store_pd(s0, _mm256_add_pd(_mm256_load_pd(s0), bd));
    _mm256_store_pd(s1, _mm256_add_pd(_mm256_load_pd(s1), da));
    _mm256_store_pd(s2, _mm256_add_pd(_mm256_load_pd(s2), ab));
    volume = _mm256_fmadd_pd(zxy(a), bd, volume);  // a . (b x d), lane by lane
  }
  return lane_sum(volume);
}

// The per-node part of gradient_and_direction from the rotated sums, four lanes at once.
double directions_from_rotated(const Model& model, Workspace& work, const VolumeConstraint& c,
                               VolumeCache& cache, std::span<const Vec3> x, std::span<Vec3> grad,
                               bool keep) {
  const double* __restrict sum = scatter_slots(work);
  const int* __restrict nodes = c.nodes.data();
  const Vec3* __restrict w = model.inverse_mass.data();
  Vec3* __restrict g = grad.data();
  Vec3* __restrict direction = cache.direction.data();
  Vec3* __restrict kept = cache.gradient.data();
  Vec3* __restrict at = cache.gradient_at.data();
  const __m256d sixth = _mm256_set1_pd(1.0 / 6.0);
  __m256d product = _mm256_setzero_pd();
  const int n = int(c.nodes.size());
  for (int m = 0; m < n; ++m) {
    const int i = nodes[m];
    const __m256d six = yzx(_mm256_load_pd(sum + 4 * size_t(i)));
    const __m256d d = _mm256_mul_pd(sixth, _mm256_mul_pd(six, load3(w[i])));
    store3(g[i], six);
    store3(direction[m], d);
    product = _mm256_fmadd_pd(six, d, product);
    if (keep) store3(kept[m], six), at[m] = x[size_t(i)];
  }
  return lane_sum(product);
}
#endif

// The chord iterations' volumes: the same sum of a . (b x d) (lane by lane with AVX2).
double volume(const VolumeConstraint& c, std::span<const Vec3> x) {
#ifdef PHYMUL_VOLUME_AVX2
  const Vec3* __restrict p = x.data();
  __m256d six_volume = _mm256_setzero_pd();
  for (const Triangle& t : c.triangles) {
    const __m256d a = load3(p[t[0]]), b = load3(p[t[1]]), d = load3(p[t[2]]);
    const __m256d bd = _mm256_fmsub_pd(b, yzx(d), _mm256_mul_pd(yzx(b), d));
    six_volume = _mm256_fmadd_pd(zxy(a), bd, six_volume);
  }
  return lane_sum(six_volume) / 6.0;
#else
  double six_volume = 0.0;
  for (const Triangle& t : c.triangles) six_volume += x[t[0]].dot(x[t[1]].cross(x[t[2]]));
  return six_volume / 6.0;
#endif
}

// sum over c's nodes of local[m] . field[nodes[m]].
double local_dot(const VolumeConstraint& c, const Vec3* __restrict local,
                 const Vec3* __restrict field) {
  const int* __restrict nodes = c.nodes.data();
  const int n = int(c.nodes.size());
#ifdef PHYMUL_VOLUME_AVX2
  __m256d sum = _mm256_setzero_pd();
  for (int m = 0; m < n; ++m) sum = _mm256_fmadd_pd(load3(local[m]), load3(field[nodes[m]]), sum);
  return lane_sum(sum);
#else
  double sum = 0.0;
  for (int m = 0; m < n; ++m) sum += local[m].dot(field[nodes[m]]);
  return sum;
#endif
}

// field[nodes[m]] -= s * local[m], each local[m] first scaled by w[nodes[m]] / 6 when w is
// given (a kept gradient's direction).
void subtract_along(const VolumeConstraint& c, double s, const Vec3* __restrict local,
                    const Vec3* __restrict w, Vec3* __restrict field) {
  const int* __restrict nodes = c.nodes.data();
  const int n = int(c.nodes.size());
#ifdef PHYMUL_VOLUME_AVX2
  const __m256d factor = _mm256_set1_pd(s), sixth = _mm256_set1_pd(1.0 / 6.0);
  for (int m = 0; m < n; ++m) {
    Vec3& f = field[nodes[m]];
    __m256d d = load3(local[m]);
    if (w) d = _mm256_mul_pd(sixth, _mm256_mul_pd(d, load3(w[nodes[m]])));
    store3(f, _mm256_fnmadd_pd(factor, d, load3(f)));
  }
#else
  for (int m = 0; m < n; ++m) {
    const Vec3 d = w ? Vec3((1.0 / 6.0) * local[m].cwiseProduct(w[nodes[m]])) : local[m];
    field[nodes[m]] -= s * d;
  }
#endif
}

// At x, for c: 6 dV/dx at its own nodes into grad (node-indexed), its direction w dV/dx
// into the cache's direction, and, with `keep`, the gradient and x into its gradient and
// gradient_at. Returns the sum of 6 dV/dx . d over its nodes; 6 V into six_volume.
double gradient_and_direction(const Model& model, Workspace& work, const VolumeConstraint& c,
                              VolumeCache& cache, std::span<const Vec3> x, std::span<Vec3> grad,
                              bool keep, double& six_volume) {
#ifdef PHYMUL_VOLUME_AVX2
  if (gathered(c)) {  // every corner is one of `nodes`: the scatter touches nothing else
    six_volume = rotated_six_gradient(work, c, x);
    return directions_from_rotated(model, work, c, cache, x, grad, keep);
  }
#else
  (void)work;
#endif
  six_volume = six_gradient(model, c, x, grad);
  const int* __restrict nodes = c.nodes.data();
  const Vec3* __restrict w = model.inverse_mass.data();
  const Vec3* __restrict g = grad.data();
  Vec3* __restrict direction = cache.direction.data();
  Vec3* __restrict kept = cache.gradient.data();
  Vec3* __restrict at = cache.gradient_at.data();
  double product = 0.0;
  const int n = int(c.nodes.size());
  for (int m = 0; m < n; ++m) {
    const int i = nodes[m];
    const Vec3 d = (1.0 / 6.0) * g[i].cwiseProduct(w[i]);
    direction[m] = d;
    product += g[i].dot(d);
    if (keep) kept[m] = g[i], at[m] = x[size_t(i)];
  }
  return product;
}

// At x: every direction d_k = w dV_k/dx (into the caches' direction), the symmetric
// G W G^T (a_kl = dV_k/dx . d_l, zero but on the nodes two surfaces share) and, given
// `volumes`, each V_k. One gradient pass per surface; `keep`: each 6 dV_k/dx and x into the
// caches' gradient, gradient_at.
void linearise(const Model& model, Workspace& w, std::span<const Vec3> x, std::span<Vec3> grad,
               Square& a, Column* volumes, bool keep) {
  constexpr double kSixth = 1.0 / 6.0;
  const int n = int(model.volumes.size());
  for (int k = 0; k < n; ++k) {
    const VolumeConstraint& c = model.volumes[size_t(k)];
    double six_volume = 0.0;
    a[size_t(k * kMax + k)] = kSixth * gradient_and_direction(model, w, c, w.volumes[size_t(k)], x,
                                                              grad, keep, six_volume);
    if (volumes) (*volumes)[size_t(k)] = six_volume / 6.0;
    // grad is 6 dV_k/dx on c's nodes here, d_l is stored: the shared nodes, by l then node.
    for (int l = 0; l < k; ++l) a[size_t(k * kMax + l)] = a[size_t(l * kMax + k)] = 0.0;
    double product = 0.0;
    for (size_t s = 0; s < c.shared.size(); ++s) {
      const auto [l, here, there] = c.shared[s];
      product += grad[c.nodes[size_t(here)]].dot(w.volumes[size_t(l)].direction[size_t(there)]);
      if (s + 1 == c.shared.size() || c.shared[s + 1][0] != l) {
        a[size_t(k * kMax + l)] = a[size_t(l * kMax + k)] = kSixth * product;
        product = 0.0;
      }
    }
  }
}

// The linearisation the last velocity projection kept is still the one at x: the same
// positions on every surface (a step's first projection, of the accelerations, comes at the
// positions of the last one's, whatever was computed in between: a monitor's residual).
bool kept_linearisation_at(const Model& model, const Workspace& w, std::span<const Vec3> x) {
  if (!w.joint.factor_valid) return false;
  for (size_t k = 0; k < model.volumes.size(); ++k)
    if (!gradient_kept_at(model.volumes[k], w.volumes[k], x)) return false;
  return true;
}

// Lower Cholesky factor in place; false unless clearly positive definite (a surface held
// still has a zero row, two surfaces with dependent gradients a vanishing pivot).
bool cholesky(int n, Square& a) {
  for (int j = 0; j < n; ++j) {
    double pivot = a[size_t(j * kMax + j)];
    const double scale = pivot;
    for (int p = 0; p < j; ++p) pivot -= a[size_t(j * kMax + p)] * a[size_t(j * kMax + p)];
    if (!(scale > 0.0) || !(pivot > 1e-12 * scale)) return false;
    const double root = std::sqrt(pivot);
    a[size_t(j * kMax + j)] = root;
    for (int i = j + 1; i < n; ++i) {
      double s = a[size_t(i * kMax + j)];
      for (int p = 0; p < j; ++p) s -= a[size_t(i * kMax + p)] * a[size_t(j * kMax + p)];
      a[size_t(i * kMax + j)] = s / root;
    }
  }
  return true;
}

// b <- (L L^T)^-1 b.
void solve(int n, const Square& l, Column& b) {
  for (int i = 0; i < n; ++i) {
    for (int p = 0; p < i; ++p) b[size_t(i)] -= l[size_t(i * kMax + p)] * b[size_t(p)];
    b[size_t(i)] /= l[size_t(i * kMax + i)];
  }
  for (int i = n - 1; i >= 0; --i) {
    for (int p = i + 1; p < n; ++p) b[size_t(i)] -= l[size_t(p * kMax + i)] * b[size_t(p)];
    b[size_t(i)] /= l[size_t(i * kMax + i)];
  }
}

// field -= sum_k coefficient_k d_k.
void move_along_directions(const Model& model, const Workspace& w, const Column& coefficient,
                           std::span<Vec3> field) {
  for (size_t k = 0; k < model.volumes.size(); ++k)
    subtract_along(model.volumes[k], coefficient[k], w.volumes[k].direction.data(), nullptr,
                   field.data());
}

// The factor of G W G^T at the positions the caches' gradient_at hold, for the velocity
// projection that comes next at the same positions.
bool keep_factor(Workspace& w, int n, Square& a) {
  w.joint.factor_valid = false;
  if (!cholesky(n, a)) return false;
  std::copy(a.begin(), a.end(), w.joint.factor.begin());
  w.joint.factor_valid = true;
  return true;
}

}  // namespace

bool project_coupled_volumes(const Model& model, const Controls& controls, Workspace& w,
                             std::span<Vec3> x, double load_time, std::span<Vec3> grad) {
  // Chord iterations on V_k(x0 + sum_j lambda_j d_j) = target_k with the Jacobian at x0,
  // G W G^T: exact to first order, so each iteration squares the relative error (1e-6 ->
  // 1e-12 -> round-off) and costs only the volumes, not their gradients.
  // From an error this small, the first chord step lands within round-off: its volumes are
  // then taken with the gradients at the projected positions, which the velocity projection
  // needs next (one gradient pass a step instead of two). A later step, with the Jacobian of
  // the start, shrinks the error by about the ratio of the last two: it takes the gradients
  // when that ratio predicts a landing, so a larger start error (a contact's, 1e-4) costs a
  // volume pass more rather than a gradient pass more.
  constexpr double kLastStep = 1e-7;
  if (!usable(model, w)) return false;
  const int n = int(model.volumes.size());
  Square a{};
  Column volumes{}, targets{}, residual{};
  linearise(model, w, x, grad, a, &volumes, /*keep=*/true);
  auto worst_error = [&] {
    double worst = 0.0;
    for (int k = 0; k < n; ++k) {
      residual[size_t(k)] = volumes[size_t(k)] - targets[size_t(k)];
      worst = std::max(worst, std::abs(residual[size_t(k)]) / std::abs(targets[size_t(k)]));
    }
    return worst;
  };
  for (int k = 0; k < n; ++k)
    targets[size_t(k)] = target_volume(model, controls, size_t(k), load_time);
  double worst = worst_error();
  if (!keep_factor(w, n, a)) return worst <= kExact;
  if (worst <= kExact) return true;
  double previous = 0.0;  // the error before the last chord step; 0: none yet
  for (int it = 0; it < kMaxIterations; ++it) {
    Column step = residual;
    solve(n, a, step);
    move_along_directions(model, w, step, x);
    const bool lands = previous == 0.0 || worst * (worst / previous) <= kExact;
    if (worst <= kLastStep && lands) {
      // Should it not land yet, the next steps are Newton's, with this linearisation.
      linearise(model, w, x, grad, a, &volumes, /*keep=*/true);
      if (!keep_factor(w, n, a)) return false;
    } else {
      for (int k = 0; k < n; ++k) volumes[size_t(k)] = volume(model.volumes[size_t(k)], x);
    }
    previous = worst;
    worst = worst_error();
    if (landed(worst, previous)) return true;
  }
  return false;
}

bool project_coupled_volume_velocities(const Model& model, Workspace& w, std::span<const Vec3> x,
                                       std::span<Vec3> v, std::span<Vec3> grad) {
  constexpr double kSixth = 1.0 / 6.0;
  if (!usable(model, w)) return false;
  const int n = int(model.volumes.size());
  Square a{};
  if (kept_linearisation_at(model, w, x)) {
    std::copy_n(w.joint.factor.begin(), kMax * kMax, a.begin());
  } else {
    linearise(model, w, x, grad, a, nullptr, /*keep=*/true);
    if (!keep_factor(w, n, a)) return false;
  }
  Column rates{};  // dV_k/dt
  for (int k = 0; k < n; ++k) {
    const VolumeConstraint& c = model.volumes[size_t(k)];
    rates[size_t(k)] = kSixth * local_dot(c, w.volumes[size_t(k)].gradient.data(), v.data());
  }
  solve(n, a, rates);
  // v -= sum_k mu_k w dV_k/dx from the kept gradients: the directions' scratch may have been
  // overwritten since (the position projection, a residual's pressures).
  for (int k = 0; k < n; ++k) {
    const VolumeConstraint& c = model.volumes[size_t(k)];
    subtract_along(c, rates[size_t(k)], w.volumes[size_t(k)].gradient.data(),
                   model.inverse_mass.data(), v.data());
  }
  return true;
}

namespace {

// Node i's d_k . push over each volume k (d_k = w dV_k/dx from the kept gradients; 0 where
// the node is not on k), and push . W push (W: its inverse mass, 0 on held axes).
double along_push(const Model& model, const Workspace& w, const ObstacleContact& c,
                  std::array<double, kMax>& along) {
  const Vec3 wi = model.inverse_mass[size_t(c.node)];
  for (size_t k = 0; k < model.volumes.size(); ++k) {
    const VolumeConstraint& v = model.volumes[k];
    const auto at = std::lower_bound(v.nodes.begin(), v.nodes.end(), c.node);
    along[k] =
        at != v.nodes.end() && *at == c.node
            ? (1.0 / 6.0) *
                  w.volumes[k].gradient[size_t(at - v.nodes.begin())].cwiseProduct(wi).dot(c.push)
            : 0.0;
  }
  return c.push.cwiseProduct(wi).dot(c.push);
}

// G W G^T from its kept Cholesky factor.
Square kept_matrix(const Workspace& w, int n) {
  Square a{};
  const std::vector<double>& l = w.joint.factor;
  for (int k = 0; k < n; ++k)
    for (int m = 0; m <= k; ++m) {
      double sum = 0.0;
      for (int p = 0; p <= m; ++p) sum += l[size_t(k * kMax + p)] * l[size_t(m * kMax + p)];
      a[size_t(k * kMax + m)] = a[size_t(m * kMax + k)] = sum;
    }
  return a;
}

// The Cholesky factor of G W' G^T from a = G W G^T, W' each held node's inverse mass without
// its push direction (W - W p p^T W / p.W p); false where singular.
bool held_factor(const Model& model, const Workspace& w, const Square& a,
                 std::span<const ObstacleContact> held, Square& reduced) {
  const int n = int(model.volumes.size());
  reduced = a;
  std::array<double, kMax> along{};
  for (const ObstacleContact& c : held) {
    const double pwp = along_push(model, w, c, along);
    if (!(pwp > 0.0)) continue;
    for (int k = 0; k < n; ++k)
      for (int l = 0; l < n; ++l)
        reduced[size_t(k * kMax + l)] -= along[size_t(k)] * along[size_t(l)] / pwp;
  }
  return cholesky(n, reduced);
}

// Held node c's reaction: the velocity along its push the volumes' correction would take
// away, sum_k mu_k d_k . push, over push . W push (> 0: the obstacle pushes).
double held_reaction(const Model& model, const Workspace& w, const ObstacleContact& c,
                     const Column& mu) {
  std::array<double, kMax> along{};
  const double pwp = along_push(model, w, c, along);
  if (!(pwp > 0.0)) return 0.0;
  double s = 0.0;
  for (size_t k = 0; k < model.volumes.size(); ++k) s += mu[k] * along[k];
  return s / pwp;
}

// Solves the held projection's multipliers for `rates` into mu, its factor into `reduced`,
// releasing the held nodes the obstacle would pull (at most 4 passes; false after, or where
// singular).
bool hold_and_solve(const Model& model, const Workspace& w, std::vector<ObstacleContact>& held,
                    const Column& rates, Square& reduced, Column& mu) {
  constexpr int kMostPasses = 4;
  const int n = int(model.volumes.size());
  const Square a = kept_matrix(w, n);
  for (int pass = 0;; ++pass) {
    if (!held_factor(model, w, a, held, reduced)) return false;
    mu = rates;
    solve(n, reduced, mu);
    const auto pulled = [&](const ObstacleContact& c) {
      return held_reaction(model, w, c, mu) < 0.0;
    };
    if (std::none_of(held.begin(), held.end(), pulled)) return true;
    if (pass + 1 == kMostPasses) return false;
    held.erase(std::remove_if(held.begin(), held.end(), pulled), held.end());
  }
}

// field -= W' G^T mu: along every direction from the kept gradients, then each held node's
// push part given back (passed to `record` with the node).
template <class Record>
void move_held(const Model& model, const Workspace& w, const Column& mu,
               std::span<const ObstacleContact> held, std::span<Vec3> field, Record record) {
  for (size_t k = 0; k < model.volumes.size(); ++k)
    subtract_along(model.volumes[k], mu[k], w.volumes[k].gradient.data(), model.inverse_mass.data(),
                   field.data());
  for (const ObstacleContact& c : held) {
    const Vec3 back = held_reaction(model, w, c, mu) *
                      Vec3(c.push.cwiseProduct(model.inverse_mass[size_t(c.node)]));
    field[size_t(c.node)] += back;
    record(c.node, back);
  }
}

}  // namespace

bool project_coupled_volume_velocities_held(const Model& model, Workspace& w,
                                            std::span<const Vec3> x, std::span<Vec3> v,
                                            std::vector<ObstacleContact>& held,
                                            std::span<const int> touching,
                                            std::span<Vec3> impulse) {
  if (!usable(model, w) || !kept_linearisation_at(model, w, x)) return false;
  const int n = int(model.volumes.size());
  Column rates{}, mu{};
  for (int k = 0; k < n; ++k)
    rates[size_t(k)] = (1.0 / 6.0) * local_dot(model.volumes[size_t(k)],
                                               w.volumes[size_t(k)].gradient.data(), v.data());
  Square reduced{};
  if (!hold_and_solve(model, w, held, rates, reduced, mu)) return false;
  move_held(model, w, mu, held, v, [&](int i, const Vec3& dv) {
    impulse[size_t(touching[size_t(i)])] += model.mass[size_t(i)] * dv;
  });
  return true;
}

bool reproject_coupled_volumes_held(const Model& model, const Controls& controls, Workspace& w,
                                    std::span<Vec3> x, double load_time,
                                    std::vector<ObstacleContact>& held,
                                    std::span<const int> touching, std::span<Vec3> impulse,
                                    double dt) {
  if (!usable(model, w) || !w.joint.factor_valid) return false;
  const int n = int(model.volumes.size());
  Column residual{}, mu{};
  auto worst_error = [&] {
    double worst = 0.0;
    for (int k = 0; k < n; ++k) {
      const double target = target_volume(model, controls, size_t(k), load_time);
      residual[size_t(k)] = volume(model.volumes[size_t(k)], x) - target;
      worst = std::max(worst, std::abs(residual[size_t(k)]) / std::abs(target));
    }
    return worst;
  };
  double worst = worst_error(), previous = std::numeric_limits<double>::infinity();
  if (worst <= kExact) return true;
  Square reduced{};
  // The held set from the first chord step, the largest: a node it would pull is released.
  if (!hold_and_solve(model, w, held, residual, reduced, mu)) return false;
  for (int it = 0; it < kMaxIterations; ++it) {
    if (it > 0) {
      mu = residual;
      solve(n, reduced, mu);
    }
    move_held(model, w, mu, held, x, [&](int i, const Vec3& dx) {
      impulse[size_t(touching[size_t(i)])] += model.mass[size_t(i)] * dx / dt;
    });
    previous = worst;
    worst = worst_error();
    if (landed(worst, previous)) return true;
  }
  return false;
}

// A node against an obstacle may push along the contact normal with any force: that part of
// its residual and of the gradients' free parts is left out of the least squares (of the
// residual's and of the support reactions' alike).
void remove_contact_normals(const Model& model, const Workspace& w,
                            std::span<const ObstacleContact> contact, std::span<const Vec3> r,
                            Square& a, Column& balanced) {
  const int n = int(model.volumes.size());
  for (const auto& [i, normal, friction] : contact) {
    std::array<double, kMax> along{};  // F_k . normal, F_k the free gradient part (over 6)
    for (int k = 0; k < n; ++k) {
      const VolumeConstraint& c = model.volumes[size_t(k)];
      const auto at = std::lower_bound(c.nodes.begin(), c.nodes.end(), i);
      if (at != c.nodes.end() && *at == i)
        along[size_t(k)] = w.volumes[size_t(k)]
                               .direction[size_t(at - c.nodes.begin())]
                               .cwiseProduct(free_axes(model.inverse_mass[size_t(i)]))
                               .dot(normal);
    }
    const double r_along = r[size_t(i)].dot(normal);
    for (int k = 0; k < n; ++k) {
      balanced[size_t(k)] -= along[size_t(k)] * r_along;
      for (int l = 0; l < n; ++l) a[size_t(k * kMax + l)] -= along[size_t(k)] * along[size_t(l)];
    }
  }
}

bool remove_coupled_volume_pressures(const Model& model, Workspace& w, std::span<const Vec3> x,
                                     std::span<Vec3> r, std::span<Vec3> grad, bool on_free_axes,
                                     std::span<const ObstacleContact> contact) {
  constexpr double kSixth = 1.0 / 6.0;
  if (!usable(model, w)) return false;
  const int n = int(model.volumes.size());
  Square a{};
  Column balanced{};
  // Between steps (a monitor's residual) the velocity projection has kept the gradients here.
  const bool kept = kept_linearisation_at(model, w, x);
  for (int k = 0; k < n; ++k) {
    const VolumeConstraint& c = model.volumes[size_t(k)];
    if (kept) {  // the same gradient, as six_gradient would leave it in grad
      for (const VolumeConstraint& other : model.volumes)
        for (int i : other.nodes) grad[i].setZero();
      for (size_t m = 0; m < c.nodes.size(); ++m)
        grad[c.nodes[m]] = w.volumes[size_t(k)].gradient[m];
    } else {
      six_gradient(model, c, x, grad);
    }
    double rg = 0.0;
    for (size_t m = 0; m < c.nodes.size(); ++m) {
      const int i = c.nodes[m];
      const Vec3 free_part = grad[i].cwiseProduct(free_axes(model.inverse_mass[size_t(i)]));
      w.volumes[size_t(k)].direction[m] = kSixth * (on_free_axes ? free_part : grad[i]);
      rg += free_part.dot(r[size_t(i)]);
    }
    balanced[size_t(k)] = kSixth * rg;
    for (int l = 0; l <= k; ++l) {  // F F^T: masking dV_k/dx is enough, d_l may be whole
      const VolumeConstraint& o = model.volumes[size_t(l)];
      double product = 0.0;
      for (size_t m = 0; m < o.nodes.size(); ++m) {
        const int i = o.nodes[m];
        product += grad[i]
                       .cwiseProduct(free_axes(model.inverse_mass[size_t(i)]))
                       .dot(w.volumes[size_t(l)].direction[m]);
      }
      a[size_t(k * kMax + l)] = a[size_t(l * kMax + k)] = kSixth * product;
    }
  }
  remove_contact_normals(model, w, contact, r, a, balanced);
  if (!cholesky(n, a)) return false;
  solve(n, a, balanced);
  move_along_directions(model, w, balanced, r);
  return true;
}

}  // namespace phymul
