#include <fmt/format.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>

#include "constraints/constraints.hpp"
#include "constraints/coupled_volume.hpp"

namespace phymul {
namespace {

// Per-node and per-triangle loops of a large surface run in parallel from this many items.
constexpr int kParallelFrom = 2048;

// The N sums of add(k, sums) over k in [0, n), taken in a fixed number of contiguous chunks
// whose partial sums are added in chunk order: the same bits whatever the number of threads.
template <size_t N, class Add>
std::array<double, N> ordered_sums(int n, Add&& add) {
  constexpr int kChunks = 16;
  std::array<std::array<double, N>, kChunks> part{};
#pragma omp parallel for schedule(static) if (n >= kParallelFrom)
  for (int chunk = 0; chunk < kChunks; ++chunk) {
    const int begin = int(int64_t(n) * chunk / kChunks);
    const int end = int(int64_t(n) * (chunk + 1) / kChunks);
    std::array<double, N> sums{};
    for (int k = begin; k < end; ++k) add(k, sums);
    part[size_t(chunk)] = sums;
  }
  std::array<double, N> total{};
  for (const std::array<double, N>& p : part)
    for (size_t a = 0; a < N; ++a) total[a] += p[a];
  return total;
}

// Coefficients of V(x + lambda d) = c0 + c1 l + c2 l^2 + c3 l^3, exact for a triangulated
// surface since the volume is a cubic polynomial of the node positions.
std::array<double, 4> volume_cubic(const VolumeConstraint& c, std::span<const Vec3> x,
                                   std::span<const Vec3> d) {
  std::array<double, 4> k = ordered_sums<4>(int(c.triangles.size()), [&](int n, auto& sums) {
    const Triangle& t = c.triangles[size_t(n)];
    const Vec3 &xa = x[t[0]], &xb = x[t[1]], &xc = x[t[2]];
    const Vec3 &da = d[t[0]], &db = d[t[1]], &dc = d[t[2]];
    const Vec3 xbc = xb.cross(xc), dbc = db.cross(dc);
    const Vec3 mixed = db.cross(xc) + xb.cross(dc);
    sums[0] += xa.dot(xbc);
    sums[1] += da.dot(xbc) + xa.dot(mixed);
    sums[2] += da.dot(mixed) + xa.dot(dbc);
    sums[3] += da.dot(dbc);
  });
  for (double& v : k) v /= 6.0;
  return k;
}

}  // namespace

void volume_gradient(const VolumeConstraint& c, std::span<const Vec3> x, std::span<Vec3> grad) {
  // The factor 1/6 once per node rather than three times per triangle (a node has about six
  // triangles): 9 divisions per triangle saved; rounded once, the sum is as accurate.
  // The triangles' scatter stays on one thread (triangles sharing a node would race).
  const int n = int(c.nodes.size());
#pragma omp parallel for schedule(static) if (n >= kParallelFrom)
  for (int k = 0; k < n; ++k) grad[c.nodes[size_t(k)]].setZero();
  for (const Triangle& t : c.triangles) {
    const Vec3 &a = x[t[0]], &b = x[t[1]], &d = x[t[2]];
    grad[t[0]] += b.cross(d);
    grad[t[1]] += d.cross(a);
    grad[t[2]] += a.cross(b);
  }
#pragma omp parallel for schedule(static) if (n >= kParallelFrom)
  for (int k = 0; k < n; ++k) grad[c.nodes[size_t(k)]] /= 6.0;
}

double project_volume(const VolumeConstraint& c, std::span<const Vec3> inverse_mass,
                      std::span<Vec3> x, std::span<Vec3> grad) {
  return project_volume(c, inverse_mass, x, grad, c.target_volume);
}

double project_volume(const VolumeConstraint& c, std::span<const Vec3> inverse_mass,
                      std::span<Vec3> x, std::span<Vec3> grad, double target,
                      double* relative_error_before) {
  volume_gradient(c, x, grad);
  const int n = int(c.nodes.size());
#pragma omp parallel for schedule(static) if (n >= kParallelFrom)
  for (int k = 0; k < n; ++k) {  // direction d
    const int i = c.nodes[size_t(k)];
    grad[i] = grad[i].cwiseProduct(inverse_mass[i]);
  }
  const auto k = volume_cubic(c, x, grad);
  if (relative_error_before) *relative_error_before = std::abs(k[0] - target) / std::abs(target);
  if (k[0] == target) return 0.0;
  if (k[1] <= 0.0)
    throw std::runtime_error(fmt::format(
        "volume constraint of '{}': no free surface node can change its volume (all are held "
        "by position constraints)",
        c.component));
  // Newton from lambda = 0 finds the root nearest to zero: V is increasing there (c1 > 0).
  double lambda = 0.0;
  for (int it = 0; it < 50; ++it) {
    const double r = ((k[3] * lambda + k[2]) * lambda + k[1]) * lambda + k[0] - target;
    const double slope = (3.0 * k[3] * lambda + 2.0 * k[2]) * lambda + k[1];
    const double step = r / slope;
    lambda -= step;
    if (std::abs(step) <= 1e-16 * std::abs(lambda)) break;
  }
#pragma omp parallel for schedule(static) if (n >= kParallelFrom)
  for (int k = 0; k < n; ++k) x[c.nodes[size_t(k)]] += lambda * grad[c.nodes[size_t(k)]];
  return lambda;
}

void project_volumes(const Model& model, std::span<Vec3> x, double load_time,
                     std::span<Vec3> scratch) {
  // Surfaces sharing nodes: all multipliers at once (coupled_volume.hpp). Where that cannot
  // be used, each projection is exact for its own surface and they disturb each other, so
  // Gauss-Seidel sweeps go on until every volume was already at its target when its
  // projection began (the cubic's constant term is that volume: the check is free).
  constexpr double kConverged = 1e-12;  // relative: 100 times below the 1e-10 promised
  constexpr int kMaxSweeps = 500;
  if (model.coupled_volumes && project_coupled_volumes(model, x, load_time, scratch)) return;
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    double worst = 0.0;
    for (const VolumeConstraint& c : model.volumes) {
      double before = 0.0;
      project_volume(c, model.inverse_mass, x, scratch, c.target_at(load_time), &before);
      worst = std::max(worst, before);
    }
    if (!model.coupled_volumes || worst <= kConverged) return;
  }
}

