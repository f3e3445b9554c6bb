// A label image's chosen labels as a smooth closed surface: shape-based interpolation across
// the thick slices (each slice's signed distance, interpolated between slices), resampled on
// a near-isotropic grid, cut at zero, smoothed.
#include "phymul/label_surface.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>

#include "mesh/distance_2d.hpp"
#include "mesh/marching_tetrahedra.hpp"
#include "mesh/surface_check.hpp"
#include "mesh/surface_smoothing.hpp"
#include "phymul/meshing.hpp"

namespace phymul {
namespace {

constexpr double kGridPerEdge = 0.5;  // resampling grid spacing / target edge
constexpr double kPush = 0.1;         // |value| >= kPush * spacing at grid nodes
constexpr int kTaubinIterations = 10;
// Edges shorter than this (x edge) are collapsed, none made longer than the other.
constexpr double kShortestEdge = 0.7, kLongestEdge = 1.5;
constexpr long long kMaxGridNodes = 300LL * 300LL * 300LL;

// The image seen with its axes reordered: a, b in the slice, c across the slices.
struct View {
  const LabelImage& image;
  std::array<int, 3> axis;          // image axis of a, b, c
  std::vector<unsigned char> mask;  // in the image's own order
  std::array<int, 3> lo, hi;        // the mask's voxel box, in view order
  Vec3 s;                           // voxel size (mm) along a, b, c

  int n(int v) const { return image.dims[size_t(axis[size_t(v)])]; }
  bool inside(int a, int b, int c) const {
    std::array<int, 3> ijk;
    ijk[size_t(axis[0])] = a, ijk[size_t(axis[1])] = b, ijk[size_t(axis[2])] = c;
    return mask[size_t(ijk[0]) +
                size_t(image.dims[0]) * (size_t(ijk[1]) + size_t(image.dims[1]) * size_t(ijk[2]))];
  }
};

std::string labels_present(const LabelImage& image) {
  std::vector<std::string> items;
  for (const auto& [label, count] : label_counts(image))
    items.push_back(fmt::format("{} ({} voxels)", label, count));
  return fmt::format("{}", fmt::join(items, ", "));
}

size_t make_mask(View& v, std::span<const int> labels) {
  const LabelImage& im = v.image;
  v.mask.assign(im.labels.size(), 0);
  size_t count = 0;
  for (size_t i = 0; i < im.labels.size(); ++i)
    if (std::find(labels.begin(), labels.end(), im.labels[i]) != labels.end())
      v.mask[i] = 1, ++count;
  if (count == 0)
    throw MeshError(fmt::format("no voxel holds label {}: the image holds {}",
                                fmt::join(labels, " or "), labels_present(im)));
  return count;
}

// The thickest axis across, the other two in the slice; the mask's box in that order.
void orient(View& v) {
  const Vec3 s = v.image.spacing() * 1e3;
  int c = 2;
  for (int a = 0; a < 2; ++a)
    if (s[a] > 1.01 * s[c]) c = a;
  v.axis = c == 2 ? std::array{0, 1, 2} : c == 1 ? std::array{0, 2, 1} : std::array{1, 2, 0};
  for (int k = 0; k < 3; ++k) v.s[k] = s[v.axis[size_t(k)]];
  v.lo = {v.n(0), v.n(1), v.n(2)}, v.hi = {-1, -1, -1};
  for (int c2 = 0; c2 < v.n(2); ++c2)
    for (int b = 0; b < v.n(1); ++b)
      for (int a = 0; a < v.n(0); ++a)
        if (v.inside(a, b, c2)) {
          const std::array<int, 3> p{a, b, c2};
          for (size_t k = 0; k < 3; ++k)
            v.lo[k] = std::min(v.lo[k], p[k]), v.hi[k] = std::max(v.hi[k], p[k]);
        }
}

// Each labelled slice's signed distance (mm) on the mask's box widened by `pad` pixels.
struct Slices {
  int a0, b0, na, nb, c0, nc;
  double limit;
  std::vector<std::vector<float>> distance;

