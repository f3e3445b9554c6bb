#include "model/compile_interactions.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <set>

#include "model/embedding.hpp"

namespace phymul {
namespace {

int component_index(const Model& model, const std::string& name) {
  for (int c = 0; c < int(model.components.size()); ++c)
    if (model.components[c].name == name) return c;
  return -1;
}

// The boundary faces a pressure load covers: all of them, those whose nodes are all
// selected, and/or those inside the cylinder.
void compile_pressure(const PressureSpec& p, Model& model, std::vector<Diagnostic>& problems,
                      const SelectNodes& select) {
  const int c = component_index(model, p.object);
  if (c < 0) return;  // reported by the reader's reference check
  const Component& component = model.components[c];
  if (component.boundary.empty()) {
    problems.push_back({p.loc, fmt::format("pressure on '{}': the object has no closed boundary "
                                           "surface to press on",
                                           p.object)});
    return;
  }
  std::vector<Triangle> faces = component.boundary;
  if (p.nodes.kind != NodeSelector::Kind::all) {
    const std::vector<int> nodes = select(p.object, p.nodes);
    if (nodes.empty()) return;
    const auto selected = [&](int i) { return std::binary_search(nodes.begin(), nodes.end(), i); };
    std::erase_if(faces,
                  [&](const Triangle& t) { return !std::all_of(t.begin(), t.end(), selected); });
  }
  if (p.in_cylinder) {
    const std::vector<Triangle> inside =
        faces_in_cylinder(model, c, p.cylinder_point, p.cylinder_axis, p.cylinder_radius);
    std::erase_if(faces, [&](const Triangle& t) {
      return std::find(inside.begin(), inside.end(), t) == inside.end();
    });
  }
  if (faces.empty()) {
    problems.push_back(
        {p.loc, fmt::format("this pressure covers no boundary face of '{}' (a face counts when "
                            "all its nodes are selected and its centroid is in the cylinder)",
                            p.object)});
    return;
  }
  add_pressure(model, {c, std::move(faces), p.pressure});
}

RigidObstacle obstacle_of(const ObstacleSpec& o, const Model& model, int index) {
  using Shape = RigidObstacle::Shape;
  RigidObstacle r;
  r.name = o.name.empty() ? fmt::format("obstacle{}", index) : o.name;
  r.point = o.position;
  r.axis = o.axis;
  r.radius = o.radius;
  r.motion = o.motion;
  r.keep_inside = o.keep_inside;
  r.friction = o.friction;
  r.shape = o.shape;
  // A capsule's segment has its length; a probe's core ray ends at the tip's centre.
  r.length = o.shape == Shape::capsule ? o.length : 0.0;
  for (const std::string& name : o.objects) {
    const int c = component_index(model, name);
    if (c < 0) continue;
    const Component& k = model.components[c];
    r.nodes.insert(r.nodes.end(), k.nodes.begin(), k.nodes.end());
  }
  std::sort(r.nodes.begin(), r.nodes.end());  // a stitched node is listed by both objects
  r.nodes.erase(std::unique(r.nodes.begin(), r.nodes.end()), r.nodes.end());
  return r;
}

void compile_obstacles(const Scene& scene, Model& model, std::vector<Diagnostic>& problems) {
  std::set<std::string> names;
  for (size_t k = 0; k < scene.obstacles.size(); ++k) {
    const ObstacleSpec& o = scene.obstacles[k];
    RigidObstacle r = obstacle_of(o, model, int(k));
    if (!names.insert(r.name).second) {
      problems.push_back({o.loc, fmt::format("obstacle name '{}' is used twice", r.name)});
      continue;
    }
    try {
      add_rigid_obstacle(model, std::move(r));
    } catch (const std::exception& e) {
      problems.push_back({o.loc, e.what()});
    }
  }
}

// The target at rest, embedded in a cell of its object; false (diagnosed) when outside it.
bool compile_target(const NeedleTargetSpec& spec, const Model& model, Needle& n,
                    std::vector<Diagnostic>& problems) {
  const int c = component_index(model, spec.object);
  if (c < 0) return false;  // reported by the reader's reference check
  const auto tetrahedra = cell_tetrahedra(model, c);
  if (!embed_point(tetrahedra, model.rest_position, spec.point, n.target)) {
    problems.push_back(
        {spec.loc, fmt::format("target point [{}, {}, {}] m is not inside a "
                               "volume cell of '{}' at rest",
                               spec.point.x(), spec.point.y(), spec.point.z(), spec.object)});
    return false;
  }
  n.target_component = c;
  return true;
}

void compile_needle(const NeedleSpec& spec, int index, Model& model,
                    std::vector<Diagnostic>& problems) {
  if (model.settings.mode != SolveMode::dynamic) {
    problems.push_back({spec.loc,
                        "needles need dynamic mode (simulation.mode: dynamic): "
                        "insertion is a history of punctures and friction"});
    return;
  }
  Needle n;
  n.name = spec.name.empty() ? fmt::format("needle{}", index) : spec.name;
  n.base = spec.base;
  n.direction = spec.direction;
  n.depth = spec.depth;
  n.radius = spec.radius;
  n.spacing = spec.spacing;
  for (const NeedleTissueSpec& t : spec.tissues) {
    const int c = component_index(model, t.object);
    if (c < 0) return;  // reported by the reader's reference check
    n.tissues.push_back({c, t.puncture_force, t.friction, t.cutting_force, {}});
  }
  if (spec.target && !compile_target(*spec.target, model, n, problems)) return;
  try {
    add_needle(model, std::move(n));
  } catch (const std::exception& e) {
    problems.push_back({spec.loc, e.what()});
  }
}

}  // namespace

void compile_interactions(const Scene& scene, Model& model, std::vector<Diagnostic>& problems,
                          const SelectNodes& select) {
  for (const PressureSpec& p : scene.pressures) compile_pressure(p, model, problems, select);
  compile_obstacles(scene, model, problems);
  for (const ContactSpec& c : scene.contacts) {
    const int a = component_index(model, c.objects[0]), b = component_index(model, c.objects[1]);
    if (a < 0 || b < 0) continue;  // reported by the reader's reference check
    try {
      add_contact_pair(model, a, b);
    } catch (const std::exception& e) {
      problems.push_back({c.loc, e.what()});
    }
  }
  std::set<std::string> needle_names;
  for (size_t k = 0; k < scene.needles.size(); ++k) {
    const NeedleSpec& n = scene.needles[k];
    const std::string name = n.name.empty() ? fmt::format("needle{}", k) : n.name;
    if (!needle_names.insert(name).second)
      problems.push_back({n.loc, fmt::format("needle name '{}' is used twice", name)});
    else
      compile_needle(n, int(k), model, problems);
  }
}

}  // namespace phymul
