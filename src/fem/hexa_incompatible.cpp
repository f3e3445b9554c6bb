// Trilinear hexahedron enriched with Wilson's incompatible modes (Wilson, Taylor, Doherty,
// Ghaboussi 1973), as CalculiX builds its C3D8I: three bubble modes P_k = 1 - xi_k^2, each
// with a displacement vector of its own, their gradients taken with the Jacobian at the
// element centre and scaled by det J0 / det J (Taylor, Beresford, Wilson 1976: then the modes
// integrate to zero over any element, so a homogeneous deformation leaves them at rest and
// the element passes the patch test); full 2x2x2 integration and the law evaluated
// pointwise, volumetric part included. CalculiX omits the scaling, which only matters when
// det J varies inside an element: on parallelepipeds (the cubes we compare on) the two are
// the same element.
//
// Why a second hexahedron: it is the element CalculiX's cross-check runs, so the two codes
// then discretise the same energy and must agree to their solver tolerances, node by node;
// with our mean-dilatation element they differ by the element technology (up to 3.5 % of the
// plate travel on the bonded 8^3 cube, at the singular edges). The modes let the element bend
// and relieve most of the volumetric locking of plain full integration.
//
// The nine mode amplitudes belong to one element, so they are condensed out: for given nodal
// displacements a local Newton solve makes the energy stationary in them, and the element
// passes on the force at that point and the Schur complement K_uu - K_ua K_aa^-1 K_au, which
// is the exact tangent of the condensed energy.
#include <Eigen/Cholesky>
#include <cmath>

#include "fem/element.hpp"
#include "fem/element_blocks.hpp"

namespace phymul::fem {

namespace {

constexpr int kNodes = 8, kAll = 11;

// Volumetric part of the law at one Gauss point (the deviatoric part is
// neo_hookean_deviatoric or linear_deviatoric), as energy, stress and tangent.
DeviatoricResponse pointwise_volumetric(const Mat3& grad_u, double kappa, bool finite_strain) {
  DeviatoricResponse out;
  if (!finite_strain) {  // U = kappa/2 tr(eps)^2
    const double tr = grad_u.trace();
    out.energy = 0.5 * kappa * tr * tr;
    out.stress = kappa * tr * Mat3::Identity();
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) out.tangent(3 * i + i, 3 * k + k) = kappa;
    return out;
  }
  // U = kappa/2 (J - 1)^2, P = kappa (J - 1) J F^-T; with H = F^-T,
  // dP_iJ/dF_kL = kappa (2J - 1) J H_iJ H_kL - kappa (J - 1) J H_iL H_kJ.
  const double jm1 = det_minus_one(grad_u);
  const double j = 1.0 + jm1;
  const Mat3 h = (Mat3::Identity() + grad_u).inverse().transpose();
  out.energy = 0.5 * kappa * jm1 * jm1;
  out.stress = kappa * jm1 * j * h;
  for (int i = 0; i < 3; ++i)
    for (int jj = 0; jj < 3; ++jj)
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l)
          out.tangent(3 * i + jj, 3 * k + l) =
              kappa * j * ((2.0 * j - 1.0) * h(i, jj) * h(k, l) - jm1 * h(i, l) * h(k, jj));
  return out;
}

// The whole law at one Gauss point: energy density, stress and tangent. False when the
// deformation inverts the point.
bool point_response(const Mat3& grad_u, const LawConstants& law, DeviatoricResponse& out) {
  const bool finite_strain = law.law == Law::neo_hookean;
  if (finite_strain && !(det_minus_one(grad_u) > -1.0)) return false;
  out = finite_strain ? neo_hookean_deviatoric(grad_u, law.moduli.mu, true)
                      : linear_deviatoric(grad_u, law.moduli.mu, true);
  const DeviatoricResponse vol = pointwise_volumetric(grad_u, law.moduli.kappa, finite_strain);
  out.energy += vol.energy;
  out.stress += vol.stress;
  out.tangent += vol.tangent;
  return true;
}

// Energy, force on the 8 nodes and 3 modes, and the 33 x 33 tangent.
bool evaluate_enriched(const IncompatibleHexaReference& ref,
                       const Eigen::Matrix<double, 3, kAll>& u, const LawConstants& law,
                       ElementResult<kAll>& out) {
  out.energy = 0.0;
  out.force.setZero();
  out.stiffness.setZero();
  DeviatoricResponse p;
  for (int g = 0; g < 8; ++g) {
    if (!point_response(u * ref.grad[g], law, p)) return false;
    const double w = ref.weight[g];
    out.energy += w * p.energy;
    out.force.noalias() += (w * p.stress) * ref.grad[g].transpose();
    add_material<kAll>(out.stiffness, ref.grad[g], p.tangent, w);
  }
  return true;
}

using ModeVector = Eigen::Matrix<double, 9, 1>;

// What the local solve needs, a ninth of the full tangent's work: the energy, the force on
// the modes (index 3 k + axis) and their 9 x 9 block.
struct ModeState {
  double energy = 0.0;
  ModeVector force = ModeVector::Zero();
  Stiffness<3> hessian = Stiffness<3>::Zero();
};

