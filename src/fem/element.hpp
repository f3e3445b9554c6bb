// Linear hexahedra and tetrahedra (VTK node order), total Lagrangian. Reference data is
// computed once per cell; the kernel returns the element energy, internal force and tangent
// for a given nodal displacement.
#pragma once

#include <Eigen/Core>
#include <array>

#include "fem/constitutive.hpp"
#include "phymul/mesh.hpp"

namespace phymul::fem {

// Reference-configuration data of one cell: NN nodes, NG Gauss points.
template <int NN, int NG>
struct ElementReference {
  static constexpr int nodes = NN;
  static constexpr int gauss_points = NG;
  std::array<Eigen::Matrix<double, NN, 3>, NG> grad;  // dN_a/dX at each Gauss point
  std::array<double, NG> weight{};                    // Gauss weight * det(dX/dxi)
  double volume = 0.0;                                // sum of weights (exact for both cells)
  Eigen::Matrix<double, NN, 1> nodal_volume;          // integral of N_a dV (body forces)
};

using HexaReference = ElementReference<8, 8>;   // trilinear, 2x2x2 Gauss
using TetraReference = ElementReference<4, 1>;  // linear, 1 point (exact)

// Corner signs (xi, eta, zeta) in VTK order: bottom face 0-1-2-3 counter-clockwise seen
// from +z, then the top face above it.
inline constexpr std::array<std::array<double, 3>, 8> kHexaCorners{{{-1, -1, -1},
                                                                    {1, -1, -1},
                                                                    {1, 1, -1},
                                                                    {-1, 1, -1},
                                                                    {-1, -1, 1},
                                                                    {1, -1, 1},
                                                                    {1, 1, 1},
                                                                    {-1, 1, 1}}};

// The hourglass base vectors h_a = (s0 s1, s1 s2, s0 s2, s0 s1 s2) of corner a's signs s
// (Flanagan-Belytschko), as compile-time constants.
constexpr std::array<std::array<double, 4>, 8> hexa_hourglass_base() {
  std::array<std::array<double, 4>, 8> h{};
  for (int a = 0; a < 8; ++a) {
    const auto& s = kHexaCorners[size_t(a)];
    h[size_t(a)] = {s[0] * s[1], s[1] * s[2], s[0] * s[2], s[0] * s[1] * s[2]};
  }
  return h;
}

// Shape-function gradients with respect to the reference coordinates: dN/dxi at the Gauss
// points, and the values N_a there (for body forces).
std::array<Eigen::Matrix<double, 8, 3>, 8> hexa_local_gradients();
std::array<Eigen::Matrix<double, 8, 1>, 8> hexa_shape_values();
Eigen::Matrix<double, 8, 3> hexa_local_gradient(const Eigen::Vector3d& xi);
Eigen::Vector3d hexa_gauss_point(int g);  // in the corner order, point g next to corner g

// Throw std::invalid_argument naming the cell when its Jacobian is not positive at a Gauss
// point (validate() already rejects such meshes; this guards the element's own quadrature).
HexaReference hexa_reference(const Eigen::Matrix<double, 3, 8>& x, int cell_index);
TetraReference tetra_reference(const Eigen::Matrix<double, 3, 4>& x, int cell_index);
[[noreturn]] void throw_bad_jacobian(CellType type, int cell_index, double det, int gauss_point);

// Energy, internal force (index 3 a + i) and tangent of one element.
template <int NN>
struct ElementResult {
  double energy = 0.0;
  Eigen::Matrix<double, 3, NN> force;  // column a: force on node a
  Eigen::Matrix<double, 3 * NN, 3 * NN> stiffness;
};

struct LawConstants {
  Law law = Law::neo_hookean;
  Moduli moduli;
};

// Returns false (and leaves `out` undefined) when the deformation inverts the element
// (J <= 0 at a Gauss point or for the element mean), which the Neo-Hookean law cannot take.
template <int NN, int NG>
bool evaluate_element(const ElementReference<NN, NG>& ref, const Eigen::Matrix<double, 3, NN>& u,
                      const LawConstants& law, bool with_tangent, ElementResult<NN>& out);

extern template bool evaluate_element<8, 8>(const HexaReference&,
                                            const Eigen::Matrix<double, 3, 8>&, const LawConstants&,
                                            bool, ElementResult<8>&);
extern template bool evaluate_element<4, 1>(const TetraReference&,
                                            const Eigen::Matrix<double, 3, 4>&, const LawConstants&,
                                            bool, ElementResult<4>&);

// Hexahedron with Wilson's incompatible modes (CalculiX's C3D8I, hexa_incompatible.cpp): the
// 8 nodes and 3 bubble modes P_k = 1 - xi_k^2 (rows 8 to 10 of grad, their gradients taken
// with the centre Jacobian), 2x2x2 Gauss, the law evaluated pointwise.
using IncompatibleHexaReference = ElementReference<11, 8>;
IncompatibleHexaReference incompatible_hexa_reference(const Eigen::Matrix<double, 3, 8>& x,
                                                      int cell_index);

// Amplitudes of the three bubble modes (column k: the displacement vector of mode k), m.
using ModeAmplitudes = Eigen::Matrix3d;

// Energy, force and tangent of the element once its modes minimise the energy for the nodal
// displacement u (statically condensed: the modes belong to this element alone). `modes`
// holds the start of that local solve and returns its solution. False when the deformation
// inverts the element or the local solve fails.
bool evaluate_incompatible_hexa(const IncompatibleHexaReference& ref,
                                const Eigen::Matrix<double, 3, 8>& u, const LawConstants& law,
                                bool with_tangent, ModeAmplitudes& modes, ElementResult<8>& out);

}  // namespace phymul::fem
