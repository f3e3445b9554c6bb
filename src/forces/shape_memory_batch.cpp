#include "forces/shape_memory_batch.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <vector>

#if defined(__AVX__)
#include <immintrin.h>
#endif

#include "forces/lane_io.hpp"

namespace phymul {
namespace {

using namespace lanes;  // D, Mask and their loads and stores (forces/lane_io.hpp)
static_assert(W == kShapeMemoryLanes, "the lanes are the batches' memory nodes");
using V3 = lanes::V3<D>;
using M3 = lanes::M3<D>;
using Q = lanes::Q<D>;
using Sym3 = lanes::Sym3<D>;

// shape_memory.cpp's solve_positive_definite: the lanes where M is safely positive definite
// get y = M^-1 b; the mask says which.
PHYMUL_LANES Mask solve_positive_definite(const Sym3& M, const V3& b, V3& y) {
  const D c00 = M.m11 * M.m22 - M.m12 * M.m12;
  const D c01 = M.m02 * M.m12 - M.m01 * M.m22;
  const D c02 = M.m01 * M.m12 - M.m02 * M.m11;
  const D det = M.m00 * c00 + M.m01 * c01 + M.m02 * c02;
  const D scale = (M.m00 + M.m11 + M.m22) / 3.0;
  const Mask ok =
      (M.m00 > 0.0) & (M.m00 * M.m11 > M.m01 * M.m01) & (det > 1e-6 * scale * scale * scale);
  const D c11 = M.m00 * M.m22 - M.m02 * M.m02;
  const D c12 = M.m01 * M.m02 - M.m00 * M.m12;
  const D c22 = M.m00 * M.m11 - M.m01 * M.m01;
  const D inverse = 1.0 / det;
  y = V3{{c00 * b.v[0] + c01 * b.v[1] + c02 * b.v[2], c01 * b.v[0] + c11 * b.v[1] + c12 * b.v[2],
          c02 * b.v[0] + c12 * b.v[1] + c22 * b.v[2]}} *
      inverse;
  return ok;
}

// q turned by the body-frame rotation vector theta (half = theta / 2), as shape_memory.cpp's
// turn: below 1e-4 rad by the unnormalised quaternion (1, half); above, up to 0.1 rad, by
// (cos |half|, sin |half| half / |half|) from their Taylor series (to 1e-20 there), instead of
// a sqrt, a division and trigonometry. Then one Newton step for 1/|q| near 1 renormalises.
PHYMUL_LANES Q turn(const Q& q, const V3& half) {
  const D h2 = dot(half, half);
  const Mask small = 4.0 * h2 < 1e-8;
  D rw = splat(1.0), scale = splat(1.0);
  if (!all(small)) {  // a step's turns are nearly all small: no divisions on their path
    const D cos_half = 1.0 - h2 / 2.0 * (1.0 - h2 / 12.0 * (1.0 - h2 / 30.0 * (1.0 - h2 / 56.0)));
    const D sinc_half = 1.0 - h2 / 6.0 * (1.0 - h2 / 20.0 * (1.0 - h2 / 42.0 * (1.0 - h2 / 72.0)));
    rw = small ? rw : cos_half;
    scale = small ? scale : sinc_half;
  }
#if defined(__AVX__)
  // Hidden from the optimiser, the ones of small turns multiply as the series' values do: GCC
  // contracts the products below into the same fused multiply-adds either way (with known
  // ones it would fold them and round the quaternion differently).
  asm("" : "+x"(rw), "+x"(scale));
#endif
  const D hx = half.v[0] * scale, hy = half.v[1] * scale, hz = half.v[2] * scale;
  Q t{q.w * rw - (q.x * hx + q.y * hy + q.z * hz), q.w * hx + q.x * rw + (q.y * hz - q.z * hy),
      q.w * hy + q.y * rw + (q.z * hx - q.x * hz), q.w * hz + q.z * rw + (q.x * hy - q.y * hx)};
  const D s = 1.5 - 0.5 * (t.w * t.w + t.x * t.x + t.y * t.y + t.z * t.z);
  return {t.w * s, t.x * s, t.y * s, t.z * s};
}

}  // namespace

namespace {

// N > 0: the loops unrolled for that neighbour count (a regular grid's 6); 0: any count.
template <int N>
double centred_node_forces(const ShapeMemory& m, int k, std::span<const Vec3> x,
                           std::span<Vec3> f) {
  // A node's x, y, z in one register (lane 3 zero): a handful of instructions a neighbour.
  const auto row = m.neighbours.row(k);
  const int* nb = row.data();
  const int count = N > 0 ? N : int(row.size());
  const double* p = x.data()->data();
  double* forces = f.data()->data();
  const int i = m.nodes[k];
  const D xi = load3(p + 3 * i);
  D sum{};
  for (int j = 0; j < count; ++j)
    sum += load3(p + 3 * nb[j]) - xi;  // offsets, as the fit's: exact far out too
  const D n = splat(double(count));
  const D pull = sum / n;
  const D fi = splat(m.stiffness) * pull;
  D row_of[1] = {-fi};
  subtract3(forces + 3 * i, reinterpret_cast<const double*>(row_of));
  if (m.reaction) {
    row_of[0] = fi / n;
    for (int j = 0; j < count; ++j)
      subtract3(forces + 3 * nb[j], reinterpret_cast<const double*>(row_of));
  }
  return 0.5 * m.stiffness * (pull[0] * pull[0] + pull[1] * pull[1] + pull[2] * pull[2]);
}

}  // namespace

double add_centred_node_forces(const ShapeMemory& m, int k, std::span<const Vec3> x,
                               std::span<Vec3> f) {
  return m.neighbours.row(k).size() == 6 ? centred_node_forces<6>(m, k, x, f)
                                         : centred_node_forces<0>(m, k, x, f);
}

namespace {

// Centred nodes whose global ids run from first to first + count - 1, on the stencil: in
// chunks of 64 nodes, the pulls, own forces and reactions of a whole chunk coordinate by
// coordinate (x, y, z of node after node: the same offsets for all three).
double stencil_run_forces(const ShapeMemory& m, int first, int count, std::span<const Vec3> x,
                          std::span<Vec3> f) {
  constexpr int kChunk = 64, kNeighbours = 6;
  std::array<int, kNeighbours> offset;
  for (int o = 0; o < kNeighbours; ++o) offset[size_t(o)] = 3 * m.centred_stencil[size_t(o)];
  const double stiffness = m.stiffness;
  // W coordinates at a time in the lanes, the chunk's last few one by one: which ones is
  // fixed by the plan, so the thread count changes no bit. (A plain loop would not do: its
  // sum of squares, in order, keeps the compiler from the lanes.)
  auto load = [](const double* q) {
    D v;
    std::memcpy(&v, q, sizeof v);
    return v;
  };
  auto store = [](double* q, const D& v) { std::memcpy(q, &v, sizeof v); };
  D squares{};
  double rest_squares = 0.0;
  for (int begin = 0; begin < count; begin += kChunk) {
    const int elements = 3 * std::min(kChunk, count - begin);
    const double* __restrict p = x.data()->data() + 3 * (first + begin);
    double* __restrict forces = f.data()->data() + 3 * (first + begin);
    double share[3 * kChunk];
    int e = 0;
    for (; e + W <= elements; e += W) {
      const D xe = load(p + e);
      D sum{};
      for (int o = 0; o < kNeighbours; ++o) sum += load(p + e + offset[size_t(o)]) - xe;
      const D pull = sum / double(kNeighbours);
      squares += pull * pull;
      const D fi = stiffness * pull;
      store(forces + e, load(forces + e) + fi);
      store(share + e, fi / double(kNeighbours));
    }
    for (; e < elements; ++e) {
      double sum = 0.0;
      for (int o = 0; o < kNeighbours; ++o) sum += p[e + offset[size_t(o)]] - p[e];
      const double pull = sum / double(kNeighbours);
      rest_squares += pull * pull;
      const double fi = stiffness * pull;
      forces[e] += fi;
      share[e] = fi / double(kNeighbours);
    }
    if (!m.reaction) continue;
    for (int o = 0; o < kNeighbours; ++o) {
      double* __restrict to = forces + offset[size_t(o)];
      for (int k = 0; k < elements; ++k) to[k] -= share[k];
    }
  }
  return 0.5 * stiffness * (((squares[0] + squares[1]) + (squares[2] + squares[3])) + rest_squares);
}

}  // namespace

double add_centred_forces(const ShapeMemory& m, const int* ks, int count, std::span<const Vec3> x,
                          std::span<Vec3> f) {
  double energy = 0.0;
  if (!m.centred_on_stencil) {
    for (int p = 0; p < count; ++p) energy += add_centred_node_forces(m, ks[p], x, f);
    return energy;
  }
  for (int begin = 0; begin < count;) {
    int end = begin + 1;
    while (end < count && m.nodes[ks[end]] == m.nodes[ks[end - 1]] + 1) ++end;
    energy += stencil_run_forces(m, m.nodes[ks[begin]], end - begin, x, f);
    begin = end;
  }
  return energy;
}

namespace {

// The fit of W neighbourhoods, as fit_neighbourhood: about the node itself, in one pass.
struct LaneFit {
  V3 xi, g, mean_r, c, sum_d;
  M3 A;
  D count;
};

// The normal pair, A += w N/|N| n0^T, N and n0 the current and rest normals about the centroid:
// of the ordered ring on a surface (shape_memory.cpp's ring_normal), of the frame pair of a flat
// interior neighbourhood, a box's corner (pair_normal).
struct LaneNormal {
  V3 unit_normal, rest_normal;
  D normal_length, weight;
  V3 pair_offset[2];           // x_a - g, x_b - g for the pair (a, b)
  std::array<int, 2> pair[W];  // positions of a and b in each lane's row
};

PHYMUL_LANES void add_normal_pair(const ShapeMemory& m, const std::array<int, W>& ks, int n,
                                  const V3* dx, const V3* r, LaneFit& fit, LaneNormal& normal) {
  const V3 mean_d = fit.sum_d / fit.count, mean_r = fit.mean_r;
  V3 N{}, N0{};
  if (m.surface) {  // each offset about the centroid computed once, carried to the next pair
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
  normal.unit_normal = N / normal.normal_length;
  normal.rest_normal = N0 / lane_sqrt(dot(N0, N0));
  for (int l = 0; l < W; ++l) normal.weight[l] = m.normal_weight[size_t(m.framed.find(ks[l]))];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      fit.A.a[a][b] += normal.weight * normal.unit_normal.v[a] * normal.rest_normal.v[b];
}

// The normal pair's part of the reactions: dE = hp'.dN, N the unnormalised normal.
PHYMUL_LANES V3 normal_gradient(const LaneNormal& normal, const M3& R, const V3& half_mu) {
  const V3 h = times(R, cross(half_mu, normal.rest_normal)) * normal.weight;
  return (h - normal.unit_normal * dot(normal.unit_normal, h)) / normal.normal_length;
}

// A flat interior neighbourhood's: N = (x_a - g) x (x_b - g), on a and b, and every neighbour
// through g, added to the neighbours' reactions r.
PHYMUL_LANES void add_pair_normal_reaction(int n, const LaneFit& fit, const LaneNormal& normal,
                                           const V3& hp, V3* r) {
  const V3 ga = cross(normal.pair_offset[1], hp), gb = cross(hp, normal.pair_offset[0]);
  const V3 through_centroid = (ga + gb) / fit.count;
  for (int j = 0; j < n; ++j) r[j] = r[j] - through_centroid;
  for (int l = 0; l < W; ++l)
    for (int a = 0; a < 3; ++a) {
      r[normal.pair[l][0]].v[a][l] += ga.v[a][l];
      r[normal.pair[l][1]].v[a][l] += gb.v[a][l];
    }
}

// One batch between its phases: the fit, the rotation's Newton turns, the forces.
struct Batch {
  std::array<int, W> ks;
  int n;
  int node[W];
  const int* nb[W];
  bool normal_pair;
  LaneFit fit;
  LaneNormal normal;
  V3 r[kShapeMemoryMaxBatchedNeighbours];   // X_j - X_i, later the neighbours' reactions
  V3 dx[kShapeMemoryMaxBatchedNeighbours];  // x_j - x_i
  Q q;                                      // warm start, then the settled rotation
  Mask active, failed;                      // lanes still turning, lanes for the scalar path
};

void fit_batch(const ShapeMemory& m, const int* ks, std::span<const Vec3> rest,
               std::span<const Vec3> x, std::span<const Eigen::Quaterniond> rotations, Batch& b) {
  std::copy_n(ks, W, b.ks.begin());
  const int n = b.n = int(m.neighbours.row(ks[0]).size());
  for (int l = 0; l < W; ++l) {
    b.node[l] = m.nodes[ks[l]];
    b.nb[l] = m.neighbours.row(ks[l]).data();
  }
  LaneFit& fit = b.fit;
  fit.xi = gather(x, b.node);
  const V3 Xi = gather(rest, b.node);
  // Two passes: the gathers and sums, then the products; in one, their 18 accumulators
  // would not fit the 16 vector registers.
  // (Plain lane vectors as accumulators: GCC keeps them in registers, not V3's arrays.)
  D sdx{}, sdy{}, sdz{}, srx{}, sry{}, srz{}, sXx{}, sXy{}, sXz{};
  for (int j = 0; j < n; ++j) {
    const int id[W] = {b.nb[0][j], b.nb[1][j], b.nb[2][j], b.nb[3][j]};
    const V3 Xj = gather(rest, id);
    const V3 d = gather(x, id) - fit.xi, rj = Xj - Xi;
    for (int a = 0; a < 3; ++a) b.dx[j].v[a] = d.v[a], b.r[j].v[a] = rj.v[a];
    sdx += d.v[0], sdy += d.v[1], sdz += d.v[2];
    srx += rj.v[0], sry += rj.v[1], srz += rj.v[2];
    sXx += Xj.v[0], sXy += Xj.v[1], sXz += Xj.v[2];
  }
  const V3 sum_d{{sdx, sdy, sdz}}, sum_r{{srx, sry, srz}}, sum_X{{sXx, sXy, sXz}};
  M3 P{};
  for (int j = 0; j < n; ++j)
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c) P.a[a][c] += b.dx[j].v[a] * b.r[j].v[c];
  fit.count = splat(double(n));
  fit.sum_d = sum_d;
  fit.g = fit.xi + sum_d / fit.count;
  fit.mean_r = sum_r / fit.count;
  fit.c = Xi - sum_X / fit.count;
  for (int a = 0; a < 3; ++a)
    for (int c = 0; c < 3; ++c) fit.A.a[a][c] = P.a[a][c] - sum_d.v[a] * fit.mean_r.v[c];
  b.normal_pair = m.framed.find(ks[0]) >= 0;
  for (int l = 1; l < W; ++l)  // plan_polar_batches groups lanes by count(k), framed included
    assert((m.framed.find(ks[l]) >= 0) == b.normal_pair && "a batch mixes framed lanes");
  if (b.normal_pair) add_normal_pair(m, b.ks, n, b.dx, b.r, fit, b.normal);
  const Eigen::Quaterniond* q[W] = {&rotations[ks[0]], &rotations[ks[1]], &rotations[ks[2]],
                                    &rotations[ks[3]]};
  b.q = Q{
      D{q[0]->w(), q[1]->w(), q[2]->w(), q[3]->w()}, D{q[0]->x(), q[1]->x(), q[2]->x(), q[3]->x()},
      D{q[0]->y(), q[1]->y(), q[2]->y(), q[3]->y()}, D{q[0]->z(), q[1]->z(), q[2]->z(), q[3]->z()}};
  b.active = Mask{} == 0;
  b.failed = Mask{};
}

// Newton turns of the rotation, as rotation_iteration, until they settle it as
// extract_rotation decides (below 1e-8 rad, the next turn being of its square). A lane that
// needs a turn of the linear fallback or of 0.1 rad or more, or more than kMaxTurns turns,
// redoes its node on the scalar path. A turn of a batch with no active lane changes nothing.
constexpr int kMaxTurns = 6;

PHYMUL_LANES void newton_turn(const M3& A, Q& q, Mask& active, Mask& failed) {
  const M3 S = transpose_times(rotation_matrix(q), A);
  V3 half;  // of the turn theta = 2 H^-1 axial(skew(S))
  const Mask newton = solve_positive_definite(rotation_hessian(S), axial_of_skew(S), half);
  const V3 theta = half * splat(2.0);
  const D angle2 = dot(theta, theta);
  const Mask bad = active & ~(newton & (angle2 < 1e-2));
  failed |= bad;
  active &= ~bad;
  const Mask move = active & (angle2 != 0.0);  // a zero turn leaves q as it is
  const Q turned = turn(q, half);
  q = Q{move ? turned.w : q.w, move ? turned.x : q.x, move ? turned.y : q.y, move ? turned.z : q.z};
  active &= ~(angle2 < 1e-16);
}

void settle_rotations(Batch& b) {
  Q q = b.q;
  for (int it = 0; it < kMaxTurns && any(b.active); ++it)
    newton_turn(b.fit.A, q, b.active, b.failed);
  b.q = q;
}

// Two batches' turns side by side: each turn is a chain of dependent operations, and two
// chains keep the floating-point units busier than one.
void settle_rotations(Batch& a, Batch& b) {
  Q qa = a.q, qb = b.q;
  for (int it = 0; it < kMaxTurns && any(a.active | b.active); ++it) {
    newton_turn(a.fit.A, qa, a.active, a.failed);
    newton_turn(b.fit.A, qb, b.active, b.failed);
  }
  a.q = qa;
  b.q = qb;
}

// The pull, its reaction on the neighbours and their scatter into f; lanes that did not settle
// redo their node on the scalar path, in lane order.
double add_batch_forces(const ShapeMemory& m, Batch& b, std::span<const Vec3> rest,
                        std::span<const Vec3> x, std::span<Eigen::Quaterniond> rotations,
                        std::span<Vec3> f, std::array<bool, W>* batched) {
  const int n = b.n;
  const LaneFit& fit = b.fit;
  const Q& q = b.q;
  Mask ok = ~(b.failed | b.active);
  const M3 R = rotation_matrix(q);

  const D stiffness = splat(m.stiffness);
  const V3 pull = fit.g + times(R, fit.c) - fit.xi;
  const V3 fi = pull * stiffness;
  const D energy = 0.5 * stiffness * dot(pull, pull);
  // Lane l's reaction on its neighbour j, as a row (x, y, z, *) at reaction[l][j].
  D reaction[W][kShapeMemoryMaxBatchedNeighbours];
  if (m.reaction) {
    // add_centroid_reaction and add_rotation_reaction: neighbour j gets
    // -(f_i / n + R (mu x (X_j - G0)) / 2), mu = 2 H^-1 K (c x R^T pull).
    V3 half_mu;
    ok &= solve_positive_definite(rotation_hessian(transpose_times(R, fit.A)),
                                  cross(fit.c, transpose_times(R, pull)) * stiffness, half_mu);
    const V3 share = fi / fit.count;
    auto reaction_on = [&](int j) {
      const V3 e = b.r[j] - fit.mean_r;  // X_j - G0
      return share + times(R, cross(half_mu, e));
    };
    constexpr int rows = kShapeMemoryMaxBatchedNeighbours;
    if (!b.normal_pair) {
      for (int j = 0; j < n; ++j) store_rows(reaction_on(j), &reaction[0][j], rows);
    } else if (m.surface) {  // N = sum of e_j x e_j+1 around the ring: the centroid terms cancel
      const V3 hp = normal_gradient(b.normal, R, half_mu);
      auto ring_row = [&](int j, int previous, int next) {
        store_rows(reaction_on(j) + cross(b.dx[next] - b.dx[previous], hp), &reaction[0][j], rows);
      };
      // The ring's ends apart: its wrap-around indices cost more than the rows (no modulo
      // either: an integer division each).
      ring_row(0, n - 1, 1 % n);
      for (int j = 1; j + 1 < n; ++j) ring_row(j, j - 1, j + 1);
      if (n > 1) ring_row(n - 1, n - 2, 0);
    } else {
      for (int j = 0; j < n; ++j) b.r[j] = reaction_on(j);
      add_pair_normal_reaction(n, fit, b.normal, normal_gradient(b.normal, R, half_mu), b.r);
      for (int j = 0; j < n; ++j) store_rows(b.r[j], &reaction[0][j], rows);
    }
  }

  double total = 0.0;
  double* const forces = f.data()->data();
  for (int l = 0; l < W; ++l) {
    if (batched) (*batched)[l] = ok[l] != 0;
    if (!ok[l]) {
      total += add_polar_node_forces(m, b.ks[l], rest, x, rotations, f);
      continue;
    }
    rotations[b.ks[l]] = Eigen::Quaterniond(q.w[l], q.x[l], q.y[l], q.z[l]);
    f[b.node[l]] += Vec3(fi.v[0][l], fi.v[1][l], fi.v[2][l]);
    if (m.reaction)
      for (int j = 0; j < n; ++j)
        subtract3(forces + 3 * b.nb[l][j], reinterpret_cast<const double*>(&reaction[l][j]));
    total += energy[l];
  }
  return total;
}

}  // namespace

double add_polar_batch_forces(const ShapeMemory& m, const std::array<int, W>& ks,
                              std::span<const Vec3> rest, std::span<const Vec3> x,
                              std::span<Eigen::Quaterniond> rotations, std::span<Vec3> f,
                              std::array<bool, W>* batched) {
  Batch b;
  fit_batch(m, ks.data(), rest, x, rotations, b);
  settle_rotations(b);
  return add_batch_forces(m, b, rest, x, rotations, f, batched);
}

void add_polar_batch_pair_forces(const ShapeMemory& m, const int* ks, std::span<const Vec3> rest,
                                 std::span<const Vec3> x, std::span<Eigen::Quaterniond> rotations,
                                 std::span<Vec3> f, double& energy) {
  Batch a, b;
  fit_batch(m, ks, rest, x, rotations, a);
  fit_batch(m, ks + W, rest, x, rotations, b);
  settle_rotations(a, b);
  energy += add_batch_forces(m, a, rest, x, rotations, f, nullptr);
  energy += add_batch_forces(m, b, rest, x, rotations, f, nullptr);
}

}  // namespace phymul
