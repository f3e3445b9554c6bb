// Nearest points on a fixed triangle surface, through a uniform grid: the remesher projects its
// points back onto the input surface, and its report measures distances between the two.
#pragma once

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "phymul/mesh.hpp"

namespace phymul {

// The point of triangle (a, b, c) nearest to p (Ericson, Real-Time Collision Detection 5.1.5).
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

class NearestTriangle {
 public:
  struct Hit {
    Vec3 point;       // on the surface
    double distance;  // m
  };
  // Keeps copies; `triangles` must not be empty.
  NearestTriangle(std::vector<Vec3> points, std::vector<Triangle> triangles);
  Hit nearest(const Vec3& p) const;

 private:
  using Key = std::int64_t;
  Key key(std::int64_t i, std::int64_t j, std::int64_t k) const;
  std::array<std::int64_t, 3> cell_of(const Vec3& p) const;
  void scan(const Vec3& p, const std::array<std::int64_t, 3>& lo,
            const std::array<std::int64_t, 3>& hi, Hit& best) const;
  void visit(const Vec3& p, int triangle, Hit& best) const;

  std::vector<Vec3> x_;
  std::vector<Triangle> t_;
  Vec3 origin_;
  double cell_ = 1.0;
  std::int64_t cells_per_axis_ = 1;
  std::unordered_map<Key, std::vector<int>> grid_;
};

}  // namespace phymul
