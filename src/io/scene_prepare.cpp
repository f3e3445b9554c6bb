// What a parsed scene needs before compiling: its mesh files read, shape-memory stiffness
// calibrated from Young's modulus (scene_io.hpp).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <memory>

#include "io/units.hpp"
#include "mesh/surface_check.hpp"
#include "phymul/calibration.hpp"
#include "phymul/label_surface.hpp"
#include "phymul/mesh_io.hpp"
#include "phymul/meshing.hpp"
#include "phymul/nifti.hpp"
#include "phymul/scene_io.hpp"

namespace phymul {
namespace {

// The tetrahedra's quality, for the file's notes.
std::string fill_note(const Mesh& volume, double edge, const std::string& file) {
  const TetraQuality q = tetra_quality(volume);
  return fmt::format(
      "{}: filled with {} tetrahedra and {} points (edge at most {:g} mm inside): smallest "
      "dihedral angle {:.1f} degrees, largest radius-edge ratio {:.2f}",
      file, q.tetrahedra, volume.points.size(), edge * 1e3, q.min_dihedral_deg, q.max_radius_edge);
}

// `fill: tetra`: the closed surface read from the file, checked, filled with tetrahedra; their
// quality goes to the file's notes.
Mesh fill(Mesh surface, double edge, const std::string& file, ObjectSpec& o) {
  SurfaceCheck check = check_closed_surface(surface);
  if (!check.problems.empty())
    throw MeshFileError(
        file, 0, 0,
        fmt::format("'fill' needs a closed surface: {}", fmt::join(check.problems, "; ")));
  try {
    Mesh volume = fill_with_tetrahedra(surface, edge);
    o.mesh.file_notes.push_back(fill_note(volume, edge, file));
    return volume;
  } catch (const MeshError& e) {
    throw MeshFileError(file, 0, 0, e.what());
  }
}

// A label image's labels as a surface of `edge` filled with tetrahedra, said in the notes.
Mesh image_volume(const std::filesystem::path& path, ObjectSpec& o) {
  const LabelImage image = read_nifti_labels(path, &o.mesh.file_notes);
  LabelSurfaceReport r;
  try {
    Mesh surface;
    Mesh volume = label_volume(image, o.mesh.labels, *o.mesh.fill_edge, &r, &surface);
    o.mesh.file_notes.push_back(fmt::format(
        "{}: labels {}: {} voxels, {:.2f} mL; their surface: {} triangles enclosing {:.2f} mL "
        "({:+.2f} %), centroid ({:.2f}, {:.2f}, {:.2f}) mm",
        path.string(), fmt::join(o.mesh.labels, ", "), r.voxels, r.labelled_volume * 1e6,
        surface.cells.size(), r.surface_volume * 1e6,
        100.0 * (r.surface_volume - r.labelled_volume) / r.labelled_volume, r.centroid[0] * 1e3,
        r.centroid[1] * 1e3, r.centroid[2] * 1e3));
    o.mesh.file_notes.push_back(fill_note(volume, *o.mesh.fill_edge, path.string()));
    return volume;
  } catch (const MeshError& e) {
    throw MeshFileError(path.string(), 0, 0, e.what());
  }
}

// A mesh file's path is relative to the scene file; its problems are reported where they
// are in it, naming the object whose mesh it is.
void read_mesh(const Scene& scene, ObjectSpec& o, std::vector<Diagnostic>& problems) {
  const std::filesystem::path path = scene.file.parent_path() / o.mesh.file;
  const io::Unit* unit = io::find_unit(o.mesh.units);
  try {
    if (is_nifti_path(path)) {  // a label image: its surface filled, as `phymul mesh` does
      o.mesh.file_mesh = std::make_shared<const Mesh>(image_volume(path, o));
      return;
    }
    Mesh mesh = read_mesh_file(path, unit ? unit->divisor / unit->scale : 1.0, &o.mesh.file_notes);
    if (o.mesh.fill_tetra) mesh = fill(std::move(mesh), *o.mesh.fill_edge, path.string(), o);
    o.mesh.file_mesh = std::make_shared<const Mesh>(std::move(mesh));
  } catch (const MeshFileError& e) {
    problems.push_back({{e.file, e.line, e.column},
                        fmt::format("{} (the mesh of object '{}', {}:{})", e.message, o.name,
                                    o.loc.file, o.loc.line)});
  }
}

// K from E on the object's own mesh; a failure is the object's problem, named as compiling
// names the others.
void calibrate(ObjectSpec& o, std::vector<Diagnostic>& problems) {
  MaterialSpec& material = o.material;
  if (calibration_current(o)) return;  // a scene prepared before
  try {
    o.calibration = calibration::calibrate_object(o.name, make_mesh(o.mesh), material,
                                                  o.volume_constraint, material.calibration_axis);
    material.stiffness = o.calibration->stiffness;
  } catch (const std::exception& e) {
    const std::string what = e.what();
    const std::string prefix = fmt::format("object '{}'", o.name);
    const std::string rest = what.starts_with(prefix) ? what.substr(prefix.size()) : ": " + what;
    const std::string source =
        o.mesh.file.empty() ? "" : fmt::format(" (mesh file {})", o.mesh.file);
    problems.push_back({o.loc, prefix + source + rest});
  }
}

}  // namespace

void prepare_scene(Scene& scene) {
  std::vector<Diagnostic> problems;
  for (ObjectSpec& o : scene.objects)
    if (!o.mesh.file.empty() && !o.mesh.file_mesh) read_mesh(scene, o, problems);
  if (!problems.empty()) throw SceneError(std::move(problems));
  for (ObjectSpec& o : scene.objects)
    if (o.type != ObjectType::rigid && o.material.model == ElasticModel::shape_memory &&
        o.material.young > 0.0)
      calibrate(o, problems);
  if (!problems.empty()) throw SceneError(std::move(problems));
}

}  // namespace phymul
