// Linear tetrahedron, VTK node order: constant gradients, one-point quadrature is exact.
// Note: linear tetrahedra lock as nu -> 0.5 (one volume constraint per cell with three
// degrees of freedom per node); the mean dilatation changes nothing for them, since J is
// already constant per cell. Use hexahedra for nearly incompressible materials.
#include "fem/element.hpp"

namespace phymul::fem {

TetraReference tetra_reference(const Eigen::Matrix<double, 3, 4>& x, int cell_index) {
  Eigen::Matrix<double, 4, 3> local;
  local << -1, -1, -1, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  const Eigen::Matrix3d jac = x * local;
  const double det = jac.determinant();
  if (!(det > 0.0)) throw_bad_jacobian(CellType::tetra, cell_index, det, 0);
  TetraReference ref;
  ref.grad[0] = local * jac.inverse();
  ref.weight[0] = det / 6.0;
  ref.volume = det / 6.0;
  ref.nodal_volume.setConstant(ref.volume / 4.0);
  return ref;
}

}  // namespace phymul::fem
