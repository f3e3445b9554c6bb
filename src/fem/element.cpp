// Element kernel: deviatoric energy at every Gauss point, volumetric energy once per element
// from the mean dilatation theta = v / V (Q1/P0, Simo-Taylor-Pister; see README.md):
//   Pi_e = sum_g w_g W_dev(F_g) + V U(theta),  v = sum_g w_g J_g.
// Everything derives from this one energy, so the tangent is its exact Hessian (symmetric).
#include "fem/element.hpp"

#include "fem/element_blocks.hpp"

namespace phymul::fem {

namespace {

// p d2J/dx_ai dx_bk = p J (n_ai n_bk - n_ak n_bi), n = spatial gradients of the shape
// functions; `scale` = w p J.
template <int NN>
void add_volumetric_geometric(Stiffness<NN>& k, const Eigen::Matrix<double, NN, 3>& n,
                              double scale) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (i == j) continue;
      node_block<NN>(k, i, j).noalias() +=
          scale * (n.col(i) * n.col(j).transpose() - n.col(j) * n.col(i).transpose());
    }
  }
}

}  // namespace

template <int NN, int NG>
bool evaluate_element(const ElementReference<NN, NG>& ref, const Eigen::Matrix<double, 3, NN>& u,
                      const LawConstants& law, bool with_tangent, ElementResult<NN>& out) {
  const bool finite_strain = law.law == Law::neo_hookean;
  std::array<Mat3, NG> grad_u;
  std::array<double, NG> j_minus_one;
  double volume_change = 0.0;  // v - V, summed without cancellation
  for (int g = 0; g < NG; ++g) {
    grad_u[g] = u * ref.grad[g];
    // Geometrically linear: the volume change is the linearised one, tr(grad u).
    j_minus_one[g] = finite_strain ? det_minus_one(grad_u[g]) : grad_u[g].trace();
    if (finite_strain && !(j_minus_one[g] > -1.0)) return false;
    volume_change += ref.weight[g] * j_minus_one[g];
  }
  const VolumetricResponse vol = volumetric(volume_change / ref.volume, law.moduli.kappa);

  out.energy = ref.volume * vol.energy;
  out.force.setZero();
  if (with_tangent) out.stiffness.setZero();
  Eigen::Matrix<double, 3, NN> dv_dx = Eigen::Matrix<double, 3, NN>::Zero();
  for (int g = 0; g < NG; ++g) {
    const double w = ref.weight[g];
    const auto& grad = ref.grad[g];
    const DeviatoricResponse dev =
        finite_strain ? neo_hookean_deviatoric(grad_u[g], law.moduli.mu, with_tangent)
                      : linear_deviatoric(grad_u[g], law.moduli.mu, with_tangent);
    out.energy += w * dev.energy;
    out.force.noalias() += (w * dev.stress) * grad.transpose();
    if (with_tangent) add_material<NN>(out.stiffness, grad, dev.tangent, w);
    if (!finite_strain) {
      dv_dx.noalias() += w * grad.transpose();
      continue;
    }
    // dJ/dx_a = J F^-T dN_a/dX = J n_a.
    const double j = 1.0 + j_minus_one[g];
    const Mat3 f_inv = (Mat3::Identity() + grad_u[g]).inverse();
    const Eigen::Matrix<double, NN, 3> n = grad * f_inv;
    dv_dx.noalias() += (w * j) * n.transpose();
    if (with_tangent) add_volumetric_geometric<NN>(out.stiffness, n, w * j * vol.pressure);
  }
  out.force += vol.pressure * dv_dx;
  if (with_tangent) {
    const Eigen::Map<const Eigen::Matrix<double, 3 * NN, 1>> g(dv_dx.data());
    out.stiffness.noalias() += (vol.modulus / ref.volume) * g * g.transpose();
  }
  return true;
}

template bool evaluate_element<8, 8>(const HexaReference&, const Eigen::Matrix<double, 3, 8>&,
                                     const LawConstants&, bool, ElementResult<8>&);
template bool evaluate_element<4, 1>(const TetraReference&, const Eigen::Matrix<double, 3, 4>&,
                                     const LawConstants&, bool, ElementResult<4>&);

}  // namespace phymul::fem
