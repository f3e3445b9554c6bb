#include "model/embedding.hpp"

#include <algorithm>

namespace phymul {

std::vector<std::array<int, 4>> cell_tetrahedra(const Model& model, int component) {
  // Six tetrahedra around the 0-6 diagonal of a VTK hexahedron; three of a VTK wedge.
  static constexpr int kHexa[6][4] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6},
                                      {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
  static constexpr int kWedge[3][4] = {{0, 1, 2, 3}, {1, 2, 3, 4}, {2, 3, 4, 5}};
  const Component& c = model.components[size_t(component)];
  std::vector<std::array<int, 4>> out;
  for (int k = c.first_cell; k < c.first_cell + c.cell_count; ++k) {
    const Cell& cell = model.cells[size_t(k)];
    auto add = [&](const int(&corners)[4]) {
      out.push_back({cell.nodes[size_t(corners[0])], cell.nodes[size_t(corners[1])],
                     cell.nodes[size_t(corners[2])], cell.nodes[size_t(corners[3])]});
    };
    if (cell.type == CellType::tetra)
      add({0, 1, 2, 3});
    else if (cell.type == CellType::hexa)
      for (const auto& t : kHexa) add(t);
    else if (cell.type == CellType::wedge)
      for (const auto& t : kWedge) add(t);
  }
  return out;
}

bool barycentric(const std::array<int, 4>& tet, std::span<const Vec3> x, const Vec3& p,
                 std::array<double, 4>& weights) {
  const Vec3& a = x[size_t(tet[0])];
  Eigen::Matrix3d m;
  m.col(0) = x[size_t(tet[1])] - a;
  m.col(1) = x[size_t(tet[2])] - a;
  m.col(2) = x[size_t(tet[3])] - a;
  const double det = m.determinant();
  const double scale = m.col(0).norm() * m.col(1).norm() * m.col(2).norm();
  if (!(std::abs(det) > 1e-12 * scale)) return false;
  const Vec3 w = m.inverse() * (p - a);
  weights = {1.0 - w.sum(), w.x(), w.y(), w.z()};
  return true;
}

bool embed_point(std::span<const std::array<int, 4>> tetrahedra, std::span<const Vec3> x,
                 const Vec3& p, EmbeddedPoint& out, double tolerance) {
  std::array<double, 4> w{};
  for (const std::array<int, 4>& t : tetrahedra) {
    // A box test first: most tetrahedra are far from p.
    Vec3 lo = x[size_t(t[0])], hi = lo;
    for (int k = 1; k < 4; ++k) {
      lo = lo.cwiseMin(x[size_t(t[size_t(k)])]);
      hi = hi.cwiseMax(x[size_t(t[size_t(k)])]);
    }
    const Vec3 pad = Vec3::Constant(tolerance * (hi - lo).maxCoeff());
    if ((p.array() < (lo - pad).array()).any() || (p.array() > (hi + pad).array()).any()) continue;
    if (!barycentric(t, x, p, w)) continue;
    if (*std::min_element(w.begin(), w.end()) < -tolerance) continue;
    out.nodes = t;
    out.weights = w;
    return true;
  }
  return false;
}

}  // namespace phymul
