// What a parsed scene needs before compiling: its mesh files read, shape-memory stiffness
// calibrated from Young's modulus (scene_io.hpp).
#include <fmt/format.h>

#include <memory>

#include "io/units.hpp"
#include "phymul/calibration.hpp"
#include "phymul/mesh_io.hpp"
#include "phymul/scene_io.hpp"

namespace phymul {
namespace {

// A mesh file's path is relative to the scene file; its problems are reported where they
// are in it, naming the object whose mesh it is.
void read_mesh(const Scene& scene, ObjectSpec& o, std::vector<Diagnostic>& problems) {
  const std::filesystem::path path = scene.file.parent_path() / o.mesh.file;
  const io::Unit* unit = io::find_unit(o.mesh.units);
  try {
    o.mesh.file_mesh = std::make_shared<const Mesh>(
        read_mesh_file(path, unit ? unit->divisor / unit->scale : 1.0));
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
  const std::optional<StiffnessCalibration>& done = o.calibration;
  if (done && done->young == material.young && done->poisson == material.poisson &&
      done->axis == material.calibration_axis)
    return;  // a scene prepared before
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
