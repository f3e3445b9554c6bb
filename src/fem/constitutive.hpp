// Material laws of the reference solver, split into a deviatoric part evaluated at every Gauss
// point and a volumetric part evaluated once per element from its mean dilatation (see
// README.md for why the split matters at nu = 0.499).
#pragma once

#include <Eigen/Core>

#include "phymul/fem.hpp"

namespace phymul::fem {

using Mat3 = Eigen::Matrix3d;
// Fourth-order tangent as a 9x9 matrix: A(3 i + J, 3 k + L) = d P_iJ / d F_kL.
using Mat9 = Eigen::Matrix<double, 9, 9>;

struct Moduli {
  double mu = 0.0;     // shear modulus E / (2 (1 + nu))
  double kappa = 0.0;  // bulk modulus E / (3 (1 - 2 nu))
};

Moduli moduli(const Material& material);

// Energy density, first Piola-Kirchhoff stress and its derivative with respect to F of the
// deviatoric part of a law, at one Gauss point.
struct DeviatoricResponse {
  double energy = 0.0;
  Mat3 stress = Mat3::Zero();
  Mat9 tangent = Mat9::Zero();
};

// W = mu/2 (J^(-2/3) I1 - 3) with F = I + grad_u. Requires det F > 0.
DeviatoricResponse neo_hookean_deviatoric(const Mat3& grad_u, double mu, bool with_tangent);

// W = mu |dev eps|^2 with eps = sym(grad_u): the small-strain limit of the law above.
DeviatoricResponse linear_deviatoric(const Mat3& grad_u, double mu, bool with_tangent);

// Volumetric energy per unit reference volume U = kappa/2 (theta - 1)^2 of the element
// dilatation theta, with U' (the pressure) and U''. Takes theta - 1 to keep small
// dilatations exact.
struct VolumetricResponse {
  double energy = 0.0;
  double pressure = 0.0;
  double modulus = 0.0;
};

VolumetricResponse volumetric(double theta_minus_one, double kappa);

// det(I + H) - 1 without the cancellation of forming I + H first.
double det_minus_one(const Mat3& grad_u);

}  // namespace phymul::fem
