#include "io/scene_lml.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <unordered_map>

#include "phymul/camitk.hpp"
#include "phymul/mesh_io.hpp"

namespace phymul::io {
namespace {

const char* type_name(LmlLoad::Type t) {
  return t == LmlLoad::Type::translation ? "Translation"
         : t == LmlLoad::Type::force     ? "Force"
                                         : "Pressure";
}

struct Holder {
  int object, node;
};

class LmlMapper {
 public:
  LmlMapper(Scene& scene, std::vector<Diagnostic>& problems, std::string file)
      : scene_(scene), problems_(problems), file_(std::move(file)) {}
  bool index_objects();
  void add(const LmlLoad& load);

 private:
  std::optional<std::vector<int>> atoms_of(const LmlLoad& load);
  std::map<int, std::vector<int>> nodes_of(const LmlLoad& load, const std::vector<int>& atoms);
  Schedule schedule(const LmlLoad& load, const Vec3& factor) const;
  void problem(const LmlLoad& load, std::string message) {
    problems_.push_back({{file_, load.line, 0}, std::move(message)});
  }

  Scene& scene_;
  std::vector<Diagnostic>& problems_;
  std::string file_;
  std::vector<int> pml_objects_;
  std::unordered_map<int, std::vector<Holder>> holders_;  // atom index -> its nodes
};

// The objects read from the PML file, and which of their nodes each atom is.
bool LmlMapper::index_objects() {
  std::set<std::string> files;
  for (size_t i = 0; i < scene_.objects.size(); ++i) {
    const MeshSpec& m = scene_.objects[i].mesh;
    if (m.atom_ids.empty()) continue;
    pml_objects_.push_back(int(i));
    files.insert(m.file);
    for (size_t n = 0; n < m.atom_ids.size(); ++n)
      holders_[m.atom_ids[n]].push_back({int(i), int(n)});
  }
  const SourceLoc& at = scene_.lml->loc;
  if (pml_objects_.empty()) {
    problems_.push_back({at,
                         "'lml' loads atoms of a CamiTK PML file, and no object's mesh is one "
                         "(mesh: {file: model.pml, component: ...})"});
    return false;
  }
  if (files.size() > 1) {
    problems_.push_back({at, fmt::format("'lml' names atoms of one PML file, and the objects "
                                         "come from {}: keep one PML file per scene",
                                         fmt::join(files, ", "))});
    return false;
  }
  return true;
}

// The atoms a load names: indices, component names (as the objects' node sets) or "*".
std::optional<std::vector<int>> LmlMapper::atoms_of(const LmlLoad& load) {
  std::vector<int> atoms = load.atoms;
  for (const std::string& name : load.names) {
    bool found = false;
    for (int i : pml_objects_) {
      const MeshSpec& m = scene_.objects[size_t(i)].mesh;
      const auto set = m.file_mesh->node_sets.find(pml_node_set_name(name));
      if (name != "*" && set == m.file_mesh->node_sets.end()) continue;
      found = true;
      if (name == "*")
        atoms.insert(atoms.end(), m.atom_ids.begin(), m.atom_ids.end());
      else
        for (int n : set->second) atoms.push_back(m.atom_ids[size_t(n)]);
    }
    if (!found) {
      problem(load, fmt::format("<appliedTo> names '{}', which is no component with atoms in the "
                                "objects read from {}",
                                name, scene_.objects[size_t(pml_objects_[0])].mesh.file));
      return std::nullopt;
    }
  }
  std::sort(atoms.begin(), atoms.end());
  atoms.erase(std::unique(atoms.begin(), atoms.end()), atoms.end());
  return atoms;
}

// Per object, its nodes among the atoms; a force goes to the first object holding an atom.
std::map<int, std::vector<int>> LmlMapper::nodes_of(const LmlLoad& load,
                                                    const std::vector<int>& atoms) {
  std::map<int, std::vector<int>> nodes;
  std::vector<int> missing;
  for (int a : atoms) {
    const auto it = holders_.find(a);
    if (it == holders_.end()) {
      missing.push_back(a);
      continue;
    }
    for (const Holder& h : it->second) {
      nodes[h.object].push_back(h.node);
      if (load.type == LmlLoad::Type::force) break;
    }
  }
  if (!missing.empty()) {
    std::vector<std::string> names;
    for (int i : pml_objects_) names.push_back(fmt::format("'{}'", scene_.objects[size_t(i)].name));
    problem(load,
            fmt::format("the {} load applies to atom {}{}, which no object holds (the "
                        "objects read from {}: {})",
                        type_name(load.type), missing[0],
                        missing.size() > 1 ? fmt::format(" (and {} more)", missing.size() - 1) : "",
                        scene_.objects[size_t(pml_objects_[0])].mesh.file, fmt::join(names, ", ")));
    return {};
  }
  for (auto& [object, list] : nodes) std::sort(list.begin(), list.end());
  return nodes;
}

// value(t) * factor at the load's dates. CamiTK applies nothing before the first date: a force
// or pressure starting later is 0 until just before it.
Schedule LmlMapper::schedule(const LmlLoad& load, const Vec3& factor) const {
  Schedule s;
  if (load.type != LmlLoad::Type::translation && load.dates[0] > 0.0 && load.values[0] != 0.0) {
    s.times = {0.0, std::nextafter(load.dates[0], 0.0)};
    s.values = {Vec3::Zero(), Vec3::Zero()};
  }
  for (size_t k = 0; k < load.dates.size(); ++k) {
    s.times.push_back(load.dates[k]);
    s.values.push_back(load.values[k] * factor);
  }
  return s;
}

void LmlMapper::add(const LmlLoad& load) {
  const auto atoms = atoms_of(load);
  if (!atoms) return;
  const auto nodes = nodes_of(load, *atoms);
  Vec3 factor = Vec3::Zero();
  std::array<bool, 3> held{};
  for (int k = 0; k < 3; ++k) {
    held[size_t(k)] = load.axes[size_t(k)] != LmlLoad::Axis::free;
    if (load.axes[size_t(k)] == LmlLoad::Axis::given) factor[k] = load.direction[k];
  }
  const SourceLoc loc{file_, load.line, 0};
  if (load.type == LmlLoad::Type::translation && load.dates[0] > 0.0)
    scene_.notes.push_back(
        fmt::format("{}:{}: the Translation starts at {:g} s; phymul holds its "
                    "first value from 0 s (CamiTK leaves the nodes free before)",
                    file_, load.line, load.dates[0]));
  for (const auto& [object, list] : nodes) {
    NodeSelector selector;
    selector.kind = NodeSelector::Kind::indices;
    selector.indices = list;
    selector.loc = loc;
    const std::string& name = scene_.objects[size_t(object)].name;
    if (load.type == LmlLoad::Type::force) {
      scene_.loads.push_back({name, selector, schedule(load, factor), loc});
    } else if (load.type == LmlLoad::Type::pressure) {
      PressureSpec p;
      p.object = name, p.nodes = selector, p.loc = loc;
      p.pressure = schedule(load, Vec3::UnitX());
      scene_.pressures.push_back(std::move(p));
    } else {
      ConstraintSpec c;
      c.object = name, c.nodes = selector, c.loc = loc, c.axes = held;
      c.displacement = schedule(load, factor);
      const bool still = std::all_of(c.displacement.values.begin(), c.displacement.values.end(),
                                     [](const Vec3& v) { return v.isZero(0.0); });
      const bool all_axes = held[0] && held[1] && held[2];
      c.kind = still && all_axes ? ConstraintSpec::Kind::fixed : ConstraintSpec::Kind::displacement;
      if (c.kind == ConstraintSpec::Kind::fixed)
        c.displacement = Schedule::constant(Vec3::Zero());  // as the scene reader spells it
      scene_.constraints.push_back(std::move(c));
    }
  }
}

}  // namespace

void apply_lml(Scene& scene, std::vector<Diagnostic>& problems) {
  if (!scene.lml || scene.lml->applied) return;
  const std::filesystem::path path = scene.file.parent_path() / scene.lml->file;
  LmlMapper mapper(scene, problems, path.string());
  if (!mapper.index_objects()) return;
  std::vector<LmlLoad> loads;
  try {
    loads = read_lml(path);
  } catch (const MeshFileError& e) {
    problems.push_back({{e.file, e.line, e.column}, e.message + " (the scene's 'lml')"});
    return;
  }
  const size_t before = problems.size();
  for (const LmlLoad& load : loads) mapper.add(load);
  if (problems.size() == before) scene.lml->applied = true;
}

}  // namespace phymul::io
