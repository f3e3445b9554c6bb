#include "model/compile_interactions.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <set>

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
}

}  // namespace phymul
