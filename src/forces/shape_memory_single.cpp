#include "forces/shape_memory_single.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "forces/shape_memory.hpp"
#include "forces/shape_memory_batch.hpp"
#include "phymul/parallel_plan.hpp"

#if defined(__AVX__)
#include <immintrin.h>
#endif

#include "forces/lane_algebra.hpp"

namespace phymul {
namespace {

constexpr int W = kShapeMemorySingleLanes;
static_assert(W == 8, "the transposes below spell out eight lanes");
constexpr int kMaxNeighbours = kShapeMemoryMaxBatchedNeighbours;

// GCC/Clang vector extensions, as in shape_memory_batch.cpp: eight float lanes, one AVX
// instruction an operation with -march=native.
using F = float __attribute__((vector_size(W * sizeof(float))));
using Mask = int __attribute__((vector_size(W * sizeof(int))));
using Row = double __attribute__((vector_size(4 * sizeof(double))));  // (x, y, z, *), double

using V3 = lanes::V3<F>;
using M3 = lanes::M3<F>;
using Q = lanes::Q<F>;
using Sym3 = lanes::Sym3<F>;

PHYMUL_LANES F splat(float s) { return F{} + s; }
PHYMUL_LANES F lane_sqrt(const F& v) {
#if defined(__AVX__)
  return _mm256_sqrt_ps(v);
#else
  F r;
  for (int l = 0; l < W; ++l) r[l] = std::sqrt(v[l]);
  return r;
#endif
}
PHYMUL_LANES int sign_bits(const Mask& m) {
#if defined(__AVX__)
  return _mm256_movemask_ps(__m256(m));
#else
  int bits = 0;
  for (int l = 0; l < W; ++l) bits |= m[l] ? 1 << l : 0;
  return bits;
#endif
}
PHYMUL_LANES bool any(const Mask& m) { return sign_bits(m) != 0; }
PHYMUL_LANES bool all(const Mask& m) { return sign_bits(m) == (1 << W) - 1; }

// (p[0], p[1], p[2], 0): one point, without reading past it (the last node of x, say).
PHYMUL_LANES Row load3(const double* p) {
#if defined(__AVX__)
  return _mm256_maskload_pd(p, _mm256_set_epi64x(0, -1, -1, -1));
#else
  return Row{p[0], p[1], p[2], 0.0};
#endif
}

#if defined(__AVX__)
// Eight rows (x, y, z, w) of floats as the lane vectors of their x, y, z and w.
PHYMUL_LANES void transpose_rows(const __m128* row, F* out, int columns) {
  const __m256 t0 = _mm256_set_m128(row[4], row[0]), t1 = _mm256_set_m128(row[5], row[1]);
  const __m256 t2 = _mm256_set_m128(row[6], row[2]), t3 = _mm256_set_m128(row[7], row[3]);
  const __m256 a = _mm256_unpacklo_ps(t0, t1), b = _mm256_unpacklo_ps(t2, t3);  // x x y y
  const __m256 c = _mm256_unpackhi_ps(t0, t1), d = _mm256_unpackhi_ps(t2, t3);  // z z w w
  out[0] = _mm256_shuffle_ps(a, b, _MM_SHUFFLE(1, 0, 1, 0));
  out[1] = _mm256_shuffle_ps(a, b, _MM_SHUFFLE(3, 2, 3, 2));
  out[2] = _mm256_shuffle_ps(c, d, _MM_SHUFFLE(1, 0, 1, 0));
  if (columns == 4) out[3] = _mm256_shuffle_ps(c, d, _MM_SHUFFLE(3, 2, 3, 2));
}
#endif

// The offsets p[id[l]] - origin[l], taken in double, then rounded: the lanes never see an
// absolute position.
PHYMUL_LANES V3 gather_offsets(const double* p, const int* id, const Row* origin) {
  V3 u;
#if defined(__AVX__)
  __m128 row[W];
  for (int l = 0; l < W; ++l) row[l] = _mm256_cvtpd_ps(load3(p + 3 * id[l]) - origin[l]);
  transpose_rows(row, u.v, 3);
#else
  for (int l = 0; l < W; ++l)
    for (int a = 0; a < 3; ++a) u.v[a][l] = float(p[3 * id[l] + a] - origin[l][a]);
#endif
  return u;
}

// Lane l of u as the double row (x, y, z, 0) at rows[l * stride] (transpose_rows' inverse).
PHYMUL_LANES void store_rows(const V3& u, Row* rows, int stride) {
#if defined(__AVX__)
  const __m256 zero = _mm256_setzero_ps();
  const __m256 xy_lo = _mm256_unpacklo_ps(u.v[0], u.v[1]);  // x0 y0 x1 y1 | x4 y4 x5 y5
  const __m256 xy_hi = _mm256_unpackhi_ps(u.v[0], u.v[1]);  // x2 y2 x3 y3 | x6 y6 x7 y7
  const __m256 z_lo = _mm256_unpacklo_ps(u.v[2], zero), z_hi = _mm256_unpackhi_ps(u.v[2], zero);
  const __m256 r[4] = {_mm256_shuffle_ps(xy_lo, z_lo, _MM_SHUFFLE(1, 0, 1, 0)),
                       _mm256_shuffle_ps(xy_lo, z_lo, _MM_SHUFFLE(3, 2, 3, 2)),
                       _mm256_shuffle_ps(xy_hi, z_hi, _MM_SHUFFLE(1, 0, 1, 0)),
                       _mm256_shuffle_ps(xy_hi, z_hi, _MM_SHUFFLE(3, 2, 3, 2))};
  for (int l = 0; l < 4; ++l) {  // r[l] holds lanes l and l + 4
    rows[l * stride] = _mm256_cvtps_pd(_mm256_castps256_ps128(r[l]));
    rows[(l + 4) * stride] = _mm256_cvtps_pd(_mm256_extractf128_ps(r[l], 1));
  }
#else
  for (int l = 0; l < W; ++l) rows[l * stride] = Row{u.v[0][l], u.v[1][l], u.v[2][l], 0.0};
#endif
}

// p[0..2] -= row[0..2], by a pair and a single (see shape_memory_batch.cpp's subtract3).
PHYMUL_LANES void subtract3(double* p, const double* row) {
  using Pair = double __attribute__((vector_size(2 * sizeof(double))));
  Pair xy, r;
  std::memcpy(&xy, p, sizeof xy);
  std::memcpy(&r, row, sizeof r);
  xy -= r;
  std::memcpy(p, &xy, sizeof xy);
  p[2] -= row[2];
}

// The rotations q[l] (Eigen's x, y, z, w), rounded.
PHYMUL_LANES Q load_rotations(std::span<const Eigen::Quaterniond> rotations, const int* ks) {
  F c[4];
#if defined(__AVX__)
  __m128 row[W];
  for (int l = 0; l < W; ++l)
    row[l] = _mm256_cvtpd_ps(_mm256_loadu_pd(rotations[ks[l]].coeffs().data()));
  transpose_rows(row, c, 4);
#else
  for (int l = 0; l < W; ++l)
    for (int a = 0; a < 4; ++a) c[a][l] = float(rotations[ks[l]].coeffs()[a]);
#endif
  return {c[3], c[0], c[1], c[2]};
}

// The float adjugate's determinant carries a round-off of a few eps scale^3 (eps = 6e-8): a
// floor of 1e-3 scale^3 (the double kernel's is 1e-6) keeps its relative error, and that of
// the reactions' mu, below about 1e-4; rarer, flatter Hessians go the double way.
constexpr float kSingleDeterminantFloor = 1e-3f;

PHYMUL_LANES Mask solve_positive_definite(const Sym3& M, const V3& b, V3& y) {
  const F c00 = M.m11 * M.m22 - M.m12 * M.m12;
  const F c01 = M.m02 * M.m12 - M.m01 * M.m22;
  const F c02 = M.m01 * M.m12 - M.m02 * M.m11;
  const F det = M.m00 * c00 + M.m01 * c01 + M.m02 * c02;
  const F scale = (M.m00 + M.m11 + M.m22) * (1.0f / 3.0f);
  const Mask ok = (M.m00 > 0.0f) & (M.m00 * M.m11 > M.m01 * M.m01) &
                  (det > kSingleDeterminantFloor * scale * scale * scale);
  const F c11 = M.m00 * M.m22 - M.m02 * M.m02;
  const F c12 = M.m01 * M.m02 - M.m00 * M.m12;
  const F c22 = M.m00 * M.m11 - M.m01 * M.m01;
  const F inverse = 1.0f / det;
  y = V3{{c00 * b.v[0] + c01 * b.v[1] + c02 * b.v[2], c01 * b.v[0] + c11 * b.v[1] + c12 * b.v[2],
          c02 * b.v[0] + c12 * b.v[1] + c22 * b.v[2]}} *
      inverse;
  return ok;
}

// q turned by the body-frame rotation vector 2 half. Below 1e-3 rad the unnormalised (1, half)
// turns by it to |half|^2 / 3 < eps relative; above, up to 0.1 rad, (cos |half|, sin |half|
// half / |half|) from their Taylor series (to 1e-11). One Newton step for 1/|q| renormalises.
PHYMUL_LANES Q turn(const Q& q, const V3& half) {
  const F h2 = dot(half, half);
  const Mask small = 4.0f * h2 < 1e-6f;
  F rw = splat(1.0f), scale = splat(1.0f);
  if (!all(small)) {
    const F cos_half =
        1.0f - h2 * 0.5f * (1.0f - h2 * (1.0f / 12.0f) * (1.0f - h2 * (1.0f / 30.0f)));
    const F sinc_half = 1.0f - h2 * (1.0f / 6.0f) * (1.0f - h2 * (1.0f / 20.0f));
    rw = small ? rw : cos_half;
    scale = small ? scale : sinc_half;
  }
  const F hx = half.v[0] * scale, hy = half.v[1] * scale, hz = half.v[2] * scale;
  Q t{q.w * rw - (q.x * hx + q.y * hy + q.z * hz), q.w * hx + q.x * rw + (q.y * hz - q.z * hy),
      q.w * hy + q.y * rw + (q.z * hx - q.x * hz), q.w * hz + q.z * rw + (q.x * hy - q.y * hx)};
  const F s = 1.5f - 0.5f * (t.w * t.w + t.x * t.x + t.y * t.y + t.z * t.z);
  return {t.w * s, t.x * s, t.y * s, t.z * s};
}

// The fit of W neighbourhoods about their nodes: offsets d_j = x_j - x_i, r_j = X_j - X_i.
// The pull is a - x_i = mean(d) + R c with c = X_i - G0 = -mean(r): no absolute position.
struct LaneFit {
  V3 mean_d, mean_r;
  // (sum (x_j - g)(X_j - G0)^T + the normal pair) / sum |X_j - X_i|^2: the rotation and the
  // reaction's solve do not depend on A's scale, and at O(1) the Hessian's determinant (A^3)
  // neither underflows float on micrometre cells nor overflows it on large ones.
  M3 A;
  F scale;  // 1 / sum |X_j - X_i|^2, 1/m^2
  F count;
};

// The normal pair (shape_memory_batch.cpp's LaneNormal and add_normal_pair).
struct LaneNormal {
  V3 unit_normal, rest_normal;
  F normal_length, weight;
  V3 pair_offset[2];
  std::array<int, 2> pair[W];
};

PHYMUL_LANES void add_normal_pair(const ShapeMemory& m, const int* ks, int n, const V3* dx,
                                  const V3* r, LaneFit& fit, LaneNormal& normal) {
  const V3 mean_d = fit.mean_d, mean_r = fit.mean_r;
  V3 N{}, N0{};
  if (m.surface) {
    const V3 first = dx[0] - mean_d, first0 = r[0] - mean_r;
    V3 a = first, a0 = first0;
    for (int j = 0; j + 1 < n; ++j) {
      const V3 b = dx[j + 1] - mean_d, b0 = r[j + 1] - mean_r;
      N = N + cross(a, b);
      N0 = N0 + cross(a0, b0);
      a = b;
      a0 = b0;
    }
    if (n > 2) {
      N = N + cross(a, first);
      N0 = N0 + cross(a0, first0);
    }
  } else {
    V3 rest_offset[2];
    for (int l = 0; l < W; ++l) {
      normal.pair[l] = m.frame_pair[size_t(m.framed.find(ks[l]))];
      for (int e = 0; e < 2; ++e)
        for (int a = 0; a < 3; ++a) {
          normal.pair_offset[e].v[a][l] = dx[normal.pair[l][e]].v[a][l];
          rest_offset[e].v[a][l] = r[normal.pair[l][e]].v[a][l];
        }
    }
    for (int e = 0; e < 2; ++e) {
      normal.pair_offset[e] = normal.pair_offset[e] - mean_d;
      rest_offset[e] = rest_offset[e] - mean_r;
    }
    N = cross(normal.pair_offset[0], normal.pair_offset[1]);
    N0 = cross(rest_offset[0], rest_offset[1]);
  }
  normal.normal_length = lane_sqrt(dot(N, N));
  normal.unit_normal = N * (1.0f / normal.normal_length);
  normal.rest_normal = N0 * (1.0f / lane_sqrt(dot(N0, N0)));
  for (int l = 0; l < W; ++l)
    normal.weight[l] = float(m.normal_weight[size_t(m.framed.find(ks[l]))]);
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      fit.A.a[a][b] += normal.weight * normal.unit_normal.v[a] * normal.rest_normal.v[b];
}

PHYMUL_LANES V3 normal_gradient(const LaneNormal& normal, const M3& R, const V3& half_mu) {
  const V3 h = times(R, cross(half_mu, normal.rest_normal)) * normal.weight;
  return (h - normal.unit_normal * dot(normal.unit_normal, h)) * (1.0f / normal.normal_length);
}

PHYMUL_LANES void add_pair_normal_reaction(int n, const LaneFit& fit, const LaneNormal& normal,
                                           const V3& hp, V3* r) {
  const V3 ga = cross(normal.pair_offset[1], hp), gb = cross(hp, normal.pair_offset[0]);
  const V3 through_centroid = (ga + gb) * (1.0f / fit.count);
  for (int j = 0; j < n; ++j) r[j] = r[j] - through_centroid;
  for (int l = 0; l < W; ++l)
    for (int a = 0; a < 3; ++a) {
      r[normal.pair[l][0]].v[a][l] += ga.v[a][l];
      r[normal.pair[l][1]].v[a][l] += gb.v[a][l];
    }
}

struct Batch {
  int ks[W];  // lanes past `used` repeat the last node; they are computed, never written
  int used;
  int n;
  int node[W];
  const int* nb[W];
  bool normal_pair;
  LaneFit fit;
  LaneNormal normal;
  V3 r[kMaxNeighbours];   // X_j - X_i, later the neighbours' reactions
  V3 dx[kMaxNeighbours];  // x_j - x_i
  Q q;
  Mask active, failed;
};

void fit_batch(const ShapeMemory& m, const int* ks, int used, std::span<const Vec3> rest,
               std::span<const Vec3> x, std::span<const Eigen::Quaterniond> rotations, Batch& b) {
  b.used = used;
  for (int l = 0; l < W; ++l) b.ks[l] = ks[std::min(l, used - 1)];
  const int n = b.n = int(m.neighbours.row(ks[0]).size());
  const double *xs = x.data()->data(), *rests = rest.data()->data();
  Row xi[W], Xi[W];
  for (int l = 0; l < W; ++l) {
    b.node[l] = m.nodes[b.ks[l]];
    b.nb[l] = m.neighbours.row(b.ks[l]).data();
    xi[l] = load3(xs + 3 * b.node[l]);
    Xi[l] = load3(rests + 3 * b.node[l]);
  }
  F sdx{}, sdy{}, sdz{}, srx{}, sry{}, srz{};
  for (int j = 0; j < n; ++j) {
    int id[W];
    for (int l = 0; l < W; ++l) id[l] = b.nb[l][j];
    const V3 d = gather_offsets(xs, id, xi), rj = gather_offsets(rests, id, Xi);
    b.dx[j] = d;
    b.r[j] = rj;
    sdx += d.v[0], sdy += d.v[1], sdz += d.v[2];
    srx += rj.v[0], sry += rj.v[1], srz += rj.v[2];
  }
  LaneFit& fit = b.fit;
  M3 P{};
  F rest_square{};
  for (int j = 0; j < n; ++j) {
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c) P.a[a][c] += b.dx[j].v[a] * b.r[j].v[c];
    rest_square += dot(b.r[j], b.r[j]);
  }
  fit.count = splat(float(n));
  const F inverse_count = splat(1.0f / float(n));
  const V3 sum_d{{sdx, sdy, sdz}};
  fit.mean_d = sum_d * inverse_count;
  fit.mean_r = V3{{srx, sry, srz}} * inverse_count;
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 3; ++c) fit.A.a[a][c] = P.a[a][c] - sum_d.v[a] * fit.mean_r.v[c];
  b.normal_pair = m.framed.find(ks[0]) >= 0;
  if (b.normal_pair) add_normal_pair(m, b.ks, n, b.dx, b.r, fit, b.normal);
  fit.scale = 1.0f / rest_square;
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 3; ++c) fit.A.a[a][c] *= fit.scale;
  b.q = load_rotations(rotations, b.ks);
  b.active = Mask{} == 0;
  b.failed = Mask{};
}

