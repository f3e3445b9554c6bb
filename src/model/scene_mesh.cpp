#include <fmt/format.h>

#include <Eigen/Geometry>
#include <stdexcept>

#include "phymul/model.hpp"

namespace phymul {

namespace {

Mesh generate(const MeshSpec& m) {
  if (m.generator == "box") return make_box(m.size, m.cells, m.element, m.center);
  if (m.generator == "ellipsoid")
    return m.surface         ? make_ellipsoid_surface(m.radii, m.subdivisions, m.center)
           : m.hexahedra > 0 ? make_ellipsoid_hexa(m.radii, m.hexahedra, m.center)
                             : make_ellipsoid_volume(m.radii, m.subdivisions, m.layers, m.center);
  if (m.generator == "cylinder")
    return m.surface
               ? make_cylinder_surface(m.radius, m.length, m.around, m.along, m.center)
               : make_cylinder_volume(m.radius, m.length, m.around, m.along, m.rings, m.center);
  throw std::invalid_argument(fmt::format("unknown mesh generator '{}'", m.generator));
}

}  // namespace

void place_mesh(Mesh& mesh, const MeshTransform& t) {
  if (t.identity()) return;  // bit for bit the mesh as given
  const Eigen::Matrix3d r = Eigen::AngleAxisd(t.angle, t.axis).toRotationMatrix();
  for (Vec3& p : mesh.points) p = r * t.scale.cwiseProduct(p) + t.translate;
}

Mesh make_mesh(const MeshSpec& m) {
  if (!m.file.empty()) {
    if (!m.file_mesh)
      throw std::invalid_argument(fmt::format(
          "the mesh file {} was not read (load_scene or prepare_scene reads it)", m.file));
    return *m.file_mesh;  // placed when read
  }
  Mesh mesh = generate(m);
  place_mesh(mesh, m.transform);
  return mesh;
}

}  // namespace phymul