namespace {

// One pass of the velocity projection on one constraint. Returns the removed rate dV/dt
// relative to sum |g_i| |v_i|, for the sweeps' stopping test.
double remove_volume_rate(const VolumeConstraint& c, std::span<const Vec3> inverse_mass,
                          std::span<const Vec3> x, std::span<Vec3> v, std::span<Vec3> grad) {
  volume_gradient(c, x, grad);
  const int n = int(c.nodes.size());
  // dV/dt, g.W.g and g.g-weighted |v|
  const auto [rate, weight, speed] = ordered_sums<3>(n, [&](int k, auto& sums) {
    const int i = c.nodes[size_t(k)];
    sums[0] += grad[i].dot(v[i]);
    sums[1] += grad[i].dot(grad[i].cwiseProduct(inverse_mass[i]));
    sums[2] += grad[i].norm() * v[i].norm();
  });
  if (weight == 0.0) return 0.0;
  const double mu = rate / weight;
#pragma omp parallel for schedule(static) if (n >= kParallelFrom)
  for (int k = 0; k < n; ++k) {
    const int i = c.nodes[size_t(k)];
    v[i] -= mu * grad[i].cwiseProduct(inverse_mass[i]);
  }
  return speed > 0.0 ? std::abs(rate) / speed : 0.0;
}

}  // namespace

void project_volume_velocities(const Model& model, std::span<const Vec3> x, std::span<Vec3> v,
                               std::span<Vec3> grad) {
  // Disjoint surfaces: one pass is exact. Coupled ones: one joint solve (coupled_volume.hpp),
  // else Gauss-Seidel on the multipliers until no constraint has a rate left above round-off.
  constexpr double kConverged = 1e-12;
  constexpr int kMaxSweeps = 200;
  if (model.coupled_volumes && project_coupled_volume_velocities(model, x, v, grad)) return;
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    double worst = 0.0;
    for (const VolumeConstraint& c : model.volumes)
      worst = std::max(worst, remove_volume_rate(c, model.inverse_mass, x, v, grad));
    if (!model.coupled_volumes || worst <= kConverged) return;
  }
}

}  // namespace phymul
