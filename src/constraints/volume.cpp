#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "constraints/constraints.hpp"
#include "constraints/coupled_volume.hpp"
#include "constraints/volume_gather.hpp"
#include "constraints/volume_lanes.hpp"
#include "model/thread_team.hpp"

namespace phymul {
namespace {

// Per-node and per-triangle loops of a large surface run in parallel from this many items.
constexpr int kParallelFrom = 2048;

// N sums over [0, n), taken in a fixed number of contiguous chunks (chunk(begin, end) sums
// one) whose partial sums are added in chunk order: the same bits whatever the number of
// threads.
template <size_t N, class Chunk>
std::array<double, N> chunked_sums(int n, Chunk&& chunk) {
  constexpr int kChunks = 16;
  std::array<std::array<double, N>, kChunks> part{};
  for_each_index(kChunks, team_pays(n, kParallelFrom), [&](int c) {
    part[size_t(c)] = chunk(int(int64_t(n) * c / kChunks), int(int64_t(n) * (c + 1) / kChunks));
  });
  std::array<double, N> total{};
  for (const std::array<double, N>& p : part)
    for (size_t a = 0; a < N; ++a) total[a] += p[a];
  return total;
}

// The N sums of add(k, sums) over k in [0, n), in chunked_sums' order.
template <size_t N, class Add>
std::array<double, N> ordered_sums(int n, Add&& add) {
  return chunked_sums<N>(n, [&](int begin, int end) {
    std::array<double, N> sums{};
    for (int k = begin; k < end; ++k) add(k, sums);
    return sums;
  });
}

// Coefficients of V(x + lambda d) = c0 + c1 l + c2 l^2 + c3 l^3, exact for a triangulated
// surface since the volume is a cubic polynomial of the node positions.
std::array<double, 4> volume_cubic(const VolumeConstraint& c, std::span<const Vec3> x,
                                   std::span<const Vec3> d) {
#ifdef PHYMUL_VOLUME_AVX2
  // A triangle's vectors in one register each, its cross products in the rotated lanes
  // (z, x, y) and the products with the third corner summed lane by lane: a third of the
  // scalar instructions.
  std::array<double, 4> k = chunked_sums<4>(int(c.triangles.size()), [&](int begin, int end) {
    __m256d s0 = _mm256_setzero_pd(), s1 = s0, s2 = s0, s3 = s0;
    auto cross = [](__m256d a, __m256d b) {  // a x b in the lanes (z, x, y)
      return _mm256_fmsub_pd(a, yzx(b), _mm256_mul_pd(yzx(a), b));
    };
    for (int n = begin; n < end; ++n) {
      const Triangle& t = c.triangles[size_t(n)];
      const __m256d xa = zxy(load3(x[t[0]])), xb = load3(x[t[1]]), xc = load3(x[t[2]]);
      const __m256d da = zxy(load3(d[t[0]])), db = load3(d[t[1]]), dc = load3(d[t[2]]);
      const __m256d xbc = cross(xb, xc), dbc = cross(db, dc);
      const __m256d mixed = _mm256_add_pd(cross(db, xc), cross(xb, dc));
      s0 = _mm256_fmadd_pd(xa, xbc, s0);
      s1 = _mm256_fmadd_pd(xa, mixed, _mm256_fmadd_pd(da, xbc, s1));
      s2 = _mm256_fmadd_pd(xa, dbc, _mm256_fmadd_pd(da, mixed, s2));
      s3 = _mm256_fmadd_pd(da, dbc, s3);
    }
    return std::array<double, 4>{lane_sum(s0), lane_sum(s1), lane_sum(s2), lane_sum(s3)};
  });
#else
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
#endif
  for (double& v : k) v /= 6.0;
  return k;
}

// The triangles' scatter, for a constraint finalize did not index.
void scatter_volume_gradient(const VolumeConstraint& c, std::span<const Vec3> x,
                             std::span<Vec3> grad) {
  for (int i : c.nodes) grad[i].setZero();
  for (const Triangle& t : c.triangles) {
    const Vec3 &a = x[t[0]], &b = x[t[1]], &d = x[t[2]];
    grad[t[0]] += b.cross(d);
    grad[t[1]] += d.cross(a);
    grad[t[2]] += a.cross(b);
  }
  for (int i : c.nodes) grad[i] /= 6.0;
}

// w_i dV/dx_i into grad on the constraint's nodes: the projection's direction.
void weighted_volume_gradient(const VolumeConstraint& c, std::span<const Vec3> inverse_mass,
                              std::span<const Vec3> x, std::span<Vec3> grad) {
  const int n = int(c.nodes.size());
  const bool gather = gathered(c);
  if (!gather) scatter_volume_gradient(c, x, grad);
  const FaceGather faces(c, x);
  const int* __restrict nodes = c.nodes.data();
  Vec3* __restrict out = grad.data();
  for_each_index(n, team_pays(n, kParallelFrom), [&](int k) {
    const int i = nodes[k];
    const Vec3 g = gather ? Vec3(faces.six_gradient_at(k) / 6.0) : out[i];
    out[i] = g.cwiseProduct(inverse_mass[i]);
  });
}

}  // namespace

void volume_gradient(const VolumeConstraint& c, std::span<const Vec3> x, std::span<Vec3> grad) {
  // The factor 1/6 once per node rather than three times per triangle (a node has about six
  // triangles): 9 divisions per triangle saved; rounded once, the sum is as accurate.
  if (!gathered(c)) return scatter_volume_gradient(c, x, grad);
  const int n = int(c.nodes.size());
  for_each_index(n, team_pays(n, kParallelFrom), [&](int k) {
    grad[c.nodes[size_t(k)]] = FaceGather(c, x).six_gradient_at(k) / 6.0;
  });
}

void volume_gradient(const VolumeConstraint& c, const VolumeCache& cache, std::span<const Vec3> x,
                     std::span<Vec3> grad) {
  if (!gradient_kept_at(c, cache, x)) return volume_gradient(c, x, grad);
  for (size_t k = 0; k < c.nodes.size(); ++k) grad[size_t(c.nodes[k])] = cache.gradient[k] / 6.0;
}

namespace {

// The move along the direction d in grad (on c's nodes) that puts V at target: the root of
// the cubic V(x + lambda d) nearest to zero. Returns lambda.
double project_volume_along(const VolumeConstraint& c, std::span<Vec3> x, std::span<Vec3> grad,
                            double target, double* relative_error_before) {
  const int n = int(c.nodes.size());
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
  for_each_index(n, team_pays(n, kParallelFrom),
                 [&](int k) { x[c.nodes[size_t(k)]] += lambda * grad[c.nodes[size_t(k)]]; });
  return lambda;
}

// d = w dV/dx into grad from the gradient the last velocity projection kept (the same
// expression as weighted_volume_gradient's).
void kept_direction(const VolumeConstraint& c, const VolumeCache& cache,
                    std::span<const Vec3> inverse_mass, std::span<Vec3> grad) {
  const int n = int(c.nodes.size());
  for_each_index(n, team_pays(n, kParallelFrom), [&](int k) {
    const int i = c.nodes[size_t(k)];
    grad[i] = Vec3(cache.gradient[size_t(k)] / 6.0).cwiseProduct(inverse_mass[i]);
  });
}

}  // namespace

double project_volume(const VolumeConstraint& c, std::span<const Vec3> inverse_mass,
                      std::span<Vec3> x, std::span<Vec3> grad, double target,
                      double* relative_error_before) {
  weighted_volume_gradient(c, inverse_mass, x, grad);  // direction d
  return project_volume_along(c, x, grad, target, relative_error_before);
}

void project_volumes(const Model& model, const Controls& controls, Workspace& work,
                     std::span<Vec3> x, double load_time, std::span<Vec3> scratch,
                     std::span<const Vec3> start) {
  // Surfaces sharing nodes: all multipliers at once (coupled_volume.hpp). Where that cannot
  // be used, each projection is exact for its own surface and they disturb each other, so
  // Gauss-Seidel sweeps go on until every volume was already at its target when its
  // projection began (the cubic's constant term is that volume: the check is free).
  constexpr double kConverged = 1e-12;  // relative: 100 times below the 1e-10 promised
  constexpr int kMaxSweeps = 500;
  if (model.coupled_volumes &&
      project_coupled_volumes(model, controls, work, x, load_time, scratch))
    return;
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    double worst = 0.0;
    for (size_t k = 0; k < model.volumes.size(); ++k) {
      const VolumeConstraint& c = model.volumes[k];
      const VolumeCache& cache = work.volumes[k];
      double before = 0.0;
      const double target = target_volume(model, controls, k, load_time);
      if (!model.coupled_volumes && !start.empty() && gradient_kept_at(c, cache, start)) {
        kept_direction(c, cache, model.inverse_mass, scratch);
        project_volume_along(c, x, scratch, target, &before);
      } else {
        project_volume(c, model.inverse_mass, x, scratch, target, &before);
      }
      worst = std::max(worst, before);
    }
    if (!model.coupled_volumes || worst <= kConverged) return;
  }
}

