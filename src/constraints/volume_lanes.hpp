// A node's three coordinates in one AVX2 register, for the volume constraints' loops over a
// surface's triangles and nodes, where the build targets AVX2 and FMA (-march=native); plain
// Eigen otherwise: the same sums, in another order (results differ in the last bits).
#pragma once

#if defined(__AVX2__) && defined(__FMA__)
#define PHYMUL_VOLUME_AVX2 1
#include <immintrin.h>
#endif

#include "phymul/model.hpp"

namespace phymul {

#ifdef PHYMUL_VOLUME_AVX2
// Three doubles in the lanes 0-2 of a register, 0 in the fourth; never read or written past.
[[gnu::always_inline]] inline __m256i three_lanes() { return _mm256_setr_epi64x(-1, -1, -1, 0); }
[[gnu::always_inline]] inline __m256d load3(const Vec3& v) {
  return _mm256_maskload_pd(v.data(), three_lanes());
}
[[gnu::always_inline]] inline void store3(Vec3& v, __m256d r) {
  _mm256_maskstore_pd(v.data(), three_lanes(), r);
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

}  // namespace phymul
