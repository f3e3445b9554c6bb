// A node's three coordinates in one AVX2 register, for the volume constraints' loops over a
// surface's triangles and nodes, where the build targets AVX2 and FMA (-march=native); plain
// Eigen otherwise: the same sums, in another order (results differ in the last bits).
#pragma once

#if defined(__AVX2__) && defined(__FMA__)
#define PHYMUL_VOLUME_AVX2 1
#include <immintrin.h>
#endif

#include <algorithm>
#include <span>

#include "model/workspace.hpp"
#include "phymul/model.hpp"

namespace phymul {

#ifdef PHYMUL_VOLUME_AVX2
// Three doubles in the lanes 0-2 of a register, 0 in the fourth; never read or written past.
[[gnu::always_inline]] inline __m256i three_lanes() { return _mm256_setr_epi64x(-1, -1, -1, 0); }
[[gnu::always_inline]] inline __m256d load3(const Vec3& v) {
  return _mm256_maskload_pd(v.data(), three_lanes());
}
// As a pair and a single: a masked store covers 32 bytes for the hardware, the next node's
// first 8 too, and a load of that node would then wait for the store to retire (Intel).
[[gnu::always_inline]] inline void store3(Vec3& v, __m256d r) {
  _mm_storeu_pd(v.data(), _mm256_castpd256_pd128(r));
  _mm_store_sd(v.data() + 2, _mm256_extractf128_pd(r, 1));
}
// (y, z, x, w): the cross product a x b is a * yzx(b) - yzx(a) * b in the lanes (z, x, y).
[[gnu::always_inline]] inline __m256d yzx(__m256d v) {
  return _mm256_permute4x64_pd(v, _MM_SHUFFLE(3, 0, 2, 1));
}
[[gnu::always_inline]] inline __m256d zxy(__m256d v) {
  return _mm256_permute4x64_pd(v, _MM_SHUFFLE(3, 1, 0, 2));
}
[[gnu::always_inline]] inline double lane_sum(__m256d v) {
  alignas(32) double l[4];
  _mm256_store_pd(l, v);
  return (l[0] + l[1]) + (l[2] + l[3]);
}
#endif

// Whether c's kept velocity-projection gradient (cache.gradient) was taken at x: every node
// of c where cache.gradient_at says. Branch-free within blocks of 32 nodes: after a step's
// projection the first block already differs, between steps every node is compared.
inline bool gradient_kept_at(const VolumeConstraint& c, const VolumeCache& cache,
                             std::span<const Vec3> x) {
  if (cache.gradient_at.size() != c.nodes.size()) return false;
  const int* __restrict nodes = c.nodes.data();
  const Vec3* __restrict at = cache.gradient_at.data();
  const int n = int(c.nodes.size());
#ifdef PHYMUL_VOLUME_AVX2
  for (int begin = 0; begin < n; begin += 32) {
    __m256d differ = _mm256_setzero_pd();
    for (int m = begin; m < std::min(n, begin + 32); ++m)
      differ = _mm256_or_pd(differ,
                            _mm256_cmp_pd(load3(at[m]), load3(x[size_t(nodes[m])]), _CMP_NEQ_UQ));
    if (!_mm256_testz_pd(differ, differ)) return false;
  }
#else
  for (int m = 0; m < n; ++m)
    if (at[m] != x[size_t(nodes[m])]) return false;
#endif
  return true;
}

}  // namespace phymul