// Newton turns as the double kernel's, settled once a turn is below 1e-4 rad: the next, of
// about its square, would sit under the float rotation's own round-off (eps = 6e-8). A turn
// of 0.1 rad or more, a Hessian not safely positive definite, or more than kMaxTurns turns
// (the float noise of an ill-conditioned fit never settling) sends the lane the double way.
constexpr int kMaxTurns = 6;
constexpr float kSettledAngle2 = 1e-8f;  // rad^2

PHYMUL_LANES void newton_turn(const M3& A, Q& q, Mask& active, Mask& failed) {
  const M3 S = transpose_times(rotation_matrix(q), A);
  V3 half;
  const Mask newton = solve_positive_definite(rotation_hessian(S), axial_of_skew(S), half);
  const F angle2 = 4.0f * dot(half, half);
  const Mask bad = active & ~(newton & (angle2 < 1e-2f));
  failed |= bad;
  active &= ~bad;
  const Mask move = active & (angle2 != 0.0f);
  const Q turned = turn(q, half);
  q = Q{move ? turned.w : q.w, move ? turned.x : q.x, move ? turned.y : q.y, move ? turned.z : q.z};
  active &= ~(angle2 < kSettledAngle2);
}

void settle_rotations(Batch& b) {
  Q q = b.q;
  for (int it = 0; it < kMaxTurns && any(b.active); ++it)
    newton_turn(b.fit.A, q, b.active, b.failed);
  b.q = q;
}

