// Scenes in Python: loaded and checked as the program does, then edited field by field. Each
// field takes its unit, range and documentation from the scene schema (schema.hpp), so a value
// set from Python is checked as the same value in a scene file would be.
#include <pybind11/stl.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "phymul/scene.hpp"
#include "phymul/scene_io.hpp"
#include "phymul/schema.hpp"

namespace phymul::python {
namespace {

std::string field_doc(const char* section, const char* name) {
  const SceneField f = scene_field(section, name);
  std::string doc = f.doc;
  if (!f.unit.empty()) doc += " [" + f.unit + "]";
  if (!f.range.empty()) doc += " range " + f.range;
  return doc;
}

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

template <class T, class Get, class Set>
void property(py::class_<T>& c, const char* python_name, Get get, Set set, std::string doc) {
  c.def_property(python_name, get, set, doc.c_str());
}

template <class T>
void quantity(py::class_<T>& c, const char* section, const char* name, double T::*member,
              std::function<void(T&)> after = {}) {
  property(
      c, name, [member](const T& t) { return t.*member; },
      [=](T& t, py::handle v) {
        t.*member = to_quantity(section, name, v);
        if (after) after(t);
      },
      field_doc(section, name));
}

template <class T>
void optional_quantity(py::class_<T>& c, const char* section, const char* name,
                       std::optional<double> T::*member) {
  property(
      c, name, [member](const T& t) { return t.*member; },
      [=](T& t, py::handle v) {
        t.*member =
            v.is_none() ? std::nullopt : std::optional<double>(to_quantity(section, name, v));
      },
      field_doc(section, name) + " (None: absent)");
}

template <class T>
void vector(py::class_<T>& c, const char* section, const char* name, Eigen::Vector3d T::*member) {
  property(
      c, name, [member](const T& t) { return tuple3(t.*member); },
      [=](T& t, py::handle v) { t.*member = to_vector(section, name, v); },
      field_doc(section, name));
}

template <class T>
void integer(py::class_<T>& c, const char* section, const char* name, int T::*member) {
  property(
      c, name, [member](const T& t) { return t.*member; },
      [=](T& t, py::handle v) { t.*member = to_integer(section, name, v); },
      field_doc(section, name));
}

template <class T>
void flag(py::class_<T>& c, const char* section, const char* name, bool T::*member) {
  property(
      c, name, [member](const T& t) { return t.*member; },
      [=](T& t, py::handle v) { t.*member = to_flag(name, v); }, field_doc(section, name));
}

template <class T>
void schedule(py::class_<T>& c, const char* python_name, const char* section, const char* name,
              Schedule T::*member, bool scalar) {
  property(
      c, python_name, [=](const T& t) { return schedule_list(t.*member, scalar); },
      [=](T& t, py::handle v) { t.*member = to_schedule(section, name, v, scalar); },
      field_doc(section, name) + " As [(t, value), ...]; set a constant or a list of (t, value).");
}

// Choices as the scene file spells them.
template <class Enum>
struct Words {
  std::vector<std::pair<const char*, Enum>> words;
  const char* word(Enum e) const {
    for (const auto& [w, v] : words)
      if (v == e) return w;
    return "?";
  }
  Enum value(const char* name, const std::string& w) const {
    std::string allowed;
    for (const auto& [text, v] : words) {
      if (w == text) return v;
      allowed += (allowed.empty() ? "" : ", ") + std::string(text);
    }
    throw py::value_error("'" + std::string(name) + "' must be one of " + allowed + " (got '" + w +
                          "')");
  }
};

template <class T, class Enum>
void choice(py::class_<T>& c, const char* section, const char* name, Enum T::*member,
            Words<Enum> words, bool writable = true) {
  const auto get = [member, words](const T& t) { return std::string(words.word(t.*member)); };
  if (!writable) {
    c.def_property_readonly(name, get, field_doc(section, name).c_str());
    return;
  }
  property(
      c, name, get, [=](T& t, const std::string& w) { t.*member = words.value(name, w); },
      field_doc(section, name));
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
  optional_quantity(c, "simulation", "dt", &SimulationSpec::dt);
  quantity(c, "simulation", "dt_safety", &SimulationSpec::dt_safety);
  quantity(c, "simulation", "duration", &SimulationSpec::duration);
  vector(c, "simulation", "gravity", &SimulationSpec::gravity);
  quantity(c, "simulation", "damping", &SimulationSpec::damping);
  quantity(c, "simulation", "tolerance", &SimulationSpec::tolerance);
  optional_quantity(c, "simulation", "mass_scaling_dt", &SimulationSpec::mass_scaling_dt);
  integer(c, "simulation", "load_steps", &SimulationSpec::load_steps);
  integer(c, "simulation", "implicit_iterations", &SimulationSpec::implicit_iterations);
  quantity(c, "simulation", "implicit_tolerance", &SimulationSpec::implicit_tolerance);
  choice(c, "simulation", "mode", &SimulationSpec::mode,
         Words<SolveMode>{
             {{"dynamic", SolveMode::dynamic}, {"static", SolveMode::static_equilibrium}}});
  choice(c, "simulation", "integrator", &SimulationSpec::integrator,
         Words<Integrator>{{{"verlet", Integrator::verlet},
                            {"newton-cotes", Integrator::newton_cotes},
                            {"implicit", Integrator::implicit}}});
  choice(c, "simulation", "relaxation", &SimulationSpec::relaxation,
         Words<Relaxation>{{{"fire", Relaxation::fire},
                            {"kinetic", Relaxation::kinetic},
                            {"viscous", Relaxation::viscous}}});
}

void bind_object(py::module_& m) {
  py::class_<MaterialSpec> mat(m, "Material", "An object's `material`.");
  // Setting K directly drops a Young's modulus it would be calibrated from.
  quantity<MaterialSpec>(mat, "material", "stiffness", &MaterialSpec::stiffness,
                         [](MaterialSpec& s) { s.young = 0.0; });
  quantity(mat, "material", "young", &MaterialSpec::young);
  quantity(mat, "material", "poisson", &MaterialSpec::poisson);
  optional_quantity(mat, "material", "density", &MaterialSpec::density);
  optional_quantity(mat, "material", "mass", &MaterialSpec::mass);
  flag(mat, "material", "reaction", &MaterialSpec::reaction);
  choice(mat, "material", "model", &MaterialSpec::model,
         Words<ElasticModel>{
             {{"shape-memory", ElasticModel::shape_memory}, {"fem", ElasticModel::fem}}},
         false);

  py::class_<MeshSpec> mesh(m, "Mesh", "An object's `mesh` (generated or from a file).");
  mesh.def_readonly("generator", &MeshSpec::generator)
      .def_readonly("file", &MeshSpec::file)
      .def_readonly("units", &MeshSpec::units)
      .def_readonly("labels", &MeshSpec::labels);  // a label image's
  vector(mesh, "mesh", "size", &MeshSpec::size);
  vector(mesh, "mesh", "radii", &MeshSpec::radii);
  vector(mesh, "mesh", "center", &MeshSpec::center);
  quantity(mesh, "mesh", "radius", &MeshSpec::radius);
  quantity(mesh, "mesh", "length", &MeshSpec::length);
  integer(mesh, "mesh", "subdivisions", &MeshSpec::subdivisions);
  integer(mesh, "mesh", "hexahedra", &MeshSpec::hexahedra);
  integer(mesh, "mesh", "layers", &MeshSpec::layers);

  py::class_<ObjectSpec> o(m, "Object", "An entry of the scene's `objects`.");
  o.def_readonly("name", &ObjectSpec::name)
      .def_property_readonly("type",
                             [](const ObjectSpec& s) {
                               return Words<ObjectType>{{{"elastic", ObjectType::elastic},
                                                         {"rigid", ObjectType::rigid},
                                                         {"active", ObjectType::active}}}
                                   .word(s.type);
                             })
      .def_property_readonly(
          "material", [](ObjectSpec& s) -> MaterialSpec& { return s.material; },
          py::return_value_policy::reference_internal)
      .def_property_readonly(
          "mesh", [](ObjectSpec& s) -> MeshSpec& { return s.mesh; },
          py::return_value_policy::reference_internal);
  flag(o, "object", "volume_constraint", &ObjectSpec::volume_constraint);
  schedule(o, "target_volume", "object", "target_volume", &ObjectSpec::target_volume, true);
}

void bind_interactions(py::module_& m) {
  py::class_<LoadSpec> load(m, "Load", "A nodal force of the scene's `loads`.");
  load.def_readonly("object", &LoadSpec::object);
  schedule(load, "force", "load", "schedule", &LoadSpec::force, false);

  py::class_<PressureSpec> pressure(m, "Pressure", "A pressure of the scene's `loads`.");
  pressure.def_readonly("object", &PressureSpec::object);
  schedule(pressure, "pressure", "load", "pressure_schedule", &PressureSpec::pressure, true);

  py::class_<ConstraintSpec> constraint(m, "Constraint", "An entry of `constraints`.");
  constraint.def_readonly("object", &ConstraintSpec::object);
  schedule(constraint, "displacement", "constraint", "schedule", &ConstraintSpec::displacement,
           false);
  quantity(constraint, "constraint", "stiffness", &ConstraintSpec::stiffness);

  py::class_<ObstacleSpec> obstacle(m, "Obstacle", "An entry of the scene's `obstacles`.");
  obstacle.def_readonly("name", &ObstacleSpec::name)
      .def_readonly("objects", &ObstacleSpec::objects);
  vector(obstacle, "obstacle", "position", &ObstacleSpec::position);
  quantity(obstacle, "obstacle", "radius", &ObstacleSpec::radius);
  quantity(obstacle, "obstacle", "length", &ObstacleSpec::length);
  quantity(obstacle, "obstacle", "friction", &ObstacleSpec::friction);
  schedule(obstacle, "motion", "obstacle", "motion", &ObstacleSpec::motion, false);

  py::class_<OutputSpec> output(m, "Output", "The scene's `output` section.");
  quantity(output, "output", "interval", &OutputSpec::interval);
  flag(output, "output", "vtk", &OutputSpec::vtk);
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
        d["range"] = f.range;
        d["doc"] = f.doc;
        return d;
      },
      py::arg("section"), py::arg("name"), "A scene field's unit, range and documentation.");
}

}  // namespace phymul::python
