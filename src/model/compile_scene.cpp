// A checked scene description into a Model: meshes from generators, node selectors
// resolved against them, loads and constraints attached.
#include <fmt/format.h>

#include <algorithm>
#include <limits>
#include <optional>

#include "model/closest_match.hpp"
#include "model/compile_checks.hpp"
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

  // The object's mesh: generated, or its file as the loader read it.
  std::optional<Mesh> mesh_of(const ObjectSpec& o) {
    if (o.mesh.file.empty()) {
      try {
        return make_mesh(o.mesh);
      } catch (const std::exception& e) {
        fail(o.loc, fmt::format("object '{}': {}", o.name, e.what()));
        return std::nullopt;
      }
    }
    if (!o.mesh.file_mesh) {
      fail(o.mesh.loc, fmt::format("object '{}': the mesh file {} was not read (load_scene reads "
                                   "it; for a scene built in a program, call prepare_scene)",
                                   o.name, o.mesh.file));
      return std::nullopt;
    }
    return *o.mesh.file_mesh;
  }

  // A shape-memory material given `young`: the K its calibration found (prepare_scene).
  bool calibrated(const ObjectSpec& o, MaterialSpec& material) {
    if (calibration_current(o)) {
      material.stiffness = o.calibration->stiffness;
      model.stiffness_calibrations.push_back(*o.calibration);
      return true;
    }
    fail(material.young_loc.line > 0 ? material.young_loc : o.loc,
         fmt::format("object '{}': a shape-memory stiffness from 'young' is calibrated before "
                     "compiling (load_scene does it; after editing a scene in a program, call "
                     "prepare_scene)",
                     o.name));
    return false;
  }

  void add_object(const ObjectSpec& o) {
    std::optional<Mesh> mesh = mesh_of(o);
    if (!mesh) return;
    try {
      if (o.type == ObjectType::rigid) {
        const MotionSpec motion = o.motion.value_or(MotionSpec{});
        add_rigid_component(model, o.name, *mesh, o.material, o.motion.has_value(),
                            motion.translation, motion.rotation);
        return;
      }
      MaterialSpec material = o.material;
      if (material.model == ElasticModel::shape_memory && material.young &&
          !calibrated(o, material))
        return;
      const int c = add_elastic_component(model, o.name, *mesh, material);
      if (o.type == ObjectType::active) model.components[c].kind = ObjectType::active;
      if (o.volume_constraint) {
        add_volume_constraint(model, c);
        model.volumes.back().target_schedule = o.target_volume;
      }
    } catch (const std::exception& e) {
      const std::string what = e.what();
      const std::string prefix = fmt::format("object '{}'", o.name);
      const std::string rest = what.starts_with(prefix) ? what.substr(prefix.size()) : ": " + what;
      const std::string source =
          o.mesh.file.empty() ? "" : fmt::format(" (mesh file {})", o.mesh.file);
      fail(o.loc, prefix + source + rest);
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
        const auto close = closest_match(s.name, names);
        fail(s.loc, fmt::format("object '{}' has no node set '{}' ({}its node sets: {})", object,
                                s.name, close ? fmt::format("did you mean '{}'? ", *close) : "",
                                known.empty() ? "none" : known));
        return {};
      }
      nodes = it->second;
    } else if (s.kind == NodeSelector::Kind::indices) {
      for (int i : s.indices) {
        if (i >= int(c->nodes.size())) {
          fail(s.loc, fmt::format("node index {} is out of range: object '{}' has nodes 0-{}", i,
                                  object, c->nodes.size() - 1));
          return {};
        }
        nodes.push_back(c->nodes[i]);
      }
    } else {
      for (int i : c->nodes)
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

namespace {

// The node pairs of a stitch or doubling: each node of `nodes` with its nearest node of
// `with_nodes` within the tolerance. Explicit `nodes` must all find a partner.
std::vector<std::array<int, 2>> link_pairs(Compiler& k, const LinkSpec& l) {
  const std::vector<int> from = k.select(l.object, l.nodes);
  const std::vector<int> to = k.select(l.with, l.with_nodes);
  if (from.empty() || to.empty()) return {};
  if (l.object == l.with) {
    k.fail(l.loc,
           fmt::format("'object' and 'with' are both '{}': link two different objects", l.object));
    return {};
  }
  std::vector<std::array<int, 2>> pairs = coincident_pairs(k.model, from, to, l.tolerance);
  const auto nearest = [&](int i) {
    double d = std::numeric_limits<double>::infinity();
    for (int j : to) d = std::min(d, (k.model.rest_position[j] - k.model.rest_position[i]).norm());
    return d;
  };
  if (l.nodes.kind != NodeSelector::Kind::all && pairs.size() < from.size()) {
    for (int i : from)
      if (std::none_of(pairs.begin(), pairs.end(), [&](const auto& p) { return p[0] == i; })) {
        const Component* c = k.find(l.object, l.loc);
        const auto local = std::find(c->nodes.begin(), c->nodes.end(), i) - c->nodes.begin();
        k.fail(l.nodes.loc,
               fmt::format("node {} of '{}' has no node of '{}' within the tolerance {:g} m "
                           "(the nearest is {:.3g} m away)",
                           local, l.object, l.with, l.tolerance, nearest(i)));
        return {};
      }
  }
  if (pairs.empty()) {
    double closest = std::numeric_limits<double>::infinity();
    for (int i : from) closest = std::min(closest, nearest(i));
    k.fail(l.loc, fmt::format("no node of '{}' lies within the tolerance {:g} m of a node of '{}' "
                              "(the closest pair is {:.3g} m apart)",
                              l.object, l.tolerance, l.with, closest));
  }
  return pairs;
}

bool is_rigid(const Model& model, const std::string& object) {
  for (const Component& c : model.components)
    if (c.name == object) return c.kind == ObjectType::rigid;
  return false;
}

void add_links(Compiler& k, const Scene& scene) {
  std::vector<std::array<int, 2>> stitched;
  for (const LinkSpec& l : scene.stitches) {
    if (is_rigid(k.model, l.object) && is_rigid(k.model, l.with)) {
      k.fail(l.loc, fmt::format("a stitch cannot join two rigid objects ('{}' and '{}'): link "
                                "them by an elastic one (a ligament)",
                                l.object, l.with));
      continue;
    }
    const auto pairs = link_pairs(k, l);
    stitched.insert(stitched.end(), pairs.begin(), pairs.end());
  }
  if (!k.problems.empty()) return;
  try {
    stitch_nodes(k.model, stitched);
  } catch (const std::exception& e) {
    k.fail(scene.stitches.front().loc, e.what());
  }
}

// The component's K, given or calibrated from its Young's modulus: the fibres' default.
double shape_memory_stiffness(const Model& model, const std::string& component) {
  for (const ShapeMemory& s : model.shape_memory)
    if (s.component == component) return s.stiffness;
  return 0.0;
}

void add_fibres_of(Compiler& k, const Scene& scene) {
  for (size_t c = 0; c < scene.objects.size(); ++c) {
    const ObjectSpec& o = scene.objects[c];
    if (o.type != ObjectType::active) continue;
    try {
      add_fibres(k.model, int(c), o.fibres.direction,
                 o.fibres.stiffness.value_or(shape_memory_stiffness(k.model, o.name)),
                 o.fibres.max_contraction, o.fibres.activation);
    } catch (const std::exception& e) {
      k.fail(o.fibres.loc, e.what());
    }
  }
}

}  // namespace

Model compile_scene(const Scene& scene) {
  Compiler k{scene, {}, {}};
  k.model.settings = scene.simulation;
  k.model.gravity = scene.simulation.gravity;
  k.model.damping = scene.simulation.damping;
  check_newton_scene(scene, k.problems);
  check_implicit_scene(scene, k.problems);
  for (const ObjectSpec& o : scene.objects) k.add_object(o);
  if (k.problems.empty()) add_links(k, scene);
  if (k.problems.empty()) {
    for (const LoadSpec& l : scene.loads) {
      std::vector<int> nodes = k.select(l.object, l.nodes);
      if (!nodes.empty()) add_applied_force(k.model, {std::move(nodes), l.force});
    }
    for (const ConstraintSpec& c : scene.constraints) {
      if (is_rigid(k.model, c.object)) {
        k.fail(c.loc, fmt::format("object '{}' is rigid: hold or move it as a whole with its "
                                  "'motion' (motion: {{}} holds it in place)",
                                  c.object));
        continue;
      }
      std::vector<int> nodes = k.select(c.object, c.nodes);
      if (nodes.empty()) continue;
      if (c.kind == ConstraintSpec::Kind::fixed)
        add_fixed_nodes(k.model, nodes);
      else if (c.kind == ConstraintSpec::Kind::spring)
        add_spring_support(k.model, {std::move(nodes), c.stiffness});
      else
        add_prescribed_displacement(k.model, {std::move(nodes), c.axes, c.displacement});
    }
    for (const LinkSpec& l : scene.doubled) {
      if (is_rigid(k.model, l.object) && is_rigid(k.model, l.with)) {
        k.fail(l.loc, fmt::format("doubled nodes cannot join two rigid objects ('{}' and '{}'): "
                                  "link them by an elastic one (a ligament)",
                                  l.object, l.with));
        continue;
      }
      const auto pairs = link_pairs(k, l);
      if (!pairs.empty()) add_doubled_nodes(k.model, pairs);
    }
    add_fibres_of(k, scene);
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
