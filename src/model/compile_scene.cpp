// A checked scene description into a Model: meshes from generators, node selectors
// resolved against them, loads and constraints attached.
#include <fmt/format.h>

#include <algorithm>

#include "io/parameter_table.hpp"
#include "model/compile_interactions.hpp"
#include "phymul/model.hpp"

namespace phymul {
namespace {

struct Compiler {
  const Scene& scene;
  Model model;
  std::vector<Diagnostic> problems;

  void fail(const SourceLoc& loc, std::string message) {
    problems.push_back({loc, std::move(message)});
  }

  Mesh generate(const MeshSpec& m) {
    if (m.generator == "box") return make_box(m.size, m.cells, m.element, m.center);
    if (m.generator == "ellipsoid")
      return m.surface ? make_ellipsoid_surface(m.radii, m.subdivisions, m.center)
                       : make_ellipsoid_volume(m.radii, m.subdivisions, m.layers, m.center);
    if (m.generator == "cylinder")
      return m.surface
                 ? make_cylinder_surface(m.radius, m.length, m.around, m.along, m.center)
                 : make_cylinder_volume(m.radius, m.length, m.around, m.along, m.rings, m.center);
    throw std::invalid_argument(fmt::format("unknown mesh generator '{}'", m.generator));
  }

  void add_object(const ObjectSpec& o) {
    try {
      const Mesh mesh = generate(o.mesh);
      const int c = add_elastic_component(model, o.name, mesh, o.material);
      if (o.volume_constraint) {
        add_volume_constraint(model, c);
        model.volumes.back().target_schedule = o.target_volume;
      }
    } catch (const std::exception& e) {
      const std::string what = e.what();
      const std::string prefix = fmt::format("object '{}'", o.name);
      fail(o.loc, what.starts_with(prefix) ? what : prefix + ": " + what);
    }
  }

  const Component* find(const std::string& name, const SourceLoc& loc) {
    for (const Component& c : model.components)
      if (c.name == name) return &c;
    fail(loc, fmt::format("no object named '{}'", name));
    return nullptr;
  }

  static bool inside(const NodeSelector& s, const Vec3& p) {
    switch (s.kind) {
      case NodeSelector::Kind::box:
        return (p.array() >= s.min.array()).all() && (p.array() <= s.max.array()).all();
      case NodeSelector::Kind::sphere:
        return (p - s.center).norm() <= s.radius;
      case NodeSelector::Kind::half_space:
        return (p - s.point).dot(s.normal) >= 0.0;
      default:
        return true;
    }
  }

  std::vector<int> select(const std::string& object, const NodeSelector& s) {
    const Component* c = find(object, s.loc);
    if (!c) return {};
    std::vector<int> nodes;
    if (s.kind == NodeSelector::Kind::named) {
      const auto it = c->node_sets.find(s.name);
      if (it == c->node_sets.end()) {
        std::string known;
        std::vector<std::string_view> names;
        for (const auto& [name, ids] : c->node_sets) {
          known += (known.empty() ? "" : ", ") + name;
          names.push_back(name);
        }
        const auto close = io::closest_match(s.name, names);
        fail(s.loc, fmt::format("object '{}' has no node set '{}' ({}its node sets: {})", object,
                                s.name, close ? fmt::format("did you mean '{}'? ", *close) : "",
                                known.empty() ? "none" : known));
        return {};
      }
      nodes = it->second;
    } else if (s.kind == NodeSelector::Kind::indices) {
      for (int i : s.indices) {
        if (i >= c->node_count) {
          fail(s.loc, fmt::format("node index {} is out of range: object '{}' has nodes 0-{}", i,
                                  object, c->node_count - 1));
          return {};
        }
        nodes.push_back(c->first_node + i);
      }
    } else {
      for (int i = c->first_node; i < c->first_node + c->node_count; ++i)
        if (inside(s, model.rest_position[i])) nodes.push_back(i);
    }
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    if (nodes.empty())
      fail(s.loc, fmt::format("this node selection matches no node of '{}'", object));
    return nodes;
  }
};

}  // namespace

Model compile_scene(const Scene& scene) {
  Compiler k{scene, {}, {}};
  k.model.settings = scene.simulation;
  k.model.gravity = scene.simulation.gravity;
  k.model.damping = scene.simulation.damping;
  for (const ObjectSpec& o : scene.objects) k.add_object(o);
  if (k.problems.empty()) {
    for (const LoadSpec& l : scene.loads) {
      std::vector<int> nodes = k.select(l.object, l.nodes);
      if (!nodes.empty()) add_applied_force(k.model, {std::move(nodes), l.force});
    }
    for (const ConstraintSpec& c : scene.constraints) {
      std::vector<int> nodes = k.select(c.object, c.nodes);
      if (nodes.empty()) continue;
      if (c.kind == ConstraintSpec::Kind::fixed)
        add_fixed_nodes(k.model, nodes);
      else
        add_prescribed_displacement(k.model, {std::move(nodes), c.axes, c.displacement});
    }
    compile_interactions(
        scene, k.model, k.problems,
        [&](const std::string& object, const NodeSelector& s) { return k.select(object, s); });
  }
  if (!k.problems.empty()) throw SceneError(std::move(k.problems));
  try {
    finalize(k.model);
  } catch (const std::exception& e) {
    throw SceneError({{SourceLoc{scene.file.string(), 0, 0}, e.what()}});
  }
  return std::move(k.model);
}

}  // namespace phymul