// Two batches' turns side by side: each turn is a chain of dependent operations, two keep the
// floating-point units busier (as the double kernel's pairs).
void settle_rotations(Batch& a, Batch& b) {
  Q qa = a.q, qb = b.q;
  for (int it = 0; it < kMaxTurns && any(a.active | b.active); ++it) {
    newton_turn(a.fit.A, qa, a.active, a.failed);
    newton_turn(b.fit.A, qb, b.active, b.failed);
  }
  a.q = qa;
  b.q = qb;
}

// The pull, its exact reaction and their scatter, lane by lane in their order; lanes that did
// not settle redo their node on the double scalar path.
double add_batch_forces(const ShapeMemory& m, Batch& b, std::span<const Vec3> rest,
                        std::span<const Vec3> x, std::span<Eigen::Quaterniond> rotations,
                        std::span<Vec3> f, std::array<bool, W>* batched) {
  const int n = b.n;
  const LaneFit& fit = b.fit;
  const Q& q = b.q;
  Mask ok = ~(b.failed | b.active);
  const M3 R = rotation_matrix(q);

  const F stiffness = splat(float(m.stiffness));
  const V3 pull = fit.mean_d - times(R, fit.mean_r);  // g + R c - x_i
  const V3 fi = pull * stiffness;
  const F energy = 0.5f * stiffness * dot(pull, pull);
  Row reaction[W][kMaxNeighbours];
  Row pulled[W];
  store_rows(fi, pulled, 1);
  if (m.reaction) {
    // As the double kernel: neighbour j gets -(f_i / n + R (mu x (X_j - G0)) / 2),
    // mu = 2 H^-1 K (c x R^T pull), c = -mean(r).
    V3 half_mu;
    ok &= solve_positive_definite(
        rotation_hessian(transpose_times(R, fit.A)),
        cross(transpose_times(R, pull), fit.mean_r) * (stiffness * fit.scale), half_mu);
    const V3 share = fi * (1.0f / fit.count);
    auto reaction_on = [&](int j) { return share + times(R, cross(half_mu, b.r[j] - fit.mean_r)); };
    if (!b.normal_pair) {
      for (int j = 0; j < n; ++j) store_rows(reaction_on(j), &reaction[0][j], kMaxNeighbours);
    } else if (m.surface) {
      const V3 hp = normal_gradient(b.normal, R, half_mu);
      for (int j = 0; j < n; ++j) {
        const int next = j + 1 == n ? 0 : j + 1, previous = j == 0 ? n - 1 : j - 1;
        store_rows(reaction_on(j) + cross(b.dx[next] - b.dx[previous], hp), &reaction[0][j],
                   kMaxNeighbours);
      }
    } else {
      for (int j = 0; j < n; ++j) b.r[j] = reaction_on(j);
      add_pair_normal_reaction(n, fit, b.normal, normal_gradient(b.normal, R, half_mu), b.r);
      for (int j = 0; j < n; ++j) store_rows(b.r[j], &reaction[0][j], kMaxNeighbours);
    }
  }

  double total = 0.0;
  double* const forces = f.data()->data();
  for (int l = 0; l < b.used; ++l) {
    if (batched) (*batched)[size_t(l)] = ok[l] != 0;
    if (!ok[l]) {
      total += add_polar_node_forces(m, b.ks[l], rest, x, rotations, f);
      continue;
    }
    // Rounded to float, |q| is 1 to about eps: one Newton step in double makes it 1 again.
    Eigen::Quaterniond& r = rotations[b.ks[l]];
    r = Eigen::Quaterniond(q.w[l], q.x[l], q.y[l], q.z[l]);
    r.coeffs() *= 1.5 - 0.5 * r.squaredNorm();
    f[b.node[l]] += Vec3(pulled[l][0], pulled[l][1], pulled[l][2]);
    if (m.reaction)
      for (int j = 0; j < n; ++j)
        subtract3(forces + 3 * b.nb[l][j], reinterpret_cast<const double*>(&reaction[l][j]));
    total += double(energy[l]);
  }
  if (batched)
    for (int l = b.used; l < W; ++l) (*batched)[size_t(l)] = false;
  return total;
}

}  // namespace

