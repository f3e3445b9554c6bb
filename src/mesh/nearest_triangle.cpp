#include "mesh/nearest_triangle.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace phymul {

Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return a + d1 / (d1 - d3) * ab;
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0)
    return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

NearestTriangle::NearestTriangle(std::vector<Vec3> points, std::vector<Triangle> triangles)
    : x_(std::move(points)), t_(std::move(triangles)) {
  const auto [lo, hi] = bounding_box(x_);
  origin_ = lo;
  double edges = 0.0;
  for (const Triangle& t : t_) edges += (x_[size_t(t[0])] - x_[size_t(t[1])]).norm();
  const double diagonal = (hi - lo).norm();
  // Cells about two edges wide, but at most ~100 per axis so a huge triangle stays cheap.
  cell_ = std::max({2.0 * edges / double(std::max<size_t>(t_.size(), 1)), diagonal / 100.0,
                    std::numeric_limits<double>::min()});
  cells_per_axis_ = std::int64_t(diagonal / cell_) + 3;
  for (int k = 0; k < int(t_.size()); ++k) {
    const Triangle& t = t_[size_t(k)];
    auto a = cell_of(x_[size_t(t[0])]), b = a;
    for (int v = 1; v < 3; ++v) {
      const auto c = cell_of(x_[size_t(t[size_t(v)])]);
      for (int i = 0; i < 3; ++i) a[size_t(i)] = std::min(a[size_t(i)], c[size_t(i)]);
      for (int i = 0; i < 3; ++i) b[size_t(i)] = std::max(b[size_t(i)], c[size_t(i)]);
    }
    for (auto i = a[0]; i <= b[0]; ++i)
      for (auto j = a[1]; j <= b[1]; ++j)
        for (auto l = a[2]; l <= b[2]; ++l) grid_[key(i, j, l)].push_back(k);
  }
}

NearestTriangle::Key NearestTriangle::key(std::int64_t i, std::int64_t j, std::int64_t k) const {
  return (i * cells_per_axis_ + j) * cells_per_axis_ + k;
}

std::array<std::int64_t, 3> NearestTriangle::cell_of(const Vec3& p) const {
  std::array<std::int64_t, 3> c{};
  for (int i = 0; i < 3; ++i) {
    const double s = std::floor((p[i] - origin_[i]) / cell_);
    c[size_t(i)] = std::int64_t(std::clamp(s, -1.0, double(cells_per_axis_ - 1)));
  }
  return c;
}

void NearestTriangle::visit(const Vec3& p, int triangle, Hit& best) const {
  const Triangle& t = t_[size_t(triangle)];
  const Vec3 q = closest_on_triangle(p, x_[size_t(t[0])], x_[size_t(t[1])], x_[size_t(t[2])]);
  const double d = (q - p).norm();
  if (d < best.distance) best = {q, d};
}

void NearestTriangle::scan(const Vec3& p, const std::array<std::int64_t, 3>& lo,
                           const std::array<std::int64_t, 3>& hi, Hit& best) const {
  for (auto i = lo[0]; i <= hi[0]; ++i)
    for (auto j = lo[1]; j <= hi[1]; ++j)
      for (auto k = lo[2]; k <= hi[2]; ++k)
        if (auto it = grid_.find(key(i, j, k)); it != grid_.end())
          for (int triangle : it->second) visit(p, triangle, best);
}

NearestTriangle::Hit NearestTriangle::nearest(const Vec3& p) const {
  Hit best{p, std::numeric_limits<double>::infinity()};
  // Boxes of growing half-width r around p: a hit within r is the nearest, since every
  // triangle with a point within r is filed in a cell the box meets.
  for (double r = cell_;; r *= 2.0) {
    const auto lo = cell_of(p - Vec3::Constant(r)), hi = cell_of(p + Vec3::Constant(r));
    const double cells =
        double(hi[0] - lo[0] + 1) * double(hi[1] - lo[1] + 1) * double(hi[2] - lo[2] + 1);
    if (cells > double(grid_.size())) break;  // cheaper to look at every triangle
    scan(p, lo, hi, best);
    if (best.distance <= r) return best;
  }
  for (int k = 0; k < int(t_.size()); ++k) visit(p, k, best);
  return best;
}

}  // namespace phymul
