#include "model/explicit_fem_cells.hpp"

#include <fmt/format.h>

#include <Eigen/LU>
#include <cmath>
#include <stdexcept>

#include "fem/element.hpp"
#include "model/parallel_plan.hpp"

namespace phymul {
namespace {

using Mat3 = Eigen::Matrix3d;
template <int N>
using Gradient = Eigen::Matrix<double, N, 3>;

double cell_measure_at(std::span<const Vec3> rest, int first_node, const Cell& t) {
  const Vec3& a = rest[first_node + t.nodes[0]];
  return (rest[first_node + t.nodes[1]] - a)
      .cross(rest[first_node + t.nodes[2]] - a)
      .dot(rest[first_node + t.nodes[3]] - a);
}
void fail_cell(const std::string& component, int cell, double det) {
  throw std::invalid_argument(fmt::format(
      "object '{}': cell {} is inverted or degenerate for finite elements (Jacobian {:.3g})",
      component, cell, det));
}
void add_hexa(ExplicitFem& fem, const std::string& component, int cell, const Cell& c,
              int first_node, std::span<const Vec3> rest) {
  static const Gradient<8> local = ::phymul::fem::hexa_local_gradient(Vec3::Zero());
  Eigen::Matrix<double, 3, 8> X;
  for (int a = 0; a < 8; ++a) X.col(a) = rest[first_node + c.nodes[a]];
  const Mat3 jac = X * local;
  const double det = jac.determinant();
  if (!(det > 0.0)) fail_cell(component, cell, det);
  const Gradient<8> G = local * jac.inverse();
  // Flanagan-Belytschko: the hourglass base vectors made orthogonal to every linear field,
  // so rigid motions and homogeneous strains feel no hourglass force.
  constexpr auto base = ::phymul::fem::hexa_hourglass_base();
  Eigen::Matrix<double, 8, 4> h;
  for (int a = 0; a < 8; ++a)
    for (int m = 0; m < 4; ++m) h(a, m) = base[size_t(a)][size_t(m)];
  const Eigen::Matrix<double, 8, 4> gamma = h - G * (X * h);
  const double volume = 8.0 * det;
  for (int a = 0; a < 8; ++a) fem.cells.push_back(first_node + c.nodes[a]);
  for (int a = 0; a < 8; ++a)
    for (int d = 0; d < 3; ++d) fem.gradient.push_back(G(a, d));
  for (int a = 0; a < 8; ++a)
    for (int m = 0; m < 4; ++m) fem.gamma.push_back(gamma(a, m));
  fem.volume.push_back(volume);
  // Scaled by the shear modulus, not the bulk one: hourglass modes resisted with the bulk
  // stiffness lock as nu -> 0.5 (8^3 cube, nu = 0.499: top force 1.67 times the reference).
  fem.hourglass_stiffness.push_back(fem.mu * volume * G.squaredNorm() / 8.0);
}
void add_tetra(ExplicitFem& fem, const std::string& component, int cell, const Cell& c,
               int first_node, std::span<const Vec3> rest) {
  const Vec3 X0 = rest[first_node + c.nodes[0]];
  Mat3 edges;
  for (int a = 1; a < 4; ++a) edges.col(a - 1) = rest[first_node + c.nodes[a]] - X0;
  const double det = edges.determinant();
  if (!(det > 0.0)) fail_cell(component, cell, det);
  Gradient<4> G;
  G.bottomRows<3>() = edges.inverse();  // rows: gradients of the barycentric coordinates
  G.row(0) = -G.bottomRows<3>().colwise().sum();
  for (int a = 0; a < 4; ++a) fem.cells.push_back(first_node + c.nodes[a]);
  for (int a = 0; a < 4; ++a)
    for (int d = 0; d < 3; ++d) fem.gradient.push_back(G(a, d));
  fem.volume.push_back(det / 6.0);
  fem.hourglass_stiffness.push_back(0.0);
}

}  // namespace

ExplicitFem build_explicit_fem(const std::string& component, const Mesh& mesh, int first_node,
                               const MaterialSpec& material, std::span<const Vec3> rest) {
  const double young = material.young.value_or(0.0), poisson = material.poisson.value_or(0.0);
  if (!material.young || !material.poisson || !(young > 0.0) || !(poisson > -1.0 && poisson < 0.5))
    throw std::invalid_argument(fmt::format(
        "object '{}': finite elements need young > 0 Pa and poisson in (-1, 0.5) (got {}, {})",
        component, material.young ? fmt::format("{} Pa", young) : "no young",
        material.poisson ? fmt::format("{}", poisson) : "no poisson"));
  ExplicitFem fem;
  fem.component = component;
  fem.material = {material.law, young, poisson, material.hexa};
  fem.mu = young / (2.0 * (1.0 + poisson));
  fem.kappa = young / (3.0 * (1.0 - 2.0 * poisson));
  const bool hexa = !mesh.cells.empty() && mesh.cells[0].type == CellType::hexa;
  fem.nodes_per_cell = hexa ? 8 : 4;
  for (int e = 0; e < int(mesh.cells.size()); ++e) {
    const Cell& c = mesh.cells[e];
    if (hexa != (c.type == CellType::hexa) || !is_volumetric(c.type) || c.type == CellType::quad) {
      throw std::invalid_argument(fmt::format(
          "object '{}': finite elements take hexahedra alone, or tetrahedra and wedges (cell {} "
          "is {}, cell 0 is {})",
          component, e, cell_type_name(c.type), cell_type_name(mesh.cells[0].type)));
    }
    if (c.type == CellType::hexa) {
      add_hexa(fem, component, e, c, first_node, rest);
      fem.hourglass_stiffness.back() *= material.hourglass;
    } else if (c.type == CellType::tetra) {
      add_tetra(fem, component, e, c, first_node, rest);
    } else {
      for (Cell t : wedge_tetrahedra(c)) {
        if (cell_measure_at(rest, first_node, t) < 0.0) std::swap(t.nodes[1], t.nodes[2]);
        add_tetra(fem, component, e, t, first_node, rest);
      }
    }
  }
  plan_explicit_fem(fem);
  return fem;
}

void plan_explicit_fem(ExplicitFem& fem) {
  const int n = fem.nodes_per_cell;
  fem.plan = plan_blocks(int(fem.volume.size()), [&fem, n](int e, const auto& visit) {
    for (int a = 0; a < n; ++a) visit(fem.cells[size_t(e) * n + a]);
  });
}

void explicit_fem_cell_stiffness(const ExplicitFem& fem, int e, const Eigen::Matrix3d& turn,
                                 std::span<Eigen::Matrix3d> out) {
  const int n = fem.nodes_per_cell;
  const double* G = fem.gradient.data() + size_t(e) * n * 3;
  const double v = fem.volume[size_t(e)], lambda = fem.kappa - 2.0 / 3.0 * fem.mu;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      const Vec3 ga(G[3 * a], G[3 * a + 1], G[3 * a + 2]), gb(G[3 * b], G[3 * b + 1], G[3 * b + 2]);
      Mat3 k = fem.mu * (ga.dot(gb) * Mat3::Identity() + gb * ga.transpose()) +
               lambda * ga * gb.transpose();
      if (n == 8) {
        const double* g = fem.gamma.data() + size_t(e) * 32;
        double gg = 0.0;
        for (int m = 0; m < 4; ++m) gg += g[4 * a + m] * g[4 * b + m];
        k += fem.hourglass_stiffness[size_t(e)] / v * gg * Mat3::Identity();
      }
      out[size_t(a * n + b)] = v * turn * k * turn.transpose();
    }
}

