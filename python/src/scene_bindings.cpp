// Scenes in Python: loaded and checked as the program does, then edited field by field. Each
// field takes its unit, range and documentation from the scene schema (schema.hpp), so a value
// set from Python is checked as the same value in a scene file would be.
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include "bindings.hpp"
#include "phymul/scene.hpp"
#include "phymul/scene_io.hpp"
#include "phymul/schema.hpp"

namespace phymul::python {
namespace {

// A number (SI) or a quantity text ("4 mm"), checked against the field's range.
double to_quantity(const char* section, const char* name, py::handle value) {
  if (py::isinstance<py::str>(value))
    return parse_scene_field(section, name, value.cast<std::string>());
  if (py::isinstance<py::bool_>(value) || !PyNumber_Check(value.ptr()))
    throw py::type_error(std::string("'") + name +
                         "' expects a number (SI) or a quantity such as '4 mm', got " +
                         std::string(py::str(py::type::of(value).attr("__name__"))));
  return check_scene_field(section, name, py::float_(py::reinterpret_borrow<py::object>(value)));
}

Eigen::Vector3d to_vector(const char* section, const char* name, py::handle value) {
  if (py::isinstance<py::str>(value) || !py::isinstance<py::sequence>(value) || py::len(value) != 3)
    throw py::type_error(std::string("'") + name + "' expects three numbers [x, y, z]");
  const auto items = py::reinterpret_borrow<py::sequence>(value);
  Eigen::Vector3d v;
  for (int k = 0; k < 3; ++k) v[k] = to_quantity(section, name, items[k]);
  return v;
}

int to_integer(const char* section, const char* name, py::handle value) {
  if (py::isinstance<py::bool_>(value) || !PyIndex_Check(value.ptr()))
    throw py::type_error(std::string("'") + name + "' expects a whole number");
  const long long n = value.cast<long long>();
  return int(check_scene_field(section, name, double(n)));
}

bool to_flag(const char* name, py::handle value) {
  if (!py::isinstance<py::bool_>(value))
    throw py::type_error(std::string("'") + name + "' expects True or False");
  return value.cast<bool>();
}

py::tuple tuple3(const Eigen::Vector3d& v) { return py::make_tuple(v.x(), v.y(), v.z()); }

// A schedule as [(t, value), ...] (value: a float for scalar schedules, else (x, y, z)).
py::list schedule_list(const Schedule& s, bool scalar) {
  py::list out;
  for (size_t k = 0; k < s.times.size(); ++k)
    out.append(py::make_tuple(s.times[k], scalar ? py::object(py::float_(s.values[k].x()))
                                                 : py::object(tuple3(s.values[k]))));
  return out;
}

// A constant (number, vector) or [(t, value), ...] with strictly increasing times.
Schedule to_schedule(const char* section, const char* name, py::handle value, bool scalar) {
  const auto one = [&](py::handle v) {
    return scalar ? Eigen::Vector3d(to_quantity(section, name, v), 0, 0)
                  : to_vector(section, name, v);
  };
  const bool events = py::isinstance<py::sequence>(value) && !py::isinstance<py::str>(value) &&
                      py::len(value) > 0 && py::isinstance<py::tuple>(value[py::int_(0)]);
  if (!events) return Schedule::constant(one(value));
  Schedule s;
  for (py::handle event : value) {
    if (!py::isinstance<py::tuple>(event) || py::len(event) != 2)
      throw py::type_error(std::string("'") + name + "' events are (t, value) pairs");
    const auto pair = py::reinterpret_borrow<py::tuple>(event);
    const double t = to_quantity("scalar_schedule", "t", pair[0]);
    if (!s.times.empty() && !(t > s.times.back()))
      throw py::value_error(std::string("'") + name + "' times must be strictly increasing");
    s.times.push_back(t);
    s.values.push_back(one(pair[1]));
  }
  return s;
}

std::string field_doc(const SceneField& f) {
  std::string doc = f.doc;
  if (!f.unit.empty()) doc += " [" + f.unit + "]";
  if (!f.range.empty()) doc += " range " + f.range;
  if (!f.choices.empty()) {
    doc += " One of:";
    for (const auto& word : f.choices) doc += " " + word;
    doc += ".";
  }
  return doc;
}

// A word of the field's choices, or ValueError listing them.
std::string to_word(const SceneField& f, py::handle value) {
  if (!py::isinstance<py::str>(value))
    throw py::type_error("'" + f.name + "' expects a word (str)");
  const std::string word = value.cast<std::string>();
  std::string allowed;
  for (const auto& choice : f.choices) {
    if (choice == word) return word;
    allowed += (allowed.empty() ? "" : ", ") + choice;
  }
  throw py::value_error("'" + f.name + "' must be one of " + allowed + " (got '" + word + "')");
}

std::array<bool, 3> to_axes(const SceneField& f, py::handle value) {
  const std::string text = py::isinstance<py::str>(value) ? value.cast<std::string>() : "";
  std::array<bool, 3> axes{false, false, false};
  for (const char c : text)
    if (c >= 'x' && c <= 'z') axes[size_t(c - 'x')] = true;
  if (text.empty() || text.find_first_not_of("xyz") != std::string::npos)
    throw py::value_error("'" + f.name + "' expects a combination of x, y and z such as 'xz'");
  return axes;
}

template <class Spec>
using Getter = std::function<py::object(const Spec&)>;
template <class Spec>
using Setter = std::function<void(Spec&, py::handle)>;  // empty: read-only

// Python's view of one member: (getter, setter); the setter checks as a scene file would.
// Names, files and labels (what loading read) get no setter.
template <class Spec, class Member>
std::pair<Getter<Spec>, Setter<Spec>> accessors(const SceneField& f, const Member& m) {
  if constexpr (std::is_same_v<Member, ChoiceMember<Spec>>) {
    return {[m](const Spec& s) { return py::cast(std::string(m.get(s))); },
            [m, f](Spec& s, py::handle v) { m.set(s, to_word(f, v)); }};
  } else {
    using T = std::decay_t<decltype(std::declval<Spec&>().*m)>;
    const Getter<Spec> get = [m](const Spec& s) { return py::cast(s.*m); };
    const std::string sec = f.section, name = f.name;
    if constexpr (std::is_same_v<T, double>) {
      return {get,
              [=](Spec& s, py::handle v) { s.*m = to_quantity(sec.c_str(), name.c_str(), v); }};
    } else if constexpr (std::is_same_v<T, std::optional<double>>) {
      return {get, [=](Spec& s, py::handle v) {
                s.*m = v.is_none()
                           ? std::nullopt
                           : std::optional<double>(to_quantity(sec.c_str(), name.c_str(), v));
              }};
    } else if constexpr (std::is_same_v<T, int> || std::is_same_v<T, long>) {
      return {get,
              [=](Spec& s, py::handle v) { s.*m = T(to_integer(sec.c_str(), name.c_str(), v)); }};
    } else if constexpr (std::is_same_v<T, bool>) {
      return {get, [=](Spec& s, py::handle v) { s.*m = to_flag(name.c_str(), v); }};
    } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
      return {[m](const Spec& s) { return py::object(tuple3(s.*m)); },
              [=](Spec& s, py::handle v) { s.*m = to_vector(sec.c_str(), name.c_str(), v); }};
    } else if constexpr (std::is_same_v<T, std::array<int, 3>>) {
      return {
          [m](const Spec& s) {
            return py::object(py::make_tuple((s.*m)[0], (s.*m)[1], (s.*m)[2]));
          },
          [=](Spec& s, py::handle v) {
            if (py::isinstance<py::str>(v) || !py::isinstance<py::sequence>(v) || py::len(v) != 3)
              throw py::type_error("'" + name + "' expects three whole numbers");
            const auto items = py::reinterpret_borrow<py::sequence>(v);
            for (size_t k = 0; k < 3; ++k)
              (s.*m)[k] = to_integer(sec.c_str(), name.c_str(), items[k]);
          }};
    } else if constexpr (std::is_same_v<T, std::array<bool, 3>>) {
      return {[m](const Spec& s) {
                std::string axes;
                for (int k = 0; k < 3; ++k)
                  if ((s.*m)[size_t(k)]) axes += char('x' + k);
                return py::object(py::str(axes));
              },
              [m, f](Spec& s, py::handle v) { s.*m = to_axes(f, v); }};
    } else if constexpr (std::is_same_v<T, Schedule>) {
      const bool scalar = f.kind == "quantity" || f.kind == "scalar_schedule";
      return {
          [m, scalar](const Spec& s) { return py::object(schedule_list(s.*m, scalar)); },
          [=](Spec& s, py::handle v) { s.*m = to_schedule(sec.c_str(), name.c_str(), v, scalar); }};
    } else {
      return {get, {}};
    }
  }
}

// A property's kind as the sweeps (phymul/sweep.py) name it.
template <class Spec>
std::string python_kind(const SceneField& f, const FieldMember<Spec>& member) {
  if (std::holds_alternative<ChoiceMember<Spec>>(member)) return "choice";
  if (std::holds_alternative<double Spec::*>(member)) return "quantity";
  if (std::holds_alternative<std::optional<double> Spec::*>(member)) return "optional";
  if (std::holds_alternative<int Spec::*>(member) || std::holds_alternative<long Spec::*>(member))
    return "integer";
  if (std::holds_alternative<bool Spec::*>(member)) return "flag";
  if (std::holds_alternative<Eigen::Vector3d Spec::*>(member)) return "vector";
  if (std::holds_alternative<Schedule Spec::*>(member))
    return f.kind == "quantity" || f.kind == "scalar_schedule" ? "scalar_schedule"
                                                               : "vector_schedule";
  return f.kind;  // integer_vector, axes
}

template <class Spec>
bool same_member(const FieldMember<Spec>& a, const FieldMember<Spec>& b) {
  if (a.index() != b.index() || std::holds_alternative<ChoiceMember<Spec>>(a)) return false;
  return std::visit(
      [&](const auto& x) {
        using M = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<M, ChoiceMember<Spec>>)
          return false;
        else
          return x == std::get<M>(b);
      },
      a);
}

