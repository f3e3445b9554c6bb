#include "mesh/spatial_hash.hpp"

#include <algorithm>
#include <cmath>

namespace phymul {

void TriangleHash::reserve(size_t triangles) {
  size_t buckets = 1;
  while (buckets < 2 * std::max<size_t>(triangles, 1)) buckets <<= 1;
  mask_ = uint32_t(buckets - 1);
  start_.assign(buckets + 1, 0);
  entries_.assign(triangles, 0);
  slot_.assign(triangles, 0);
  seen_.assign(buckets, 0);
}

// Cells beyond 2^52 (points far from the origin against the triangles' size, or not finite)
// share the bounding cells: a broad phase may return more candidates, never fewer, and the
// neighbours' indices (c +- 1) stay representable.
TriangleHash::Cell TriangleHash::cell_of(const Vec3& p) const {
  constexpr double kLimit = 4503599627370496.0;  // 2^52
  const auto index = [&](double v) {
    const double c = std::floor(v / cell_);
    return int64_t(c >= -kLimit ? (c <= kLimit ? c : kLimit) : -kLimit);
  };
  return {index(p.x()), index(p.y()), index(p.z())};
}

uint32_t TriangleHash::bucket(const Cell& c) const {
  // The usual large primes of spatial hashing (Teschner et al. 2003).
  const uint64_t h =
      uint64_t(c[0]) * 73856093u ^ uint64_t(c[1]) * 19349663u ^ uint64_t(c[2]) * 83492791u;
  return uint32_t(h ^ (h >> 32)) & mask_;
}

bool TriangleHash::visited_stamp(uint32_t b) {
  if (seen_[b] == stamp_) return true;
  seen_[b] = stamp_;
  return false;
}

void TriangleHash::build(std::span<const Triangle> triangles, std::span<const Vec3> x,
                         double margin) {
  double reach = 0.0;
  for (const Triangle& t : triangles) {
    const Vec3 c = (x[t[0]] + x[t[1]] + x[t[2]]) / 3.0;
    for (int i : t) reach = std::max(reach, (x[i] - c).norm());
  }
  cell_ = std::max(reach + margin, 1e-12);
  // Counting sort by bucket: counts, prefix sums, then placement.
  std::fill(start_.begin(), start_.end(), 0);
  for (size_t k = 0; k < triangles.size(); ++k) {
    const Triangle& t = triangles[k];
    slot_[k] = bucket(cell_of((x[t[0]] + x[t[1]] + x[t[2]]) / 3.0));
    ++start_[slot_[k] + 1];
  }
  for (size_t b = 1; b < start_.size(); ++b) start_[b] += start_[b - 1];
  for (size_t k = 0; k < triangles.size(); ++k) entries_[size_t(start_[slot_[k]]++)] = int(k);
  // Placement advanced each start to the next bucket's: shift back.
  for (size_t b = start_.size() - 1; b > 0; --b) start_[b] = start_[b - 1];
  start_[0] = 0;
}

}  // namespace phymul
