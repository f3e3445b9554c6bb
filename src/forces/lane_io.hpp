// Four lanes of doubles (GCC/Clang vector extensions) and the loads and stores between them
// and the model's per-node arrays: the batched kernels' common ground (the polar shape memory,
// forces/shape_memory_batch.cpp; the explicit finite elements' hexahedra,
// forces/explicit_fem.cpp).
#pragma once

#include <cmath>
#include <cstring>
#include <span>

#if defined(__AVX__)
#include <immintrin.h>
#endif

#include "forces/lane_algebra.hpp"
#include "phymul/mesh.hpp"

namespace phymul::lanes {

constexpr int W = 4;  // the gathers below spell out four lanes

// GCC/Clang vector extensions: each operation acts on the W lanes at once (one AVX
// instruction with -march=native, two SSE2 ones without).
using D = double __attribute__((vector_size(W * sizeof(double))));
using Mask = long long __attribute__((vector_size(W * sizeof(long long))));

PHYMUL_LANES D splat(double s) { return D{} + s; }
PHYMUL_LANES D lane_sqrt(const D& v) {
#if defined(__AVX__)
  return _mm256_sqrt_pd(v);  // correctly rounded, as std::sqrt
#else
  return D{std::sqrt(v[0]), std::sqrt(v[1]), std::sqrt(v[2]), std::sqrt(v[3])};
#endif
}
// Masks hold all ones (true) or zeros per lane.
PHYMUL_LANES int sign_bits(const Mask& m) {
#if defined(__AVX__)
  return _mm256_movemask_pd(__m256d(m));
#else
  return (m[0] ? 1 : 0) | (m[1] ? 2 : 0) | (m[2] ? 4 : 0) | (m[3] ? 8 : 0);
#endif
}
PHYMUL_LANES bool any(const Mask& m) { return sign_bits(m) != 0; }
PHYMUL_LANES bool all(const Mask& m) { return sign_bits(m) == (1 << W) - 1; }

// (p[0], p[1], p[2], 0): one point, without reading past it (the last node of x, say).
PHYMUL_LANES D load3(const double* p) {
#if defined(__AVX__)
  return _mm256_maskload_pd(p, _mm256_set_epi64x(0, -1, -1, -1));
#else
  return D{p[0], p[1], p[2], 0.0};
#endif
}

// The rows (x, y, z, *) of four points as the lane vectors of their x, y and z.
PHYMUL_LANES V3<D> transpose_rows(const D& a, const D& b, const D& c, const D& d) {
  const D ab_xz = __builtin_shufflevector(a, b, 0, 4, 2, 6),
          ab_y = __builtin_shufflevector(a, b, 1, 5, 3, 7);
  const D cd_xz = __builtin_shufflevector(c, d, 0, 4, 2, 6),
          cd_y = __builtin_shufflevector(c, d, 1, 5, 3, 7);
  return {{__builtin_shufflevector(ab_xz, cd_xz, 0, 1, 4, 5),
           __builtin_shufflevector(ab_y, cd_y, 0, 1, 4, 5),
           __builtin_shufflevector(ab_xz, cd_xz, 2, 3, 6, 7)}};
}

// The W points p[id[l]].
PHYMUL_LANES V3<D> gather(std::span<const Vec3> p, const int* id) {
  const double* base = p.data()->data();
  return transpose_rows(load3(base + 3 * id[0]), load3(base + 3 * id[1]), load3(base + 3 * id[2]),
                        load3(base + 3 * id[3]));
}

// Lane l of u as the row (x, y, z, *) in rows[l] (the inverse of transpose_rows).
PHYMUL_LANES void store_rows(const V3<D>& u, D* rows, int stride) {
  const D xy02 = __builtin_shufflevector(u.v[0], u.v[1], 0, 4, 2, 6);
  const D xy13 = __builtin_shufflevector(u.v[0], u.v[1], 1, 5, 3, 7);
  const D z13 = __builtin_shufflevector(u.v[2], u.v[2], 1, 1, 3, 3);
  rows[0] = __builtin_shufflevector(xy02, u.v[2], 0, 1, 4, 5);
  rows[stride] = __builtin_shufflevector(xy13, z13, 0, 1, 4, 5);
  rows[2 * stride] = __builtin_shufflevector(xy02, u.v[2], 2, 3, 6, 7);
  rows[3 * stride] = __builtin_shufflevector(xy13, z13, 2, 3, 6, 7);
}

// p[0..2] -= row[0..2], by a pair and a single: a masked store would not forward to the next
// load of the same node (the next lanes' neighbours are largely the same), and costs twice.
PHYMUL_LANES void subtract3(double* p, const double* row) {
  using Pair = double __attribute__((vector_size(2 * sizeof(double))));
  Pair xy, r;
  std::memcpy(&xy, p, sizeof xy);
  std::memcpy(&r, row, sizeof r);
  xy -= r;
  std::memcpy(p, &xy, sizeof xy);
  p[2] -= row[2];
}

}  // namespace phymul::lanes
