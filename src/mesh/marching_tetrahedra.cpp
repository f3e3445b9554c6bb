#include "mesh/marching_tetrahedra.hpp"

#include <cstdint>
#include <unordered_map>

namespace phymul::detail {
namespace {

// The six tetrahedra of a cube (corner bits: x 1, y 2, z 4), each a path 0 -> 7 along edges
// (Kuhn's triangulation: translation-invariant, hence conforming between cubes).
constexpr int kTetra[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7},
                              {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};

class Extractor {
 public:
  explicit Extractor(const ScalarGrid& g) : g_(g) {}

  Mesh run() {
    const auto [nx, ny, nz] = g_.nodes;
    for (int z = 0; z + 1 < nz; ++z)
      for (int y = 0; y + 1 < ny; ++y)
        for (int x = 0; x + 1 < nx; ++x) cube(x, y, z);
    return std::move(mesh_);
  }

 private:
  size_t node(int x, int y, int z) const {
    return size_t(x) + size_t(g_.nodes[0]) * (size_t(y) + size_t(g_.nodes[1]) * size_t(z));
  }
  Vec3 position(size_t n) const {
    const size_t nx = size_t(g_.nodes[0]), ny = size_t(g_.nodes[1]);
    return Vec3(double(n % nx), double((n / nx) % ny), double(n / (nx * ny)))
        .cwiseProduct(g_.spacing);
  }
  float value(size_t n) const { return g_.values[n]; }

  // The point where the function crosses zero on the edge (a, b), made once per edge.
  int crossing(size_t a, size_t b) {
    if (a > b) std::swap(a, b);
    const std::uint64_t key = std::uint64_t(a) * g_.values.size() + b;
    const auto [it, added] = index_.try_emplace(key, int(mesh_.points.size()));
    if (added) {
      const double fa = value(a), fb = value(b);
      mesh_.points.push_back(position(a) + fa / (fa - fb) * (position(b) - position(a)));
    }
    return it->second;
  }

  // A triangle turned so that its normal points along `outward`.
  void triangle(int p, int q, int r, const Vec3& outward) {
    const Vec3& a = mesh_.points[size_t(p)];
    const Vec3 n = (mesh_.points[size_t(q)] - a).cross(mesh_.points[size_t(r)] - a);
    Cell c;
    c.type = CellType::triangle;
    c.nodes[0] = p, c.nodes[1] = n.dot(outward) >= 0.0 ? q : r,
    c.nodes[2] = n.dot(outward) >= 0.0 ? r : q;
    mesh_.cells.push_back(c);
  }

  void cube(int x, int y, int z) {
    std::array<size_t, 8> corner;
    for (int c = 0; c < 8; ++c)
      corner[size_t(c)] = node(x + (c & 1), y + ((c >> 1) & 1), z + (c >> 2));
    for (const auto& t : kTetra) {
      std::array<size_t, 4> in{}, out{};
      int n_in = 0, n_out = 0;
      for (int k : t) {
        const size_t n = corner[size_t(k)];
        (value(n) < 0.0f ? in[size_t(n_in++)] : out[size_t(n_out++)]) = n;
      }
      if (n_in == 0 || n_out == 0) continue;
      if (n_in == 1) {
        const Vec3 dir =
            position(out[0]) + position(out[1]) + position(out[2]) - 3.0 * position(in[0]);
        triangle(crossing(in[0], out[0]), crossing(in[0], out[1]), crossing(in[0], out[2]), dir);
      } else if (n_in == 3) {
        const Vec3 dir =
            3.0 * position(out[0]) - position(in[0]) - position(in[1]) - position(in[2]);
        triangle(crossing(in[0], out[0]), crossing(in[1], out[0]), crossing(in[2], out[0]), dir);
      } else {
        quad(in[0], in[1], out[0], out[1]);
      }
    }
  }

  // Inside a, b; outside c, d: the cycle ac, ad, bd, bc, split along its shorter diagonal.
  void quad(size_t a, size_t b, size_t c, size_t d) {
    const Vec3 dir = position(c) + position(d) - position(a) - position(b);
    const int ac = crossing(a, c), ad = crossing(a, d), bd = crossing(b, d), bc = crossing(b, c);
    const auto& p = mesh_.points;
    if ((p[size_t(ac)] - p[size_t(bd)]).squaredNorm() <=
        (p[size_t(ad)] - p[size_t(bc)]).squaredNorm()) {
      triangle(ac, ad, bd, dir);
      triangle(ac, bd, bc, dir);
    } else {
      triangle(ad, bd, bc, dir);
      triangle(ad, bc, ac, dir);
    }
  }

  const ScalarGrid& g_;
  Mesh mesh_;
  std::unordered_map<std::uint64_t, int> index_;
};

}  // namespace

Mesh marching_tetrahedra(const ScalarGrid& grid) { return Extractor(grid).run(); }

}  // namespace phymul::detail
