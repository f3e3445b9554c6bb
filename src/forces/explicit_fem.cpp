#include "forces/explicit_fem.hpp"

#include <fmt/format.h>

#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "fem/constitutive.hpp"
#include "fem/element.hpp"
#include "forces/shape_memory.hpp"
#include "model/parallel_plan.hpp"

namespace phymul {
namespace {

using Mat3 = Eigen::Matrix3d;
template <int N>
using Gradient = Eigen::Matrix<double, N, 3>;

template <int N>
inline Mat3 displacement_gradient(const ExplicitFem& fem, int e, std::span<const Vec3> rest,
                                  std::span<const Vec3> x, Eigen::Matrix<double, 3, N>& U) {
  const int* nodes = fem.cells.data() + size_t(e) * N;
  const Eigen::Map<const Eigen::Matrix<double, N, 3, Eigen::RowMajor>> G(fem.gradient.data() +
                                                                         size_t(e) * N * 3);
  for (int a = 0; a < N; ++a) U.col(a) = x[nodes[a]] - rest[nodes[a]];
  return U * G;
}

// Internal forces of one cell: -V P grad N (P the first Piola-Kirchhoff stress), plus the
// hourglass forces; returns the cell's energy, NaN where the cell is inverted.
template <int N>
double cell_forces(const ExplicitFem& fem, int e, std::span<const Vec3> rest,
                   std::span<const Vec3> x, std::span<Vec3> f) {
  const int* nodes = fem.cells.data() + size_t(e) * N;
  const Eigen::Map<const Eigen::Matrix<double, N, 3, Eigen::RowMajor>> G(fem.gradient.data() +
                                                                         size_t(e) * N * 3);
  Eigen::Matrix<double, 3, N> U;
  const Mat3 grad_u = displacement_gradient<N>(fem, e, rest, x, U);
  const Mat3 F = Mat3::Identity() + grad_u;
  const double j_minus_one = ::phymul::fem::det_minus_one(grad_u);
  const double J = 1.0 + j_minus_one;
  // F^-T = cof(F) / J, the cofactors' columns the cross products of F's.
  Mat3 H;
  H.col(0) = F.col(1).cross(F.col(2));
  H.col(1) = F.col(2).cross(F.col(0));
  H.col(2) = F.col(0).cross(F.col(1));
  H /= J;
  const double i1 = F.squaredNorm();
  const double cube_root = std::cbrt(J);
  const double jm23 = 1.0 / (cube_root * cube_root);
  const Mat3 P = fem.mu * jm23 * (F - (i1 / 3.0) * H) + fem.kappa * J * j_minus_one * H;
  const double volume = fem.volume[e];
  Eigen::Matrix<double, 3, N> fe = -volume * P * G.transpose();
  double energy =
      volume * (0.5 * fem.mu * (jm23 * i1 - 3.0) + 0.5 * fem.kappa * j_minus_one * j_minus_one);
  if constexpr (N == 8) {
    const Eigen::Map<const Eigen::Matrix<double, 8, 4, Eigen::RowMajor>> gamma(fem.gamma.data() +
                                                                               size_t(e) * 32);
    const Eigen::Matrix<double, 3, 4> q = U * gamma;
    const double k = fem.hourglass_stiffness[e];
    fe.noalias() -= k * q * gamma.transpose();
    energy += 0.5 * k * q.squaredNorm();
  }
  for (int a = 0; a < N; ++a) f[nodes[a]] += fe.col(a);
  // cbrt keeps the sign, so an inverted cell's stress is finite: the energy carries the alarm
  // (the simulator's check reads it; a step with it is undone).
  return J > 0.0 ? energy : std::numeric_limits<double>::quiet_NaN();
}

template <int N>
void fit_rotations(const ExplicitFem& fem, std::span<const Vec3> rest, std::span<const Vec3> x,
                   std::span<Eigen::Quaterniond> rotation) {
  Eigen::Matrix<double, 3, N> U;
  for (int e = 0; e < int(fem.volume.size()); ++e)
    extract_rotation(Mat3::Identity() + displacement_gradient<N>(fem, e, rest, x, U),
                     rotation[size_t(e)]);
}

template <int N>
InvertedCell first_inverted(const ExplicitFem& fem, std::span<const Vec3> rest,
                            std::span<const Vec3> x) {
  Eigen::Matrix<double, 3, N> U;
  for (int e = 0; e < int(fem.volume.size()); ++e) {
    const double J =
        1.0 + ::phymul::fem::det_minus_one(displacement_gradient<N>(fem, e, rest, x, U));
    if (!(J > 0.0)) return {e, J, std::span<const int>(fem.cells.data() + size_t(e) * N, N)};
  }
  return {};
}

}  // namespace

double add_explicit_fem_forces(const ExplicitFem& fem, std::span<const Vec3> rest,
                               std::span<const Vec3> x, std::span<Vec3> f,
                               std::span<double> blocks) {
  if (fem.nodes_per_cell == 8)
    return run_coloured(fem.plan, blocks,
                        [&](int e) { return cell_forces<8>(fem, e, rest, x, f); });
  return run_coloured(fem.plan, blocks, [&](int e) { return cell_forces<4>(fem, e, rest, x, f); });
}

void fit_cell_rotations(const ExplicitFem& fem, std::span<const Vec3> rest, std::span<const Vec3> x,
                        std::span<Eigen::Quaterniond> rotation) {
  if (fem.nodes_per_cell == 8) return fit_rotations<8>(fem, rest, x, rotation);
  fit_rotations<4>(fem, rest, x, rotation);
}

InvertedCell first_inverted_cell(const ExplicitFem& fem, std::span<const Vec3> rest,
                                 std::span<const Vec3> x) {
  return fem.nodes_per_cell == 8 ? first_inverted<8>(fem, rest, x)
                                 : first_inverted<4>(fem, rest, x);
}

}  // namespace phymul