double add_polar_batch_forces_single(const ShapeMemory& m, const int* ks, int used,
                                     std::span<const Vec3> rest, std::span<const Vec3> x,
                                     std::span<Eigen::Quaterniond> rotations, std::span<Vec3> f,
                                     std::array<bool, W>* batched) {
  Batch b;
  fit_batch(m, ks, used, rest, x, rotations, b);
  settle_rotations(b);
  return add_batch_forces(m, b, rest, x, rotations, f, batched);
}

namespace {

// Batches ks[0, W) then ks[W, 2 W), as two calls of add_polar_batch_forces_single.
double add_polar_batch_pair_forces_single(const ShapeMemory& m, const int* ks,
                                          std::span<const Vec3> rest, std::span<const Vec3> x,
                                          std::span<Eigen::Quaterniond> rotations,
                                          std::span<Vec3> f) {
  Batch a, b;
  fit_batch(m, ks, W, rest, x, rotations, a);
  fit_batch(m, ks + W, W, rest, x, rotations, b);
  settle_rotations(a, b);
  const double energy = add_batch_forces(m, a, rest, x, rotations, f, nullptr);
  return energy + add_batch_forces(m, b, rest, x, rotations, f, nullptr);
}

}  // namespace

double add_shape_memory_forces_single(const ShapeMemory& m, std::span<const Vec3> rest,
                                      std::span<const Vec3> x,
                                      std::span<Eigen::Quaterniond> rotations, std::span<Vec3> f) {
  if (m.frame != FrameMode::polar || !polar_batches_planned(m))
    return add_shape_memory_forces(m, rest, x, rotations, f);
  // Lanes share their neighbour count and whether they carry the normal pair (as
  // plan_polar_batches groups them).
  auto kind = [&m](int k) {
    return 2 * int(m.neighbours.row(k).size()) + (m.framed.find(k) >= 0 ? 1 : 0);
  };
  return run_coloured_blocks(m.plan, [&](int block) {
    double energy = 0.0;
    const int batched = m.batched_end[block], centred = m.centred_start[block],
              end = m.plan.block_start[block + 1];
    int p = m.plan.block_start[block];
    // Two full batches of one kind side by side, their turns interleaved.
    while (p + 2 * W <= batched &&
           kind(m.batch_order[size_t(p)]) == kind(m.batch_order[size_t(p + 2 * W - 1)])) {
      energy +=
          add_polar_batch_pair_forces_single(m, m.batch_order.data() + p, rest, x, rotations, f);
      p += 2 * W;
    }
    while (p < batched) {
      const int* ks = m.batch_order.data() + p;
      const int used = p + W <= batched && kind(ks[0]) == kind(ks[W - 1]) ? W : kShapeMemoryLanes;
      energy += add_polar_batch_forces_single(m, ks, used, rest, x, rotations, f);
      p += used;
    }
    for (; p < centred; ++p)
      energy += add_polar_node_forces(m, m.batch_order[size_t(p)], rest, x, rotations, f);
    return energy + add_centred_forces(m, m.batch_order.data() + p, end - p, x, f);
  });
}

}  // namespace phymul
