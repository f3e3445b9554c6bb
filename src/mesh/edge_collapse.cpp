// Coarsening a closed triangle surface to a target edge by collapsing its short edges, each
// collapse kept only when the surface stays manifold and no triangle turns over.
#include <algorithm>
#include <vector>

#include "mesh/surface_smoothing.hpp"

namespace phymul::detail {
namespace {

constexpr double kWorstQuality = 0.3;  // no collapse makes a triangle worse than this

class Collapser {
 public:
  Collapser(Mesh& m, double min_edge, double max_edge)
      : m_(m), min2_(min_edge * min_edge), max2_(max_edge * max_edge), around_(m.points.size()) {
    for (size_t t = 0; t < m.cells.size(); ++t) {
      tris_.push_back({m.cells[t].nodes[0], m.cells[t].nodes[1], m.cells[t].nodes[2]});
      for (int k = 0; k < 3; ++k) around_[size_t(tris_[t][size_t(k)])].push_back(int(t));
    }
    alive_.assign(tris_.size(), 1);
  }

  void run(int passes) {
    for (int pass = 0; pass < passes; ++pass) {
      int collapsed = 0;
      for (size_t t = 0; t < tris_.size(); ++t)
        for (int k = 0; k < 3 && alive_[t]; ++k) {
          const int a = tris_[t][size_t(k)], b = tris_[t][size_t((k + 1) % 3)];
          if ((m_.points[size_t(a)] - m_.points[size_t(b)]).squaredNorm() < min2_ && collapse(a, b))
            ++collapsed;
        }
      if (collapsed == 0) break;
    }
    rebuild();
  }

 private:
  std::vector<int> ring(int v) const {
    std::vector<int> r;
    for (int t : around_[size_t(v)])
      for (int w : tris_[size_t(t)])
        if (w != v) r.push_back(w);
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
    return r;
  }
  Vec3 normal(const std::array<int, 3>& t, int moved, const Vec3& at) const {
    auto p = [&](int v) { return v == moved ? at : m_.points[size_t(v)]; };
    return (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]));
  }

  // b merged into a at their midpoint, when the link condition holds (exactly two common
  // neighbours: the surface stays manifold) and no triangle flips or grows a long edge.
  bool collapse(int a, int b) {
    const std::vector<int> ra = ring(a), rb = ring(b);
    std::vector<int> common;
    std::set_intersection(ra.begin(), ra.end(), rb.begin(), rb.end(), std::back_inserter(common));
    if (common.size() != 2 || ra.size() <= 3 || rb.size() <= 3) return false;
    const Vec3 mid = 0.5 * (m_.points[size_t(a)] + m_.points[size_t(b)]);
    for (int v : {a, b})
      for (int t : around_[size_t(v)]) {
        const auto& tri = tris_[size_t(t)];
        if (std::count(tri.begin(), tri.end(), a) + std::count(tri.begin(), tri.end(), b) == 2)
          continue;  // one of the two that go
        const Vec3 before = normal(tri, -1, mid), after = normal(tri, v, mid);
        if (after.dot(before) < 0.5 * before.norm() * after.norm()) return false;
        auto p = [&](int w) { return w == v ? mid : m_.points[size_t(w)]; };
        if (triangle_quality(p(tri[0]), p(tri[1]), p(tri[2])) < kWorstQuality) return false;
        for (int w : tri)
          if (w != v && (m_.points[size_t(w)] - mid).squaredNorm() > max2_) return false;
      }
    for (int t : around_[size_t(b)]) {
      auto& tri = tris_[size_t(t)];
      if (std::find(tri.begin(), tri.end(), a) != tri.end()) {
        alive_[size_t(t)] = 0;
        continue;
      }
      std::replace(tri.begin(), tri.end(), b, a);
      around_[size_t(a)].push_back(t);
    }
    std::erase_if(around_[size_t(a)], [&](int t) { return !alive_[size_t(t)]; });
    for (int c : common)
      std::erase_if(around_[size_t(c)], [&](int t) { return !alive_[size_t(t)]; });
    around_[size_t(b)].clear();
    m_.points[size_t(a)] = mid;
    return true;
  }

  void rebuild() {
    std::vector<int> renumber(m_.points.size(), -1);
    std::vector<Vec3> points;
    m_.cells.clear();
    for (size_t t = 0; t < tris_.size(); ++t) {
      if (!alive_[t]) continue;
      Cell c;
      c.type = CellType::triangle;
      for (int k = 0; k < 3; ++k) {
        int& r = renumber[size_t(tris_[t][size_t(k)])];
        if (r < 0) r = int(points.size()), points.push_back(m_.points[size_t(tris_[t][size_t(k)])]);
        c.nodes[size_t(k)] = r;
      }
      m_.cells.push_back(c);
    }
    m_.points = std::move(points);
  }

  Mesh& m_;
  double min2_, max2_;
  std::vector<std::array<int, 3>> tris_;
  std::vector<char> alive_;
  std::vector<std::vector<int>> around_;
};

}  // namespace

void collapse_short_edges(Mesh& surface, double min_edge, double max_edge, int passes) {
  Collapser(surface, min_edge, max_edge).run(passes);
}

}  // namespace phymul::detail