bool evaluate_modes(const IncompatibleHexaReference& ref, const Eigen::Matrix<double, 3, kAll>& u,
                    const LawConstants& law, ModeState& out) {
  out = ModeState{};
  Eigen::Map<Mat3> force(out.force.data());
  DeviatoricResponse p;
  for (int g = 0; g < 8; ++g) {
    if (!point_response(u * ref.grad[g], law, p)) return false;
    const double w = ref.weight[g];
    const Mat3 modes_grad = ref.grad[g].bottomRows<3>();
    out.energy += w * p.energy;
    force.noalias() += (w * p.stress) * modes_grad.transpose();
    add_material<3>(out.hessian, modes_grad, p.tangent, w);
  }
  return true;
}

}  // namespace

IncompatibleHexaReference incompatible_hexa_reference(const Eigen::Matrix<double, 3, 8>& x,
                                                      int cell_index) {
  const HexaReference hexa = hexa_reference(x, cell_index);
  const Eigen::Matrix3d centre = x * hexa_local_gradient(Vec3::Zero());  // dX/dxi
  const Eigen::Matrix3d centre_inverse = centre.inverse();
  const double centre_det = centre.determinant();
  IncompatibleHexaReference ref;
  ref.volume = hexa.volume;
  ref.nodal_volume.setZero();  // the modes carry no body force (as in CalculiX)
  ref.nodal_volume.head<kNodes>() = hexa.nodal_volume;
  for (int g = 0; g < 8; ++g) {
    const Vec3 xi = hexa_gauss_point(g);
    ref.weight[g] = hexa.weight[g];
    ref.grad[g].topRows<kNodes>() = hexa.grad[g];
    const double scale = centre_det / hexa.weight[g];  // Gauss weights are 1
    for (int k = 0; k < 3; ++k)  // dP_k/dxi = -2 xi_k e_k, mapped by the centre Jacobian
      ref.grad[g].row(kNodes + k) = -2.0 * xi[k] * scale * centre_inverse.row(k);
  }
  return ref;
}

bool evaluate_incompatible_hexa(const IncompatibleHexaReference& ref,
                                const Eigen::Matrix<double, 3, 8>& u, const LawConstants& law,
                                bool with_tangent, ModeAmplitudes& modes, ElementResult<8>& out) {
  // Minimises the element energy over the modes from their last solution: Newton steps,
  // shifted towards gradient steps (K_aa + shift I) where K_aa is not positive definite or a
  // step would raise the energy or invert the element (far from equilibrium the energy is
  // not convex in the modes). Converged when a plain Newton step is below 1e-12 of the
  // element size: the force error is then of the order of round-off.
  constexpr int kMaxIterations = 60;
  const double small_step = 1e-12 * std::cbrt(ref.volume);
  Eigen::Matrix<double, 3, kAll> full;
  full.leftCols<kNodes>() = u;
  full.rightCols<3>() = modes;
  ModeState r, trial;
  if (!evaluate_modes(ref, full, law, r)) return false;
  Eigen::LDLT<Eigen::Matrix<double, 9, 9>> kaa;
  double shift = 0.0;
  for (int it = 0;; ++it) {
    if (it == kMaxIterations) return false;
    const double scale = r.hessian.diagonal().cwiseAbs().maxCoeff();
    kaa.compute(r.hessian + shift * Eigen::Matrix<double, 9, 9>::Identity());
    if (kaa.info() != Eigen::Success || !kaa.isPositive()) {
      shift = std::max(4.0 * shift, 1e-6 * scale);
      continue;
    }
    const ModeVector step = -kaa.solve(r.force);
    if (!step.allFinite()) return false;
    if (shift == 0.0 && step.lpNorm<Eigen::Infinity>() <= small_step) break;
    Eigen::Matrix<double, 3, kAll> next = full;
    next.rightCols<3>() += Eigen::Map<const Mat3>(step.data());
    const bool downhill = evaluate_modes(ref, next, law, trial) &&
                          trial.energy <= r.energy + 1e-13 * std::abs(r.energy);
    if (!downhill) {
      shift = std::max(4.0 * shift, 1e-6 * scale);
      continue;
    }
    full = next;
    std::swap(r, trial);
    shift = shift < 1e-6 * scale ? 0.0 : 0.25 * shift;
  }
  ElementResult<kAll> whole;  // once, at the solution
  if (!evaluate_enriched(ref, full, law, whole)) return false;
  modes = full.rightCols<3>();
  out.energy = whole.energy;
  out.force = whole.force.leftCols<kNodes>();
  if (with_tangent) {
    const auto kau = whole.stiffness.block<9, 3 * kNodes>(3 * kNodes, 0);
    out.stiffness = whole.stiffness.topLeftCorner<3 * kNodes, 3 * kNodes>() -
                    kau.transpose() * kaa.solve(Eigen::Matrix<double, 9, 3 * kNodes>(kau));
  }
  return true;
}

}  // namespace phymul::fem
