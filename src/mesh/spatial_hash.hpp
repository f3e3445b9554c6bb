// A uniform grid over space, hashed into a fixed number of buckets: triangles are filed by
// the cell of their centroid, and a query visits the 27 cells around a point. Every buffer is
// sized once (reserve), so rebuilding it each step allocates nothing.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "phymul/mesh.hpp"

namespace phymul {

class TriangleHash {
 public:
  // Room for `triangles` entries; the bucket count is the next power of two >= 2 x that.
  void reserve(size_t triangles);

  // Files every triangle by its centroid's cell. The cell edge is the largest distance from
  // a triangle's centroid to its corners plus `margin` (m), so a point within `margin` of a
  // triangle lies in one of the 27 cells around the point's own cell.
  void build(std::span<const Triangle> triangles, std::span<const Vec3> x, double margin);

  // Calls visit(triangle index) for the triangles filed in the 27 cells around p (and any
  // sharing their buckets: callers test distances anyway).
  template <class Visit>
  void around(const Vec3& p, Visit visit) {
    around(cell_of(p), visit);
  }

  // The same around a cell: points in one cell share their neighbours (callers reuse them).
  using Cell = std::array<int64_t, 3>;
  Cell cell_of(const Vec3& p) const;
  template <class Visit>
  void around(const Cell& c, Visit visit) {
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const uint32_t b = bucket({c[0] + dx, c[1] + dy, c[2] + dz});
          if (visited_stamp(b)) continue;  // two neighbour cells may share a bucket
          for (int k = start_[b]; k < start_[b + 1]; ++k) visit(entries_[size_t(k)]);
        }
    ++stamp_;
  }

  // The filed triangles in bucket order (in triangle order within a bucket), and visit(first,
  // last) for the runs of that order filed around a cell: data kept in the same order is read
  // in runs, not scattered.
  std::span<const int> entries() const { return entries_; }
  template <class Visit>
  void runs_around(const Cell& c, Visit visit) {
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const uint32_t b = bucket({c[0] + dx, c[1] + dy, c[2] + dz});
          if (!visited_stamp(b) && start_[b] < start_[b + 1]) visit(start_[b], start_[b + 1]);
        }
    ++stamp_;
  }

 private:
  uint32_t bucket(const Cell& c) const;
  bool visited_stamp(uint32_t b);

  double cell_ = 1.0;
  uint32_t mask_ = 0;
  std::vector<int> start_;      // bucket b holds entries_[start_[b] .. start_[b+1])
  std::vector<int> entries_;    // triangle indices, grouped by bucket
  std::vector<uint32_t> slot_;  // per triangle: its bucket
  std::vector<uint64_t> seen_;  // per bucket: stamp of the last query that visited it
  uint64_t stamp_ = 1;
};

}  // namespace phymul
