// Small-strain linear elasticity, deviatoric part: W = mu |dev eps|^2, sigma = 2 mu dev eps.
// Geometrically linear: grad_u is taken with respect to the reference configuration and the
// stress is used as if it were a first Piola-Kirchhoff stress, so the element code is shared
// with the Neo-Hookean law (of which this is the linearisation at F = I).
#include "fem/constitutive.hpp"

namespace phymul::fem {

namespace {

// A_iJkL = mu (d_ik d_JL + d_iL d_Jk - 2/3 d_iJ d_kL): constant, hence one Newton iteration.
Mat9 linear_tangent(double mu) {
  Mat9 a = Mat9::Zero();
  for (int i = 0; i < 3; ++i) {
    for (int jj = 0; jj < 3; ++jj) {
      for (int k = 0; k < 3; ++k) {
        for (int l = 0; l < 3; ++l) {
          const double v = (i == k && jj == l ? 1.0 : 0.0) + (i == l && jj == k ? 1.0 : 0.0) -
                           (i == jj && k == l ? 2.0 / 3.0 : 0.0);
          a(3 * i + jj, 3 * k + l) = mu * v;
        }
      }
    }
  }
  return a;
}

}  // namespace

DeviatoricResponse linear_deviatoric(const Mat3& grad_u, double mu, bool with_tangent) {
  const Mat3 strain = 0.5 * (grad_u + grad_u.transpose());
  const Mat3 dev = strain - (strain.trace() / 3.0) * Mat3::Identity();
  DeviatoricResponse out;
  out.energy = mu * dev.squaredNorm();
  out.stress = 2.0 * mu * dev;
  if (with_tangent) out.tangent = linear_tangent(mu);
  return out;
}

}  // namespace phymul::fem
