#include "mesh/surface_smoothing.hpp"

#include <cmath>
#include <numeric>

namespace phymul::detail {
namespace {

// One umbrella step: every point moves `factor` of the way to its neighbours' mean.
void umbrella(Mesh& surface, const Adjacency& around, double factor, std::vector<Vec3>& moved) {
  for (int i = 0; i < around.rows(); ++i) {
    const auto ring = around.row(i);
    if (ring.empty()) continue;
    Vec3 mean = Vec3::Zero();
    for (int j : ring) mean += surface.points[size_t(j)];
    mean /= double(ring.size());
    moved[size_t(i)] = surface.points[size_t(i)] + factor * (mean - surface.points[size_t(i)]);
  }
  for (int i = 0; i < around.rows(); ++i)
    if (!around.row(i).empty()) surface.points[size_t(i)] = moved[size_t(i)];
}

int find(std::vector<int>& parent, int i) {
  while (parent[size_t(i)] != i) i = parent[size_t(i)] = parent[size_t(parent[size_t(i)])];
  return i;
}

}  // namespace

void taubin_smooth(Mesh& surface, int iterations, double lambda, double mu) {
  const Adjacency around = edge_neighbours(surface);
  std::vector<Vec3> moved(surface.points.size());
  for (int k = 0; k < iterations; ++k) {
    umbrella(surface, around, lambda, moved);
    umbrella(surface, around, mu, moved);
  }
}

void restore_volume(Mesh& surface, double volume) {
  for (int pass = 0; pass < 3; ++pass) {  // dV = area * offset, to first order
    std::vector<Vec3> normal(surface.points.size(), Vec3::Zero());
    double area = 0.0, now = 0.0;
    for (const Cell& c : surface.cells) {
      const Vec3 &a = surface.points[size_t(c.nodes[0])], &b = surface.points[size_t(c.nodes[1])],
                 &d = surface.points[size_t(c.nodes[2])];
      const Vec3 n = 0.5 * (b - a).cross(d - a);  // area-weighted
      area += n.norm(), now += a.dot(b.cross(d)) / 6.0;
      for (int k = 0; k < 3; ++k) normal[size_t(c.nodes[size_t(k)])] += n;
    }
    if (!(area > 0.0)) return;
    const double offset = (volume - now) / area;
    for (size_t i = 0; i < normal.size(); ++i)
      if (normal[i].squaredNorm() > 0.0) surface.points[i] += offset * normal[i].normalized();
  }
}

LargestPart largest_part(const Mesh& surface) {
  std::vector<int> parent(surface.points.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (const Cell& c : surface.cells)
    for (int k = 1; k < 3; ++k)
      parent[size_t(find(parent, c.nodes[0]))] = find(parent, c.nodes[size_t(k)]);
  // Each part's enclosed volume, by the divergence theorem over its triangles.
  std::vector<double> volume(surface.points.size(), 0.0);
  for (const Cell& c : surface.cells) {
    const Vec3 &a = surface.points[size_t(c.nodes[0])], &b = surface.points[size_t(c.nodes[1])],
               &d = surface.points[size_t(c.nodes[2])];
    volume[size_t(find(parent, c.nodes[0]))] += a.dot(b.cross(d)) / 6.0;
  }
  int best = -1;
  for (size_t i = 0; i < volume.size(); ++i)
    if (parent[i] == int(i) && (best < 0 || volume[i] > volume[size_t(best)])) best = int(i);
  LargestPart out;
  for (size_t i = 0; i < volume.size(); ++i)
    if (parent[i] == int(i) && int(i) != best && volume[i] != 0.0)
      ++out.dropped, out.dropped_volume += std::abs(volume[i]);
  std::vector<int> renumber(surface.points.size(), -1);
  for (const Cell& c : surface.cells) {
    if (find(parent, c.nodes[0]) != best) continue;
    Cell kept = c;
    for (int k = 0; k < 3; ++k) {
      int& r = renumber[size_t(c.nodes[size_t(k)])];
      if (r < 0)
        r = int(out.mesh.points.size()),
        out.mesh.points.push_back(surface.points[size_t(c.nodes[size_t(k)])]);
      kept.nodes[size_t(k)] = r;
    }
    out.mesh.cells.push_back(kept);
  }
  return out;
}

}  // namespace phymul::detail
