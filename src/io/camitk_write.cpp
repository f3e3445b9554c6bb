// `phymul export-pml` (camitk.hpp): a prepared scene's objects as a CamiTK PML physical model
// and its loads, fixed and prescribed nodes as LML, in millimetres, newtons and kilopascals.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "phymul/camitk.hpp"
#include "phymul/model.hpp"

namespace phymul {
namespace {

constexpr double kMm = 1e3;   // coordinates and translations are written in mm
constexpr double kKPa = 1e3;  // pressures in kPa

const char* pml_type(CellType t) {
  switch (t) {
    case CellType::tetra:
      return "TETRAHEDRON";
    case CellType::hexa:
      return "HEXAHEDRON";
    case CellType::wedge:
      return "WEDGE";
    case CellType::triangle:
      return "TRIANGLE";
    case CellType::quad:
      return "QUAD";
  }
  return "INVALID";
}

// The objects' meshes and each node's atom index: the PML's own indices when every object
// came from one and no index is used twice, else object after object from 0.
struct Atoms {
  std::vector<Mesh> meshes;
  std::vector<std::vector<int>> ids;
};

Atoms number_atoms(const Scene& scene) {
  Atoms a;
  std::set<int> seen;
  bool keep = true;
  for (const ObjectSpec& o : scene.objects) {
    a.meshes.push_back(make_mesh(o.mesh));
    keep = keep && o.mesh.atom_ids.size() == a.meshes.back().points.size();
    for (int id : o.mesh.atom_ids) keep = keep && seen.insert(id).second;
  }
  int next = 0;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    std::vector<int> ids = scene.objects[i].mesh.atom_ids;
    if (!keep) {
      ids.resize(a.meshes[i].points.size());
      for (int& id : ids) id = next++;
    }
    a.ids.push_back(std::move(ids));
  }
  return a;
}

int object_index(const Scene& scene, const std::string& name) {
  for (size_t i = 0; i < scene.objects.size(); ++i)
    if (scene.objects[i].name == name) return int(i);
  throw std::invalid_argument(fmt::format("export-pml: no object named '{}'", name));
}

// The selected nodes of a mesh, as the model's compiler selects them at rest.
std::vector<int> select(const Mesh& mesh, const NodeSelector& s) {
  using Kind = NodeSelector::Kind;
  std::vector<int> nodes;
  if (s.kind == Kind::named) {
    const auto it = mesh.node_sets.find(s.name);
    if (it != mesh.node_sets.end()) nodes = it->second;
  } else if (s.kind == Kind::indices) {
    for (int i : s.indices)
      if (i >= 0 && i < int(mesh.points.size())) nodes.push_back(i);
  } else {
    for (int i = 0; i < int(mesh.points.size()); ++i) {
      const Vec3& p = mesh.points[size_t(i)];
      const bool in = s.kind == Kind::all ||
                      (s.kind == Kind::box && (p.array() >= s.min.array()).all() &&
                       (p.array() <= s.max.array()).all()) ||
                      (s.kind == Kind::sphere && (p - s.center).norm() <= s.radius) ||
                      (s.kind == Kind::half_space && (p - s.point).dot(s.normal) >= 0.0);
      if (in) nodes.push_back(i);
    }
  }
  return nodes;
}

// "0-3,7": the atoms of a selection as CamiTK's target lists write them.
std::string target_list(std::vector<int> atoms) {
  std::sort(atoms.begin(), atoms.end());
  atoms.erase(std::unique(atoms.begin(), atoms.end()), atoms.end());
  std::string out;
  for (size_t i = 0; i < atoms.size();) {
    size_t j = i;
    while (j + 1 < atoms.size() && atoms[j + 1] == atoms[j] + 1) ++j;
    if (!out.empty()) out += ',';
    out += j == i ? fmt::format("{}", atoms[i]) : fmt::format("{}-{}", atoms[i], atoms[j]);
    i = j + 1;
  }
  return out;
}

void write_pml(std::ostream& out, const Scene& scene, const Atoms& a) {
  std::map<std::string, std::vector<int>> sets;  // node sets of every object, by name
  size_t atoms = 0, cells = 0;
  for (size_t i = 0; i < a.meshes.size(); ++i) {
    atoms += a.meshes[i].points.size(), cells += a.meshes[i].cells.size();
    for (const auto& [name, nodes] : a.meshes[i].node_sets)
      for (int n : nodes) sets[name].push_back(a.ids[i][size_t(n)]);
  }
  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << fmt::format("<!-- written by phymul export-pml from {}: coordinates in mm -->\n",
                     scene.file.filename().string())
      << fmt::format(
             "<physicalModel name=\"{}\" nrOfAtoms=\"{}\" nrOfExclusiveComponents=\"{}\" "
             "nrOfInformativeComponents=\"{}\" nrOfCells=\"{}\">\n",
             scene.file.stem().string(), atoms, scene.objects.size(), sets.size(),
             cells + sets.size())
      << "<atoms>\n<structuralComponent name=\"atoms\">\n"
      << fmt::format("<nrOfStructures value=\"{}\"/>\n", atoms);
  for (size_t i = 0; i < a.meshes.size(); ++i)
    for (size_t n = 0; n < a.meshes[i].points.size(); ++n) {
      const Vec3 p = a.meshes[i].points[n] * kMm;
      out << fmt::format("<atom><atomProperties index=\"{}\" x=\"{}\" y=\"{}\" z=\"{}\"/></atom>\n",
                         a.ids[i][n], p.x(), p.y(), p.z());
    }
  out << "</structuralComponent>\n</atoms>\n<exclusiveComponents>\n"
      << "<multiComponent name=\"Exclusive Components\">\n";
  for (size_t i = 0; i < a.meshes.size(); ++i) {
    out << fmt::format("<structuralComponent name=\"{}\" mode=\"WIREFRAME_AND_SURFACE\">\n",
                       scene.objects[i].name)
        << fmt::format("<nrOfStructures value=\"{}\"/>\n", a.meshes[i].cells.size());
    for (const Cell& c : a.meshes[i].cells) {
      out << fmt::format("<cell><cellProperties type=\"{}\"/>", pml_type(c.type));
      for (int n : c.node_span())
        out << fmt::format("<atomRef index=\"{}\"/>", a.ids[i][size_t(n)]);
      out << "</cell>\n";
    }
    out << "</structuralComponent>\n";
  }
  out << "</multiComponent>\n</exclusiveComponents>\n<informativeComponents>\n";
  if (!sets.empty()) out << "<multiComponent name=\"Informative Components\">\n";
  for (const auto& [name, ids] : sets) {
    out << fmt::format("<structuralComponent name=\"{}\" mode=\"POINTS\">\n", name)
        << "<nrOfStructures value=\"1\"/>\n<cell><cellProperties type=\"POLY_VERTEX\"/>";
    for (int id : ids) out << fmt::format("<atomRef index=\"{}\"/>", id);
    out << "</cell>\n</structuralComponent>\n";
  }
  if (!sets.empty()) out << "</multiComponent>\n";
  out << "</informativeComponents>\n</physicalModel>\n";
}

// One LML load: atoms, scalar events along a direction. Per axis, "NULL", a number, or
// nothing (free).
struct LmlOut {
  std::string type, unit;
  std::vector<int> atoms;
  std::vector<double> dates, values;
  std::array<std::string, 3> direction;
};

// A schedule of vectors as loads of scalar events: one along its direction when every value
// lies on one line, else one per axis. `held`: the axes a translation prescribes.
std::vector<LmlOut> as_events(const Schedule& s, std::array<bool, 3> held, double scale,
                              const LmlOut& base) {
  Vec3 u = Vec3::Zero();
  for (const Vec3& v : s.values)
    if (!v.isZero(0.0)) {
      u = v.normalized();
      break;
    }
  const bool one_line = std::all_of(s.values.begin(), s.values.end(), [&](const Vec3& v) {
    return (v - v.dot(u) * u).norm() <= 1e-12 * v.norm();
  });
  std::vector<std::pair<Vec3, std::array<bool, 3>>> parts;  // direction, axes written
  if (one_line) {
    parts.push_back({u, held});
  } else {
    for (int k = 0; k < 3; ++k)
      if (held[size_t(k)]) {
        std::array<bool, 3> axis{};
        axis[size_t(k)] = true;
        parts.push_back({Vec3::Unit(k), axis});
      }
  }
  // A translation holds a zero axis ("NULL"); a force has no component there.
  const std::string zero = base.type == "Translation" ? "NULL" : "0";
  std::vector<LmlOut> out;
  for (const auto& [d, axes] : parts) {
    LmlOut l = base;
    for (int k = 0; k < 3; ++k)
      l.direction[size_t(k)] = !axes[size_t(k)] ? "" : d[k] == 0.0 ? zero : fmt::format("{}", d[k]);
    // phymul holds the first value before the first event, CamiTK applies nothing.
    if (!s.times.empty() && s.times[0] > 0.0) {
      l.dates.push_back(0.0);
      l.values.push_back(s.values[0].dot(d) * scale);
    }
    for (size_t e = 0; e < s.times.size(); ++e) {
      l.dates.push_back(s.times[e]);
      l.values.push_back(s.values[e].dot(d) * scale);
    }
    out.push_back(std::move(l));
  }
  return out;
}

std::vector<int> atoms_of(const Scene& scene, const Atoms& a, const std::string& object,
                          const NodeSelector& nodes) {
  const int i = object_index(scene, object);
  std::vector<int> atoms;
  for (int n : select(a.meshes[size_t(i)], nodes)) atoms.push_back(a.ids[size_t(i)][size_t(n)]);
  return atoms;
}

std::vector<LmlOut> lml_loads(const Scene& scene, const Atoms& a) {
  std::vector<LmlOut> loads;
  const auto add = [&](std::vector<LmlOut> more) {
    for (LmlOut& l : more)
      if (!l.atoms.empty()) loads.push_back(std::move(l));
  };
  for (const ConstraintSpec& c : scene.constraints) {
    if (c.kind == ConstraintSpec::Kind::spring) continue;
    const LmlOut base{"Translation", "mm", atoms_of(scene, a, c.object, c.nodes), {}, {}, {}};
    const std::array<bool, 3> held =
        c.kind == ConstraintSpec::Kind::fixed ? std::array<bool, 3>{true, true, true} : c.axes;
    add(as_events(c.displacement, held, kMm, base));
  }
  for (const LoadSpec& l : scene.loads)
    add(as_events(l.force, {true, true, true}, 1.0,
                  {"Force", "N", atoms_of(scene, a, l.object, l.nodes), {}, {}, {}}));
  for (const PressureSpec& p : scene.pressures) {  // a scalar, along the faces' normals
    LmlOut out{"Pressure", "kPa", atoms_of(scene, a, p.object, p.nodes), {}, {}, {}};
    const Schedule& s = p.pressure;
    for (size_t e = 0; e < s.times.size(); ++e) {
      if (e == 0 && s.times[0] > 0.0)
        out.dates.push_back(0.0), out.values.push_back(s.values[0].x() / kKPa);
      out.dates.push_back(s.times[e]);
      out.values.push_back(s.values[e].x() / kKPa);
    }
    add({out});
  }
  return loads;
}

void write_lml(std::ostream& out, const std::vector<LmlOut>& loads) {
  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<loads xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\">\n";
  for (const LmlOut& l : loads) {
    out << fmt::format("<load xsi:type=\"{}\">\n\t<appliedTo>{}</appliedTo>\n", l.type,
                       target_list(l.atoms));
    for (size_t e = 0; e < l.dates.size(); ++e)
      out << fmt::format("\t<valueEvent date=\"{}\" value=\"{}\"/>\n", l.dates[e], l.values[e]);
    if (l.direction != std::array<std::string, 3>{}) {
      out << "\t<direction";
      for (int k = 0; k < 3; ++k)
        if (!l.direction[size_t(k)].empty())
          out << fmt::format(" {}=\"{}\"", "xyz"[k], l.direction[size_t(k)]);
      out << "/>\n";
    }
    out << fmt::format("\t<unit>{}</unit>\n</load>\n", l.unit);
  }
  out << "</loads>\n";
}

// What the PML and LML leave out, one sentence each.
std::vector<std::string> unsaid(const Scene& scene) {
  std::vector<std::string> notes{
      "objects' types and materials are not written (a PML component carries no standard "
      "material): the scene gives them"};
  const auto note = [&](bool present, const char* what) {
    const std::string text = fmt::format("{} cannot be said in PML or LML: not written", what);
    if (present && std::find(notes.begin(), notes.end(), text) == notes.end())
      notes.push_back(text);
  };
  note(std::any_of(scene.constraints.begin(), scene.constraints.end(),
                   [](const ConstraintSpec& c) { return c.kind == ConstraintSpec::Kind::spring; }),
       "spring constraints");
  note(std::any_of(scene.pressures.begin(), scene.pressures.end(),
                   [](const PressureSpec& p) { return p.in_cylinder; }),
       "a pressure's cylinder (its nodes are written, all of them loaded)");
  note(!scene.simulation.gravity.isZero(0.0), "gravity");
  note(!scene.obstacles.empty(), "obstacles");
  note(!scene.contacts.empty(), "contacts");
  note(!scene.needles.empty(), "needles");
  note(!scene.stitches.empty() || !scene.doubled.empty(), "stitches and doubled nodes");
  for (const ObjectSpec& o : scene.objects) {
    note(o.motion.has_value(), "a rigid object's motion");
    note(o.volume_constraint, "volume constraints");
  }
  return notes;
}

void save(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  if (!out.good()) throw std::runtime_error(fmt::format("cannot write {}", path.string()));
}

}  // namespace

PmlExport export_pml(const Scene& scene, const std::filesystem::path& dir) {
  const Atoms atoms = number_atoms(scene);
  std::filesystem::create_directories(dir);
  PmlExport e;
  const std::string stem = scene.file.stem().empty() ? "scene" : scene.file.stem().string();
  e.pml = dir / (stem + ".pml");
  e.lml = dir / (stem + ".lml");
  std::ostringstream pml, lml;
  write_pml(pml, scene, atoms);
  write_lml(lml, lml_loads(scene, atoms));
  save(e.pml, pml.str());
  save(e.lml, lml.str());
  e.notes = unsaid(scene);
  return e;
}

}  // namespace phymul
