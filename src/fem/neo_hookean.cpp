// Compressible Neo-Hookean law, deviatoric/volumetric split:
//   W = mu/2 (Ibar1 - 3) + kappa/2 (J - 1)^2,  Ibar1 = J^(-2/3) I1.
// Only the deviatoric part lives here; the volumetric part is evaluated per element with the
// mean dilatation (element.cpp).
#include <cmath>

#include "fem/constitutive.hpp"

namespace phymul::fem {

Moduli moduli(const Material& material) {
  const double e = material.young;
  const double nu = material.poisson;
  return {e / (2.0 * (1.0 + nu)), e / (3.0 * (1.0 - 2.0 * nu))};
}

double det_minus_one(const Mat3& h) {
  const double trace = h.trace();
  const double second = 0.5 * (trace * trace - (h * h).trace());
  return trace + second + h.determinant();
}

VolumetricResponse volumetric(double theta_minus_one, double kappa) {
  return {0.5 * kappa * theta_minus_one * theta_minus_one, kappa * theta_minus_one, kappa};
}

namespace {

// dP/dF of P = c (F - I1/3 F^-T), c = mu J^(-2/3), written with H = F^-T:
//   A_iJkL = c [d_ik d_JL - 2/3 (F - I1/3 H)_iJ H_kL - 2/3 H_iJ F_kL + I1/3 H_iL H_kJ].
Mat9 neo_hookean_tangent(const Mat3& f, const Mat3& h, double c, double i1) {
  Mat9 a;
  const Mat3 dev = f - (i1 / 3.0) * h;
  for (int i = 0; i < 3; ++i) {
    for (int jj = 0; jj < 3; ++jj) {
      for (int k = 0; k < 3; ++k) {
        for (int l = 0; l < 3; ++l) {
          const double identity = (i == k && jj == l) ? 1.0 : 0.0;
          a(3 * i + jj, 3 * k + l) =
              c * (identity - (2.0 / 3.0) * (dev(i, jj) * h(k, l) + h(i, jj) * f(k, l)) +
                   (i1 / 3.0) * h(i, l) * h(k, jj));
        }
      }
    }
  }
  return a;
}

}  // namespace

DeviatoricResponse neo_hookean_deviatoric(const Mat3& grad_u, double mu, bool with_tangent) {
  const Mat3 f = Mat3::Identity() + grad_u;
  const double j_minus_one = det_minus_one(grad_u);
  // J^(-2/3) - 1 and I1 - 3 formed without cancellation, so that small strains keep their
  // relative accuracy in the energy.
  const double jm23_minus_one = std::expm1(-2.0 / 3.0 * std::log1p(j_minus_one));
  const double i1_minus_3 = 2.0 * grad_u.trace() + grad_u.squaredNorm();
  const double jm23 = 1.0 + jm23_minus_one;
  const double i1 = 3.0 + i1_minus_3;
  const double c = mu * jm23;
  const Mat3 h = f.inverse().transpose();

  DeviatoricResponse out;
  out.energy = 0.5 * mu * (3.0 * jm23_minus_one + jm23 * i1_minus_3);
  out.stress = c * (f - (i1 / 3.0) * h);
  if (with_tangent) out.tangent = neo_hookean_tangent(f, h, c, i1);
  return out;
}

}  // namespace phymul::fem