// One property per member of Spec that a scene field lands in, named after the first field
// that does (`force` beside `schedule`: one schedule either sets). `after` runs after a set.
template <class Spec>
void bind_fields(py::class_<Spec>& c,
                 const std::map<std::string, std::function<void(Spec&)>>& after = {}) {
  std::vector<FieldMember<Spec>> bound;
  py::dict editable;  // name -> kind of each property a program may set
  for (const BoundField<Spec>& field : bound_fields<Spec>()) {
    const SceneField& f = field.field;
    const FieldMember<Spec>& member = field.member;
    if (std::any_of(bound.begin(), bound.end(),
                    [&](const auto& b) { return same_member<Spec>(b, member); }) ||
        std::holds_alternative<NodeSelector Spec::*>(member))
      continue;
    bound.push_back(member);
    auto [get, set] = std::visit([&](const auto& m) { return accessors<Spec>(f, m); }, member);
    std::string doc = field_doc(f);
    if (std::holds_alternative<Schedule Spec::*>(member))
      doc += " As [(t, value), ...]; set a constant or a list of (t, value).";
    if (std::holds_alternative<std::optional<double> Spec::*>(member)) doc += " (None: absent)";
    const auto read = [get](const Spec& s) { return get(s); };
    if (!f.editable || !set) {
      c.def_property_readonly(f.name.c_str(), read, doc.c_str());
      continue;
    }
    editable[py::str(f.name)] = python_kind(f, member);
    std::function<void(Spec&)> then;
    if (const auto hook = after.find(f.name); hook != after.end()) then = hook->second;
    c.def_property(
        f.name.c_str(), read,
        [set, then](Spec& s, py::handle v) {
          set(s, v);
          if (then) then(s);
        },
        doc.c_str());
  }
  c.attr("editable_fields") = editable;
}