namespace {

// One pass of the velocity projection on one constraint. Returns the removed rate dV/dt
// relative to sum |g_i| |v_i|, for the sweeps' stopping test (0 without sweeps, which need no
// square roots).
double remove_volume_rate(const VolumeConstraint& c, VolumeCache& cache,
                          std::span<const Vec3> inverse_mass, std::span<const Vec3> x,
                          std::span<Vec3> v, std::span<Vec3> grad, bool sweeps) {
  // The gradient in the sums' pass: kept from the last projection at these positions (the
  // velocities' at a step's end, the accelerations' at the next one's start), or gathered
  // from the faces and kept.
  const bool kept = gradient_kept_at(c, cache, x);
  const bool gather = !kept && gathered(c);
  const bool keep = gather && cache.gradient.size() == c.nodes.size();
  if (!kept && !gather) scatter_volume_gradient(c, x, grad);
  const FaceGather faces(c, x);
  const int n = int(c.nodes.size());
  // dV/dt, g.W.g and g.g-weighted |v|
  const auto [rate, weight, speed] = ordered_sums<3>(n, [&](int k, auto& sums) {
    const int i = c.nodes[size_t(k)];
    if (kept) {
      grad[i] = cache.gradient[size_t(k)] / 6.0;
    } else if (gather) {
      const Vec3 six = faces.six_gradient_at(k);
      grad[i] = six / 6.0;
      if (keep) cache.gradient[size_t(k)] = six, cache.gradient_at[size_t(k)] = x[size_t(i)];
    }
    sums[0] += grad[i].dot(v[i]);
    sums[1] += grad[i].dot(grad[i].cwiseProduct(inverse_mass[i]));
    if (sweeps) sums[2] += grad[i].norm() * v[i].norm();
  });
  if (weight == 0.0) return 0.0;
  const double mu = rate / weight;
  for_each_index(n, team_pays(n, kParallelFrom), [&](int k) {
    const int i = c.nodes[size_t(k)];
    v[i] -= mu * grad[i].cwiseProduct(inverse_mass[i]);
  });
  return speed > 0.0 ? std::abs(rate) / speed : 0.0;
}

}  // namespace

void project_volume_velocities(const Model& model, Workspace& work, std::span<const Vec3> x,
                               std::span<Vec3> v, std::span<Vec3> grad) {
  // Disjoint surfaces: one pass is exact. Coupled ones: one joint solve (coupled_volume.hpp),
  // else Gauss-Seidel on the multipliers until no constraint has a rate left above round-off.
  constexpr double kConverged = 1e-12;
  constexpr int kMaxSweeps = 200;
  if (model.coupled_volumes && project_coupled_volume_velocities(model, work, x, v, grad)) return;
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    double worst = 0.0;
    for (size_t k = 0; k < model.volumes.size(); ++k)
      worst =
          std::max(worst, remove_volume_rate(model.volumes[k], work.volumes[k], model.inverse_mass,
                                             x, v, grad, model.coupled_volumes));
    if (!model.coupled_volumes || worst <= kConverged) return;
  }
}

}  // namespace phymul
