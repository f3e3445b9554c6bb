#include "forces/explicit_fem.hpp"

#include <fmt/format.h>

#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "fem/constitutive.hpp"
#include "fem/element.hpp"
#include "forces/lane_io.hpp"
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

// The lane kernel's helpers: the four cells' constants as lanes, a 3x3 determinant.
namespace {
namespace hexa_lanes {

using namespace lanes;
using V3 = lanes::V3<D>;

// The four cells' value at offset k of their per-cell records of `stride` doubles.
PHYMUL_LANES D across(const double* first, int stride, int k) {
  return D{first[k], first[stride + k], first[2 * stride + k], first[3 * stride + k]};
}

PHYMUL_LANES D det(const D (&m)[3][3]) {
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
         m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

// The hourglass base vectors, as add_hexa takes them.
constexpr auto kHourglassSigns = ::phymul::fem::hexa_hourglass_base();

// J^(-2/3), the deviatoric scale. Near J = 1 (|J - 1| <= 1/4: every sound cell of a soft
// tissue under a surgical load) y = J^(-1/3) from its cubic Taylor start (6e-4 off at the
// range's ends) and three division-free Newton steps y += y (1 - J y^3) / 3, each of which
// squares the error (to round-off); elsewhere std::cbrt. Four scalar cube roots and their
// divisions took a tenth of the cell's time.
PHYMUL_LANES D inverse_cube_root_squared(const D& J, const D& j_minus_one) {
  D y;
  if (all((j_minus_one <= 0.25) & (j_minus_one >= -0.25))) {
    const D t = j_minus_one;
    y = 1.0 + t * (-1.0 / 3.0 + t * (2.0 / 9.0 + t * (-14.0 / 81.0)));
    for (int k = 0; k < 3; ++k) y += y * (1.0 - J * (y * y * y)) * (1.0 / 3.0);
  } else {
    for (int l = 0; l < W; ++l) y[l] = 1.0 / std::cbrt(J[l]);
  }
  return y * y;
}

}  // namespace hexa_lanes
}  // namespace

double add_four_hexahedra_forces(const ExplicitFem& fem, int e, std::span<const Vec3> rest,
                                 std::span<const Vec3> x, std::span<Vec3> f) {
  using namespace lanes;
  using namespace hexa_lanes;
  using V3 = lanes::V3<D>;
  const int* nodes = fem.cells.data() + size_t(e) * 8;
  const double* G = fem.gradient.data() + size_t(e) * 24;
  V3 U[8], X[8];
  for (int a = 0; a < 8; ++a) {
    const int id[W] = {nodes[a], nodes[8 + a], nodes[16 + a], nodes[24 + a]};
    X[a] = gather(rest, id);
    U[a] = gather(x, id) - X[a];
  }
  D grad_u[3][3] = {};
  for (int a = 0; a < 8; ++a)
    for (int c = 0; c < 3; ++c) {
      const D g = across(G, 24, 3 * a + c);
      for (int i = 0; i < 3; ++i) grad_u[i][c] += U[a].v[i] * g;
    }
  // J - 1 as fem::det_minus_one: the trace, the second invariant and the determinant of grad u.
  const D trace = grad_u[0][0] + grad_u[1][1] + grad_u[2][2];
  D square_trace{};
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) square_trace += grad_u[i][k] * grad_u[k][i];
  const D j_minus_one = trace + 0.5 * (trace * trace - square_trace) + det(grad_u);
  const D J = 1.0 + j_minus_one;
  D F[3][3];
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) F[i][k] = grad_u[i][k] + (i == k ? 1.0 : 0.0);
  // F^-T = cof(F) / J: column c the cross product of F's columns c + 1 and c + 2.
  D H[3][3], i1{};
  const D inverse_J = 1.0 / J;
  for (int c = 0; c < 3; ++c) {
    const int p = (c + 1) % 3, q = (c + 2) % 3;
    for (int i = 0; i < 3; ++i) {
      const int r = (i + 1) % 3, s = (i + 2) % 3;
      H[i][c] = (F[r][p] * F[s][q] - F[s][p] * F[r][q]) * inverse_J;
      i1 += F[i][c] * F[i][c];
    }
  }
  const D jm23 = inverse_cube_root_squared(J, j_minus_one);
  const D mu = splat(fem.mu), kappa = splat(fem.kappa);
  const D deviatoric = mu * jm23, third = i1 / 3.0, volumetric = kappa * J * j_minus_one;
  const D volume = across(fem.volume.data() + e, 1, 0);
  D P[3][3];
  for (int i = 0; i < 3; ++i)
    for (int c = 0; c < 3; ++c)
      P[i][c] = -volume * (deviatoric * (F[i][c] - third * H[i][c]) + volumetric * H[i][c]);
  D energy = volume * (0.5 * mu * (jm23 * i1 - 3.0) + 0.5 * kappa * j_minus_one * j_minus_one);
  // The hourglass modes' amplitudes q = U gamma and their forces -k q gamma^T, with
  // gamma = h - G (X h) (add_hexa's) spelled out: q = U h - grad u (X h), and the forces'
  // -k q h_a and k q (X h)^T G_a, the latter folded into P. The corner signs h are constants
  // and X h comes from the rest corners already gathered: the cell's 32 hourglass values (of
  // its 58 constants) are neither read nor assembled lane by lane.
  D Xh[3][4] = {}, q[3][4] = {};
  for (int a = 1; a < 8; ++a)  // about corner 0 (sum_a h_a = 0): offsets as small as the cell
    for (int m = 0; m < 4; ++m)
      for (int d = 0; d < 3; ++d)
        Xh[d][m] += kHourglassSigns[size_t(a)][size_t(m)] * (X[a].v[d] - X[0].v[d]);
  for (int a = 0; a < 8; ++a)
    for (int m = 0; m < 4; ++m)
      for (int i = 0; i < 3; ++i) q[i][m] += kHourglassSigns[size_t(a)][size_t(m)] * U[a].v[i];
  for (int i = 0; i < 3; ++i)
    for (int m = 0; m < 4; ++m)
      for (int d = 0; d < 3; ++d) q[i][m] -= grad_u[i][d] * Xh[d][m];
  const D k = across(fem.hourglass_stiffness.data() + e, 1, 0);
  D q2{};
  for (int i = 0; i < 3; ++i)
    for (int m = 0; m < 4; ++m) q2 += q[i][m] * q[i][m], q[i][m] *= k;
  energy += 0.5 * k * q2;
  for (int i = 0; i < 3; ++i)
    for (int d = 0; d < 3; ++d)
      for (int m = 0; m < 4; ++m) P[i][d] += q[i][m] * Xh[d][m];
  // Node a's force: -V P grad N_a - k q gamma_a, as rows, added cell by cell.
  alignas(32) D rows[8][W];
  for (int a = 0; a < 8; ++a) {
    V3 fa;
    for (int i = 0; i < 3; ++i) {
      D sum = P[i][0] * across(G, 24, 3 * a) + P[i][1] * across(G, 24, 3 * a + 1) +
              P[i][2] * across(G, 24, 3 * a + 2);
      for (int m = 0; m < 4; ++m) sum -= kHourglassSigns[size_t(a)][size_t(m)] * q[i][m];
      fa.v[i] = sum;
    }
    store_rows(fa, &rows[a][0], 1);
  }
  double total = 0.0;
  double* const forces = f.data()->data();
  for (int l = 0; l < W; ++l) {
    for (int a = 0; a < 8; ++a) {
      const double* row = reinterpret_cast<const double*>(&rows[a][l]);
      double* p = forces + 3 * nodes[8 * l + a];
      p[0] += row[0], p[1] += row[1], p[2] += row[2];
    }
    total += J[l] > 0.0 ? energy[l] : std::numeric_limits<double>::quiet_NaN();
  }
  return total;
}

double add_hexahedron_forces(const ExplicitFem& fem, int e, std::span<const Vec3> rest,
                             std::span<const Vec3> x, std::span<Vec3> f) {
  return cell_forces<8>(fem, e, rest, x, f);
}

double add_explicit_fem_forces(const ExplicitFem& fem, std::span<const Vec3> rest,
                               std::span<const Vec3> x, std::span<Vec3> f,
                               std::span<double> blocks) {
  if (fem.nodes_per_cell == 8)
    return run_coloured_blocks(fem.plan, blocks, [&](int b) {
      // Four cells at a time, the block's last few one by one: the same cells in the same
      // order as cell_forces<8> over the block.
      double energy = 0.0;
      int e = fem.plan.block_start[b];
      const int end = fem.plan.block_start[b + 1];
      for (; e + lanes::W <= end; e += lanes::W)
        energy += add_four_hexahedra_forces(fem, e, rest, x, f);
      for (; e < end; ++e) energy += cell_forces<8>(fem, e, rest, x, f);
      return energy;
    });
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