// A list of a scene's entries, indexed by position or by name (an object's, an obstacle's,
// or for loads and constraints the object they act on). Items refer into the Scene and keep
// it alive.
template <class T>
struct ListView {
  py::object owner;
  std::vector<T>* items;
  std::string (*key)(const T&);
};

template <class T>
void bind_list(py::module_& m, const char* name) {
  using View = ListView<T>;
  py::class_<View>(m, name)
      .def("__len__", [](const View& v) { return v.items->size(); })
      .def("__getitem__",
           [](const View& v, py::handle index) -> py::object {
             const auto item = [&](size_t k) {
               return py::cast(&(*v.items)[k], py::return_value_policy::reference_internal,
                               v.owner);
             };
             if (py::isinstance<py::str>(index)) {
               const std::string wanted = index.cast<std::string>();
               std::vector<size_t> found;
               for (size_t k = 0; k < v.items->size(); ++k)
                 if (v.key((*v.items)[k]) == wanted) found.push_back(k);
               if (found.size() == 1) return item(found[0]);
               std::string known;
               for (const T& t : *v.items) known += (known.empty() ? "" : ", ") + v.key(t);
               throw py::key_error(found.empty()
                                       ? "no entry '" + wanted + "' (known: " + known + ")"
                                       : "'" + wanted + "' names several entries: index them");
             }
             if (!PyIndex_Check(index.ptr())) throw py::type_error("index by position or by name");
             long long k = index.cast<long long>();
             const auto n = (long long)v.items->size();
             if (k < 0) k += n;
             if (k < 0 || k >= n) throw py::index_error("index out of range");
             return item(size_t(k));
           })
      .def("keys",
           [](const View& v) {
             py::list out;
             for (const T& t : *v.items) out.append(v.key(t));
             return out;
           })
      .def("__iter__", [](const View& v) {
        py::list out;
        for (T& t : *v.items)
          out.append(py::cast(&t, py::return_value_policy::reference_internal, v.owner));
        return py::iter(out);
      });
}