  // Bilinear in the slice; `limit` (outside) off the box.
  double in_slice(int c, double a, double b) const {
    if (c < c0 || c >= c0 + nc) return limit;
    const double x = a - a0, y = b - b0;
    if (!(x >= 0.0 && y >= 0.0 && x <= na - 1 && y <= nb - 1)) return limit;
    const int i = std::min(int(x), na - 2 < 0 ? 0 : na - 2),
              j = std::min(int(y), nb - 2 < 0 ? 0 : nb - 2);
    const double u = x - i, w = y - j;
    const auto& d = distance[size_t(c - c0)];
    auto at = [&](int di, int dj) {
      const int ii = std::min(i + di, na - 1), jj = std::min(j + dj, nb - 1);
      return double(d[size_t(ii) + size_t(na) * size_t(jj)]);
    };
    return (1 - u) * (1 - w) * at(0, 0) + u * (1 - w) * at(1, 0) + (1 - u) * w * at(0, 1) +
           u * w * at(1, 1);
  }
  // Catmull-Rom across the slices (C1, exact for a boundary moving linearly).
  double at(double a, double b, double c) const {
    const int k = int(std::floor(c));
    const double t = c - k;
    const double p0 = in_slice(k - 1, a, b), p1 = in_slice(k, a, b), p2 = in_slice(k + 1, a, b),
                 p3 = in_slice(k + 2, a, b);
    return 0.5 * (2 * p1 + (p2 - p0) * t + (2 * p0 - 5 * p1 + 4 * p2 - p3) * t * t +
                  (3 * p1 - p0 - 3 * p2 + p3) * t * t * t);
  }
};

Slices slice_distances(const View& v, double limit, int pad_a, int pad_b) {
  Slices s{v.lo[0] - pad_a,
           v.lo[1] - pad_b,
           v.hi[0] - v.lo[0] + 1 + 2 * pad_a,
           v.hi[1] - v.lo[1] + 1 + 2 * pad_b,
           v.lo[2],
           v.hi[2] - v.lo[2] + 1,
           limit,
           {}};
  std::vector<unsigned char> pixels(size_t(s.na) * size_t(s.nb));
  for (int c = s.c0; c < s.c0 + s.nc; ++c) {
    for (int b = 0; b < s.nb; ++b)
      for (int a = 0; a < s.na; ++a) {
        const int ia = s.a0 + a, ib = s.b0 + b;
        pixels[size_t(a) + size_t(s.na) * size_t(b)] =
            ia >= 0 && ib >= 0 && ia < v.n(0) && ib < v.n(1) && v.inside(ia, ib, c);
      }
    s.distance.push_back(detail::signed_distance_2d(pixels, s.na, s.nb, v.s[0], v.s[1], limit));
  }
  return s;
}

// The resampling grid: spacing h (mm) on every axis, over the box and a margin.
struct Grid {
  detail::ScalarGrid values;
  Vec3 start;  // view-order voxel index of node (0, 0, 0)
};

Grid resample(const View& v, const Slices& s, double h) {
  Grid g;
  g.values.spacing = Vec3::Constant(h);
  long long total = 1;
  for (int k = 0; k < 3; ++k) {
    const double margin = (k == 2 ? 1.5 : 1.0) + 2.0 * h / v.s[k];  // voxels
    g.start[k] = v.lo[size_t(k)] - margin;
    const double span = (v.hi[size_t(k)] - v.lo[size_t(k)] + 2.0 * margin) * v.s[k];
    g.values.nodes[size_t(k)] = int(std::ceil(span / h)) + 1;
    total *= g.values.nodes[size_t(k)];
  }
  if (total > kMaxGridNodes)
    throw MeshError(fmt::format(
        "an edge of {:g} mm is too small for the labelled region ({:.1f} x "
        "{:.1f} x {:.1f} mm): the resampling grid would have {} nodes, "
        "over the limit of {}",
        h / kGridPerEdge, (v.hi[0] - v.lo[0] + 1) * v.s[0], (v.hi[1] - v.lo[1] + 1) * v.s[1],
        (v.hi[2] - v.lo[2] + 1) * v.s[2], total, kMaxGridNodes));
  const auto [nx, ny, nz] = g.values.nodes;
  g.values.values.resize(size_t(total));
  const double push = kPush * h;
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) {
        const double f = s.at(g.start[0] + x * h / v.s[0], g.start[1] + y * h / v.s[1],
                              g.start[2] + z * h / v.s[2]);
        // Away from zero (the surface moves < push): no sliver triangle at a grid node.
        g.values.values[size_t(x) + size_t(nx) * (size_t(y) + size_t(ny) * size_t(z))] =
            float(f < 0.0 ? std::min(f, -push) : std::max(f, push));
      }
  return g;
}

// Grid frame (mm along a, b, c) to the physical frame (m); outward kept outward.
void to_physical(Mesh& m, const View& v, const Vec3& start) {
  const LabelImage& im = v.image;
  for (Vec3& p : m.points) {
    Vec3 ijk;
    for (int k = 0; k < 3; ++k) ijk[v.axis[size_t(k)]] = start[k] + p[k] / v.s[k];
    p = im.origin + im.axes * ijk;
  }
  if (enclosed_volume(m.points, boundary_triangles(m)) < 0.0)
    for (Cell& c : m.cells) std::swap(c.nodes[1], c.nodes[2]);
}

void fill_report(const Mesh& m, const View& v, size_t voxels, LabelSurfaceReport& r) {
  r.voxels = voxels;
  r.labelled_volume = double(voxels) * std::abs(v.image.axes.determinant());
  r.slice_axis = v.axis[2];
  double volume = 0.0;
  Vec3 moment = Vec3::Zero();
  for (const Cell& c : m.cells) {
    const Vec3 &a = m.points[size_t(c.nodes[0])], &b = m.points[size_t(c.nodes[1])],
               &d = m.points[size_t(c.nodes[2])];
    const double dv = a.dot(b.cross(d)) / 6.0;  // the tetrahedron (0, a, b, d)
    volume += dv, moment += dv * (a + b + d) / 4.0;
  }
  r.surface_volume = volume;
  r.centroid = moment / volume;
  r.box = bounding_box(m.points);
}

// Stage 0: coarsened to the edge and smoothed; 1: smoothed only; 2: the zero level set as
// marching tetrahedra cut it. Each keeps the zero level set's volume (`mm`: the edge).
constexpr int kStages = 3;
Mesh clean_up(Mesh m, int stage, double mm) {
  if (stage == 2) return m;
  const double volume = enclosed_volume(m.points, boundary_triangles(m));
  for (int round = 0; stage == 0 && round < 3; ++round) {  // flips free edges for collapses
    detail::collapse_short_edges(m, kShortestEdge * mm, kLongestEdge * mm);
    detail::flip_edges(m);
    detail::taubin_smooth(m, 2);
  }
  detail::taubin_smooth(m, kTaubinIterations);
  detail::restore_volume(m, volume);
  return m;
}

}  // namespace

