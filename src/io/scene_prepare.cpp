// What a parsed scene needs before compiling: its mesh files read, shape-memory stiffness
// calibrated from Young's modulus (scene_io.hpp).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <memory>

#include "io/scene_lml.hpp"
#include "io/units.hpp"
#include "mesh/surface_check.hpp"
#include "phymul/calibration.hpp"
#include "phymul/camitk.hpp"
#include "phymul/label_surface.hpp"
#include "phymul/mesh_io.hpp"
#include "phymul/meshing.hpp"
#include "phymul/model.hpp"
#include "phymul/nifti.hpp"
#include "phymul/scene_io.hpp"

namespace phymul {
namespace {

// A PML's component, with each node's atom index (for the scene's LML loads).
Mesh read_pml_mesh(const std::filesystem::path& path, double divisor, MeshSpec& spec) {
  const PmlModel pml = read_pml(path, divisor);
  spec.file_notes.insert(spec.file_notes.end(), pml.notes.begin(), pml.notes.end());
  return pml_object_mesh(pml, spec.component, &spec.atom_ids, path.string());
}

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

// `remesh`: the closed surface read from the file remeshed to the edge; its quality, deviation
// and volume change go to the file's notes.
Mesh remeshed(Mesh surface, double edge, const std::string& file, ObjectSpec& o) {
  if (surface.volumetric())
    throw MeshFileError(file, 0, 0, "'remesh' needs a closed surface; this is a volume mesh");
  for (const Cell& c : surface.cells)
    if (c.type != CellType::triangle)
      throw MeshFileError(
          file, 0, 0,
          fmt::format("'remesh' takes a triangle surface (got a {} cell)", cell_type_name(c.type)));
  SurfaceCheck check = check_closed_surface(surface);  // a .vtk or .msh surface is not checked
  if (!check.problems.empty())
    throw MeshFileError(
        file, 0, 0,
        fmt::format("'remesh' needs a closed surface: {}", fmt::join(check.problems, "; ")));
  try {
    const Remeshed r = remesh_surface(surface, edge);
    const SurfaceQuality& q = r.quality;
    o.mesh.file_notes.push_back(fmt::format(
        "{}: remeshed to {:g} mm: {} triangles and {} points, edges {:.3g}/{:.3g}/{:.3g} mm "
        "(min/mean/max), smallest angle {:.1f} degrees, largest aspect ratio {:.2f}; at most "
        "{:.3g} mm from the file's surface, enclosed volume {:.4g} mL -> {:.4g} mL ({:+.2f}%)",
        file, edge * 1e3, q.triangles, r.surface.points.size(), q.edge_min * 1e3, q.edge_mean * 1e3,
        q.edge_max * 1e3, q.min_angle_deg, q.max_aspect, r.deviation * 1e3, r.volume_before * 1e6,
        r.volume_after * 1e6, 100.0 * (r.volume_after - r.volume_before) / r.volume_before));
    return r.surface;
  } catch (const MeshError& e) {
    throw MeshFileError(file, 0, 0, fmt::format("'remesh': {}", e.what()));
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
  const double divisor = unit ? unit->divisor / unit->scale : 1.0;
  if (!o.mesh.component.empty() && path.extension() != ".pml") {
    problems.push_back({o.mesh.loc, fmt::format("'component' applies only to a CamiTK PML file "
                                                "(.pml), not {}",
                                                o.mesh.file)});
    return;
  }
  if (o.mesh.remesh && path.extension() == ".pml") {  // its atoms are what the LML loads name
    problems.push_back({o.mesh.loc, fmt::format("'remesh' does not apply to a CamiTK PML file "
                                                "({}): its atoms are the nodes its loads name",
                                                o.mesh.file)});
    return;
  }
  try {
    if (is_nifti_path(path)) {  // a label image: its surface filled, as `phymul mesh` does
      Mesh volume = image_volume(path, o);
      place_mesh(volume, o.mesh.transform);
      o.mesh.file_mesh = std::make_shared<const Mesh>(std::move(volume));
      return;
    }
    Mesh mesh = path.extension() == ".pml" ? read_pml_mesh(path, divisor, o.mesh)
                                           : read_mesh_file(path, divisor, &o.mesh.file_notes);
    place_mesh(mesh, o.mesh.transform);  // units, transform, remesh, fill: as the reference says
    if (o.mesh.remesh) mesh = remeshed(mesh, *o.mesh.remesh, path.string(), o);
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
  io::apply_lml(scene, problems);
  if (!problems.empty()) throw SceneError(std::move(problems));
  for (ObjectSpec& o : scene.objects)
    if (o.type != ObjectType::rigid && o.material.model == ElasticModel::shape_memory &&
        o.material.young)
      calibrate(o, problems);
  if (!problems.empty()) throw SceneError(std::move(problems));
}

}  // namespace phymul