template <class T>
py::object list_of(py::object scene, std::vector<T>& items, std::string (*key)(const T&)) {
  return py::cast(ListView<T>{std::move(scene), &items, key});
}

std::string object_key(const ObjectSpec& o) { return o.name; }
std::string obstacle_key(const ObstacleSpec& o) { return o.name; }
template <class T>
std::string target_key(const T& t) {
  return t.object;
}

void bind_simulation(py::module_& m) {
  py::class_<SimulationSpec> c(m, "Simulation", "The scene's `simulation` section.");
  bind_fields(c);
}

void bind_object(py::module_& m) {
  py::class_<MaterialSpec> mat(m, "Material", "An object's `material`.");
  // Setting K directly drops a Young's modulus it would be calibrated from.
  bind_fields<MaterialSpec>(mat, {{"stiffness", [](MaterialSpec& s) { s.young.reset(); }}});

  py::class_<MeshSpec> mesh(m, "Mesh", "An object's `mesh` (generated or from a file).");
  bind_fields(mesh);

  py::class_<ObjectSpec> o(m, "Object", "An entry of the scene's `objects`.");
  o.def_property_readonly(
       "material", [](ObjectSpec& s) -> MaterialSpec& { return s.material; },
       py::return_value_policy::reference_internal)
      .def_property_readonly(
          "mesh", [](ObjectSpec& s) -> MeshSpec& { return s.mesh; },
          py::return_value_policy::reference_internal);
  bind_fields(o);
}