std::map<std::int32_t, size_t> label_counts(const LabelImage& image) {
  std::map<std::int32_t, size_t> counts;
  for (std::int32_t l : image.labels) ++counts[l];
  return counts;
}

Mesh label_surface(const LabelImage& image, std::span<const int> labels, double edge,
                   LabelSurfaceReport* report, int first_stage) {
  if (!(edge > 0.0) || !std::isfinite(edge))
    throw MeshError(fmt::format("the surface's edge must be > 0 m (got {})", edge));
  if (labels.empty()) throw MeshError("no label chosen");
  View v{image, {0, 1, 2}, {}, {}, {}, Vec3::Zero()};
  const size_t voxels = make_mask(v, labels);
  orient(v);
  const double h = kGridPerEdge * edge * 1e3;  // mm
  // Distances clamped at a slice or two grid steps: deep inside, the ends cap at the last
  // slice's outer face as the voxels do; contours moving less than that between slices are
  // interpolated exactly; the clamp keeps Catmull-Rom's overshoot small.
  const double limit = std::max(v.s[2], 2.0 * h);
  const int pad_a = int(std::ceil((limit + 2.0 * h) / v.s[0])) + 2,
            pad_b = int(std::ceil((limit + 2.0 * h) / v.s[1])) + 2;
  const Slices slices = slice_distances(v, limit, pad_a, pad_b);
  const Grid grid = resample(v, slices, h);
  detail::LargestPart part = detail::largest_part(detail::marching_tetrahedra(grid.values));
  if (part.mesh.cells.empty())
    throw MeshError(
        fmt::format("the labelled region is too small for an edge of {:g} mm: no "
                    "surface was found (choose a smaller edge)",
                    edge * 1e3));
  // The first clean-up whose surface is embedded: thin parts (a voxel wide) may fold under
  // coarsening or smoothing; the zero level set itself never intersects itself.
  std::string problems;
  for (int stage = std::clamp(first_stage, 0, kStages - 1); stage < kStages; ++stage) {
    Mesh m = clean_up(part.mesh, stage, edge * 1e3);
    to_physical(m, v, grid.start);
    SurfaceCheck check = check_closed_surface(m);
    if (check.problems.empty()) {
      if (report) {
        fill_report(m, v, voxels, *report);
        report->grid_spacing = h * 1e-3;
        report->cleanup_stage = stage;
        report->dropped_components = part.dropped;
        report->dropped_volume =
            part.dropped_volume * 1e-9 * std::abs(image.axes.determinant()) / (v.s.prod() * 1e-9);
      }
      return m;
    }
    if (problems.empty()) problems = fmt::format("{}", fmt::join(check.problems, "; "));
  }
  throw MeshError(
      fmt::format("the surface extracted from the labels is not a closed surface: {}", problems));
}

Mesh label_volume(const LabelImage& image, std::span<const int> labels, double edge,
                  LabelSurfaceReport* report, Mesh* surface) {
  LabelSurfaceReport r;
  for (int stage = 0;; stage = r.cleanup_stage + 1) {
    Mesh s = label_surface(image, labels, edge, &r, stage);
    try {
      Mesh volume = fill_with_tetrahedra(s, edge);
      if (report) *report = r;
      if (surface) *surface = std::move(s);
      return volume;
    } catch (const MeshError&) {
      // Gmsh's test of touching triangles is stricter than ours: a less smoothed surface.
      if (r.cleanup_stage + 1 >= kStages) throw;
    }
  }
}

}  // namespace phymul