void add_explicit_fem_rows(const ExplicitFem& fem, std::span<double> row) {
  // |K_ab| <= (kappa + 4/3 mu) V |grad N_a|_1 |grad N_b|_1 for the material part at rest,
  // plus the hourglass part k |gamma gamma^T|_ab.
  const int n = fem.nodes_per_cell;
  const double p_modulus = fem.kappa + 4.0 / 3.0 * fem.mu;
  for (int e = 0; e < int(fem.volume.size()); ++e) {
    const double* G = fem.gradient.data() + size_t(e) * n * 3;
    double total = 0.0;
    for (int b = 0; b < n; ++b)
      total += std::abs(G[3 * b]) + std::abs(G[3 * b + 1]) + std::abs(G[3 * b + 2]);
    for (int a = 0; a < n; ++a) {
      const double own = std::abs(G[3 * a]) + std::abs(G[3 * a + 1]) + std::abs(G[3 * a + 2]);
      double r = p_modulus * fem.volume[e] * own * total;
      if (n == 8) {
        const double* g = fem.gamma.data() + size_t(e) * 32;
        for (int b = 0; b < 8; ++b) {
          double gg = 0.0;
          for (int m = 0; m < 4; ++m) gg += g[4 * a + m] * g[4 * b + m];
          r += fem.hourglass_stiffness[e] * std::abs(gg);
        }
      }
      row[fem.cells[size_t(e) * n + a]] += r;
    }
  }
}

}  // namespace phymul