void bind_interactions(py::module_& m) {
  py::class_<LoadSpec> load(m, "Load", "A nodal force of the scene's `loads`.");
  bind_fields(load);
  py::class_<PressureSpec> pressure(m, "Pressure", "A pressure of the scene's `loads`.");
  pressure.def_readonly("object", &PressureSpec::object);
  bind_fields(pressure);
  py::class_<ConstraintSpec> constraint(m, "Constraint", "An entry of `constraints`.");
  bind_fields(constraint);
  py::class_<ObstacleSpec> obstacle(m, "Obstacle", "An entry of the scene's `obstacles`.");
  obstacle.def_readonly("objects", &ObstacleSpec::objects);
  bind_fields(obstacle);
  py::class_<OutputSpec> output(m, "Output", "The scene's `output` section.");
  bind_fields(output);
}

}  // namespace

void bind_scene(py::module_& m) {
  bind_simulation(m);
  bind_object(m);
  bind_interactions(m);
  bind_list<ObjectSpec>(m, "ObjectList");
  bind_list<LoadSpec>(m, "LoadList");
  bind_list<PressureSpec>(m, "PressureList");
  bind_list<ConstraintSpec>(m, "ConstraintList");
  bind_list<ObstacleSpec>(m, "ObstacleList");

  py::class_<Scene, std::shared_ptr<Scene>>(m, "Scene", "A checked scene, editable field by field.")
      .def_static(
          "from_yaml",
          [](const std::string& text, const std::string& file_name) {
            return std::make_shared<Scene>(parse_scene(text, file_name));
          },
          py::arg("text"), py::arg("file_name") = "scene.yaml",
          "Parses and checks scene text; mesh files are relative to file_name's directory.")
      .def_property_readonly("file", [](const Scene& s) { return s.file.string(); })
      .def_property_readonly(
          "simulation", [](Scene& s) -> SimulationSpec& { return s.simulation; },
          py::return_value_policy::reference_internal)
      .def_property_readonly(
          "output", [](Scene& s) -> OutputSpec& { return s.output; },
          py::return_value_policy::reference_internal)
      .def_property_readonly(
          "objects",
          [](py::object self) { return list_of(self, self.cast<Scene&>().objects, object_key); })
      .def_property_readonly("loads",
                             [](py::object self) {
                               return list_of(self, self.cast<Scene&>().loads,
                                              target_key<LoadSpec>);
                             })
      .def_property_readonly("pressures",
                             [](py::object self) {
                               return list_of(self, self.cast<Scene&>().pressures,
                                              target_key<PressureSpec>);
                             })
      .def_property_readonly("constraints",
                             [](py::object self) {
                               return list_of(self, self.cast<Scene&>().constraints,
                                              target_key<ConstraintSpec>);
                             })
      .def_property_readonly("obstacles",
                             [](py::object self) {
                               return list_of(self, self.cast<Scene&>().obstacles, obstacle_key);
                             })
      .def(
          "copy", [](const Scene& s) { return std::make_shared<Scene>(s); },
          "An independent copy (edits to one leave the other as it is).");

  m.def(
      "load_scene",
      [](const std::string& path) { return std::make_shared<Scene>(phymul::load_scene(path)); },
      py::arg("path"), "Reads and checks a scene file (SceneError lists every problem).");
  m.def(
      "scene_field",
      [](const std::string& section, const std::string& name) {
        const SceneField f = scene_field(section, name);
        py::dict d;
        d["section"] = f.section;
        d["name"] = f.name;
        d["unit"] = f.unit;
        d["kind"] = f.kind;
        d["range"] = f.range;
        d["choices"] = f.choices;
        d["doc"] = f.doc;
        d["editable"] = f.editable;
        return d;
      },
      py::arg("section"), py::arg("name"),
      "A scene field's kind, unit, range, choices and documentation, and whether a program may "
      "set it.");
}

}  // namespace phymul::python
