#include "studies/truthcube_models.hpp"

#include <cmath>
#include <stdexcept>

namespace phymul::truthcube {

Plates plate_nodes(const Mesh& mesh, const CubeFrame& frame) {
  Plates p;
  const double tol = 1e-9;
  double best_centre = 1e300, best_x_line = 1e300;
  for (int i = 0; i < int(mesh.points.size()); ++i) {
    const Vec3& x = mesh.points[i];
    if (std::abs(x.z() - frame.plate_z) < tol) p.plate.push_back(i);
    if (std::abs(x.z() - frame.base_z) >= tol) continue;
    p.base.push_back(i);
    const Vec3 d = x - Vec3(frame.center.x(), frame.center.y(), frame.base_z);
    if (d.norm() < best_centre) best_centre = d.norm(), p.centre = i;
    // A node away from the centre on its x line: farthest along +x with y at the centre's.
    const double off_line = std::abs(d.y()) - d.x();
    if (off_line < best_x_line) best_x_line = off_line, p.on_x_line = i;
  }
  if (p.base.empty() || p.plate.empty())
    throw std::logic_error("the Truth Cube mesh has no node on a plate");
  return p;
}

}  // namespace phymul::truthcube
