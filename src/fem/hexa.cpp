// Trilinear hexahedron, VTK node order, 2x2x2 Gauss quadrature.
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "fem/element.hpp"

namespace phymul::fem {

Eigen::Vector3d hexa_gauss_point(int g) {
  const double a = 1.0 / std::sqrt(3.0);
  // Gauss points follow the corner order, so point g sits next to corner g.
  return a * Eigen::Vector3d(kHexaCorners[g][0], kHexaCorners[g][1], kHexaCorners[g][2]);
}

Eigen::Matrix<double, 8, 3> hexa_local_gradient(const Eigen::Vector3d& xi) {
  Eigen::Matrix<double, 8, 3> d;
  for (int a = 0; a < 8; ++a) {
    const double s0 = kHexaCorners[a][0], s1 = kHexaCorners[a][1], s2 = kHexaCorners[a][2];
    const double f0 = 1.0 + s0 * xi[0], f1 = 1.0 + s1 * xi[1], f2 = 1.0 + s2 * xi[2];
    d(a, 0) = 0.125 * s0 * f1 * f2;
    d(a, 1) = 0.125 * f0 * s1 * f2;
    d(a, 2) = 0.125 * f0 * f1 * s2;
  }
  return d;
}

std::array<Eigen::Matrix<double, 8, 3>, 8> hexa_local_gradients() {
  std::array<Eigen::Matrix<double, 8, 3>, 8> out;
  for (int g = 0; g < 8; ++g) out[g] = hexa_local_gradient(hexa_gauss_point(g));
  return out;
}

std::array<Eigen::Matrix<double, 8, 1>, 8> hexa_shape_values() {
  std::array<Eigen::Matrix<double, 8, 1>, 8> out;
  for (int g = 0; g < 8; ++g) {
    const Eigen::Vector3d xi = hexa_gauss_point(g);
    for (int a = 0; a < 8; ++a) {
      out[g](a) = 0.125 * (1.0 + kHexaCorners[a][0] * xi[0]) * (1.0 + kHexaCorners[a][1] * xi[1]) *
                  (1.0 + kHexaCorners[a][2] * xi[2]);
    }
  }
  return out;
}

HexaReference hexa_reference(const Eigen::Matrix<double, 3, 8>& x, int cell_index) {
  static const auto local = hexa_local_gradients();
  static const auto values = hexa_shape_values();
  HexaReference ref;
  ref.nodal_volume.setZero();
  for (int g = 0; g < 8; ++g) {
    const Eigen::Matrix3d jac = x * local[g];  // dX_i / dxi_j
    const double det = jac.determinant();
    if (!(det > 0.0)) throw_bad_jacobian(CellType::hexa, cell_index, det, g);
    ref.grad[g] = local[g] * jac.inverse();
    ref.weight[g] = det;  // Gauss weights are 1
    ref.volume += det;
    ref.nodal_volume += det * values[g];
  }
  return ref;
}

void throw_bad_jacobian(CellType type, int cell_index, double det, int gauss_point) {
  std::ostringstream out;
  out << "fem: mesh.cells[" << cell_index << "] (" << cell_type_name(type)
      << ") has a non-positive Jacobian " << det << " m^3 at Gauss point " << gauss_point;
  throw std::invalid_argument(out.str());
}

}  // namespace phymul::fem
