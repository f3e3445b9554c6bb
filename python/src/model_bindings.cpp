// Models and Data in Python: a compiled Model (read-only), Data whose arrays are NumPy views
// of the engine's memory, and the free functions that advance them, the GIL released.
#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include <string>

#include "bindings.hpp"
#include "phymul/forces.hpp"
#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"

namespace phymul::python {

Busy::Busy(PyData& d) : d_(d) {
  if (!d_.busy.exchange(true)) {
    d_.owner = std::this_thread::get_id();
    return;
  }
  if (d_.owner.load() == std::this_thread::get_id()) {
    nested_ = true;
    return;
  }
  throw std::runtime_error(
      "this Data is being stepped in another thread; give each thread its own Data "
      "(phymul.Data(model))");
}
Scene prepared_copy(const Scene& edited) {
  Scene scene = edited;
  for (ObjectSpec& o : scene.objects)
    if (!o.material.young) o.calibration.reset();  // K was set directly
  prepare_scene(scene);
  return scene;
}

Busy::~Busy() {
  if (nested_) return;
  d_.owner = std::thread::id{};
  d_.busy = false;
}

namespace {

using ModelPtr = std::shared_ptr<const Model>;

// What compile does to a scene edited in Python before compiling: its mesh files read and
// Young's moduli calibrated (prepare_scene), on a copy so the Python scene is left as it was.
ModelPtr compile(const Scene& edited) {
  return std::make_shared<const Model>(compile_scene(prepared_copy(edited)));
}

const Model& model_of(const PyData& d, const Model& model) {
  if (d.model.get() != &model)
    throw py::value_error("this Data belongs to another Model (make it with phymul.Data(model))");
  return model;
}

size_t vec3_stride() { return sizeof(Vec3); }
static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 rows are three packed doubles");

py::array vec3_view(const std::vector<Vec3>& v, py::handle owner, bool writable) {
  return view(v.empty() ? nullptr : v.front().data(), v.size(), 3, vec3_stride(), owner, writable);
}

py::array int_view(const std::vector<int>& v, py::handle owner) {
  return view(v.data(), v.size(), 0, sizeof(int), owner, false);
}

py::array triangle_view(const std::vector<Triangle>& v, py::handle owner) {
  return view(v.empty() ? nullptr : v.front().data(), v.size(), 3, sizeof(Triangle), owner, false);
}

// One component of a model: its nodes, surface triangles and node sets as index arrays.
py::dict component_dict(const Component& c, py::handle owner) {
  py::dict d;
  d["name"] = c.name;
  d["kind"] = c.kind == ObjectType::rigid    ? "rigid"
              : c.kind == ObjectType::active ? "active"
                                             : "elastic";
  d["nodes"] = int_view(c.nodes, owner);
  d["surface"] = triangle_view(c.boundary, owner);
  py::dict sets;
  for (const auto& [name, nodes] : c.node_sets) sets[py::str(name)] = int_view(nodes, owner);
  d["node_sets"] = sets;
  return d;
}

void step_n(const Model& model, PyData& d, long n) {
  if (n < 0) throw py::value_error("n must be >= 0 (got " + std::to_string(n) + ")");
  Busy busy(d);
  if (d.controller && !d.controller.is_none()) {
    // The controller acts between steps: it runs with the GIL, each step without it.
    py::object self = py::cast(&d, py::return_value_policy::reference);
    py::object model_object = py::cast(d.model);
    for (long k = 0; k < n; ++k) {
      d.controller(model_object, self);
      py::gil_scoped_release release;
      phymul::step(model, d.data);
    }
    return;
  }
  py::gil_scoped_release release;
  for (long k = 0; k < n; ++k) phymul::step(model, d.data);
}

py::dict static_result(const StaticResult& r) {
  py::dict d;
  d["converged"] = r.converged;
  d["iterations"] = r.iterations;
  d["residual"] = r.residual;
  return d;
}

// The entry of `count` named by an index or by name (names(k) gives entry k's).
template <class Name>
size_t entry(py::handle key, size_t count, Name names, const char* what) {
  if (py::isinstance<py::str>(key)) {
    const std::string wanted = key.cast<std::string>();
    std::string known;
    for (size_t k = 0; k < count; ++k) {
      if (names(k) == wanted) return k;
      known += (known.empty() ? "" : ", ") + names(k);
    }
    throw py::key_error(std::string("no ") + what + " '" + wanted +
                        "' (known: " + (known.empty() ? "none" : known) + ")");
  }
  if (!PyIndex_Check(key.ptr())) throw py::type_error(std::string(what) + ": an index or a name");
  const long long k = key.cast<long long>();
  if (k < 0 || k >= (long long)count)
    throw py::index_error(std::string(what) + " index " + std::to_string(k) + " out of range (" +
                          std::to_string(count) + ")");
  return size_t(k);
}

Vec3 finite_vector(py::handle value, const char* what) {
  const auto v = value.cast<std::vector<double>>();
  if (v.size() != 3) throw py::value_error(std::string(what) + " takes three numbers");
  for (double c : v)
    if (!std::isfinite(c)) throw py::value_error(std::string(what) + " must be finite");
  return {v[0], v[1], v[2]};
}

// A control changed by a program: from its value now to `value` at the end of the next step,
// held after; the step sees the change as a motion over its dt (the contact's friction and
// the obstacle's velocity included).
void ramp(Schedule& s, const Data& d, const Vec3& value) {
  const Vec3 now = s.empty() ? value : Vec3(s.at(d.time));
  s = Schedule{{d.time, d.time + d.dt}, {now, value}};
}

std::string component_name(const Model& m, int component) {
  return m.components[size_t(component)].name;
}

void bind_controls(py::class_<PyData, std::shared_ptr<PyData>>& c) {
  c.def_property_readonly(
      "applied_forces",
      [](py::object self) {
        PyData& d = self.cast<PyData&>();
        if (d.data.controls.applied_force.empty()) {
          Busy busy(d);  // sized once and never shrunk: views of it stay valid
          d.data.controls.applied_force.assign(d.data.x.size(), Vec3::Zero());
        }
        return vec3_view(d.data.controls.applied_force, self, true);
      },
      "(n, 3) N, writable: external forces added to the loads at every step");
  c.def(
      "obstacle_translation",
      [](const PyData& d, py::handle key) {
        const Model& m = *d.model;
        const size_t k = entry(
            key, m.obstacles.size(), [&](size_t i) { return m.obstacles[i].name; }, "obstacle");
        const Vec3 t = d.data.controls.obstacle_motion[k].at(d.data.time);
        return py::make_tuple(t.x(), t.y(), t.z());
      },
      py::arg("obstacle"), "m: the obstacle's translation from its scene position now");
  c.def(
      "move_obstacle",
      [](PyData& d, py::handle key, py::handle translation) {
        const Model& m = *d.model;
        const size_t k = entry(
            key, m.obstacles.size(), [&](size_t i) { return m.obstacles[i].name; }, "obstacle");
        const Vec3 t = finite_vector(translation, "translation");
        Busy busy(d);
        ramp(d.data.controls.obstacle_motion[k], d.data, t);
      },
      py::arg("obstacle"), py::arg("translation"),
      "Moves the obstacle to this translation (m, from its scene position) over the next step");
  c.def(
      "move_body",
      [](PyData& d, py::handle key, py::handle translation, py::handle rotation) {
        const Model& m = *d.model;
        const size_t k = entry(
            key, m.rigid_bodies.size(),
            [&](size_t i) { return component_name(m, m.rigid_bodies[i].component); }, "rigid body");
        if (!m.rigid_bodies[k].driven)
          throw py::value_error("rigid body '" + component_name(m, m.rigid_bodies[k].component) +
                                "' is free (give it a `motion` in the scene to drive it)");
        const Vec3 t = finite_vector(translation, "translation");
        const Vec3 r = finite_vector(rotation, "rotation");
        Busy busy(d);
        ramp(d.data.controls.body_translation[k], d.data, t);
        ramp(d.data.controls.body_rotation[k], d.data, r);
      },
      py::arg("body"), py::arg("translation"), py::arg("rotation") = std::vector<double>{0, 0, 0},
      "Moves a driven rigid body (an instrument) to this translation (m) and rotation vector "
      "(rad) from its rest pose over the next step");
  c.def(
      "pressure",
      [](const PyData& d, py::handle key) {
        const Model& m = *d.model;
        const size_t k = entry(
            key, m.pressures.size(),
            [&](size_t i) { return component_name(m, m.pressures[i].component); }, "pressure");
        return d.data.controls.pressure[k].at(d.data.time).x();
      },
      py::arg("load"), "Pa: the pressure load's value now (by index or its object's name)");
  c.def(
      "set_pressure",
      [](PyData& d, py::handle key, double p) {
        const Model& m = *d.model;
        const size_t k = entry(
            key, m.pressures.size(),
            [&](size_t i) { return component_name(m, m.pressures[i].component); }, "pressure");
        if (!std::isfinite(p)) throw py::value_error("pressure must be finite (Pa)");
        Busy busy(d);
        ramp(d.data.controls.pressure[k], d.data, Vec3(p, 0, 0));
      },
      py::arg("load"), py::arg("pressure"), "Pa, reached over the next step");
  c.def(
      "target_volume",
      [](const PyData& d, py::handle key) {
        const Model& m = *d.model;
        const size_t k = entry(
            key, m.volumes.size(), [&](size_t i) { return m.volumes[i].component; },
            "volume constraint");
        return target_volume(m, d.data.controls, k, d.data.time);
      },
      py::arg("object"), "m^3: the volume constraint's target now");
  c.def(
      "set_target_volume",
      [](PyData& d, py::handle key, double volume) {
        const Model& m = *d.model;
        const size_t k = entry(
            key, m.volumes.size(), [&](size_t i) { return m.volumes[i].component; },
            "volume constraint");
        if (!(volume > 0.0) || !std::isfinite(volume))
          throw py::value_error("target volume must be > 0 m^3 (got " + std::to_string(volume) +
                                ")");
        Busy busy(d);
        Schedule& s = d.data.controls.target_volume[k];
        if (s.empty()) s = Schedule::constant(Vec3(m.volumes[k].target_volume, 0, 0));
        ramp(s, d.data, Vec3(volume, 0, 0));
      },
      py::arg("object"), py::arg("volume"), "m^3, reached over the next step");
}

void bind_model_class(py::module_& m) {
  py::class_<Model, std::shared_ptr<Model>>(m, "Model", "A compiled scene: read-only.")
      .def_property_readonly("nodes", [](const Model& model) { return model.rest_position.size(); })
      .def_property_readonly("rest_positions",
                             [](py::object self) {
                               return vec3_view(self.cast<const Model&>().rest_position, self,
                                                false);
                             })
      .def_property_readonly("masses",
                             [](py::object self) {
                               const auto& mass = self.cast<const Model&>().mass;
                               return view(mass.data(), mass.size(), 0, sizeof(double), self,
                                           false);
                             })
      .def_property_readonly("components",
                             [](py::object self) {
                               py::dict out;
                               for (const Component& c : self.cast<const Model&>().components)
                                 out[py::str(c.name)] = component_dict(c, self);
                               return out;
                             })
      .def_property_readonly("obstacles",
                             [](const Model& model) {
                               std::vector<std::string> names;
                               for (const auto& o : model.obstacles) names.push_back(o.name);
                               return names;
                             })
      .def_property_readonly("duration", [](const Model& model) { return model.settings.duration; })
      .def_property_readonly("static", [](const Model& model) {
        return model.settings.mode == SolveMode::static_equilibrium;
      });
}

void bind_data_class(py::module_& m) {
  py::class_<PyData, std::shared_ptr<PyData>> c(
      m, "Data", "Everything a run changes, made for one Model (phymul.Data(model)).");
  bind_controls(c);
  c.def(py::init([](std::shared_ptr<Model> model) {
          auto d = std::make_shared<PyData>();
          d->model = model;
          {
            py::gil_scoped_release release;
            d->data = make_data(*model);
          }
          return d;
        }),
        py::arg("model"))
      .def_property_readonly("model", [](const PyData& d) { return d.model; })
      .def_property_readonly(
          "positions",
          [](py::object self) { return vec3_view(self.cast<PyData&>().data.x, self, true); },
          "(n, 3) m, a writable view of the node positions")
      .def_property_readonly(
          "velocities",
          [](py::object self) { return vec3_view(self.cast<PyData&>().data.v, self, true); },
          "(n, 3) m/s, a writable view of the node velocities")
      .def_property_readonly(
          "forces",
          [](py::object self) { return vec3_view(self.cast<PyData&>().data.f, self, false); },
          "(n, 3) N, every force but damping at the last evaluation")
      .def_property_readonly(
          "obstacle_forces",
          [](py::object self) {
            return vec3_view(self.cast<PyData&>().data.contact_force, self, false);
          },
          "(obstacles, 3) N, each obstacle's force on the body last step")
      .def_property_readonly("time", [](const PyData& d) { return d.data.time; })
      .def_property_readonly("steps", [](const PyData& d) { return d.data.step; })
      .def_property_readonly("stable_dt", [](const PyData& d) { return d.data.stable_dt; })
      .def_property(
          "dt", [](const PyData& d) { return d.data.dt; },
          [](PyData& d, double dt) {
            if (!(dt > 0.0) || !std::isfinite(dt))
              throw py::value_error("dt must be a positive finite time in s (got " +
                                    std::to_string(dt) + ")");
            Busy busy(d);
            d.data.dt = dt;
          },
          "s, the explicit step")
      .def_property(
          "controller", [](const PyData& d) { return d.controller ? d.controller : py::none(); },
          [](PyData& d, py::object f) {
            if (!f.is_none() && !PyCallable_Check(f.ptr()))
              throw py::type_error("controller must be callable as f(model, data), or None");
            d.controller = std::move(f);
          },
          "Called as f(model, data) before each step of phymul.step; None: no controller")
      .def("copy", [](const PyData& d) {
        auto c = std::make_shared<PyData>();
        c->model = d.model;
        c->data = d.data;
        return c;
      });
}

}  // namespace

void bind_model(py::module_& m) {
  bind_model_class(m);
  bind_data_class(m);
  m.def(
      "compile",
      [](const Scene& scene) {
        const Scene copy = scene;
        py::gil_scoped_release release;
        return std::const_pointer_cast<Model>(compile(copy));
      },
      py::arg("scene"), "Compiles a scene (after reading its mesh files and calibrating).");
  m.def(
      "step",
      [](const Model& model, PyData& data, long n) { step_n(model_of(data, model), data, n); },
      py::arg("model"), py::arg("data"), py::arg("n") = 1,
      "n explicit steps of data.dt (the GIL released while stepping).");
  m.def(
      "forward",
      [](const Model& model, PyData& data) {
        Busy busy(data);
        py::gil_scoped_release release;
        compute_forces(model_of(data, model), data.data, data.data.load_time);
      },
      py::arg("model"), py::arg("data"),
      "Evaluates the forces at the current positions (after writing data.positions).");
  m.def(
      "solve_static",
      [](const Model& model, PyData& data) {
        Busy busy(data);
        StaticResult r;
        {
          py::gil_scoped_release release;
          r = solve_static(model_of(data, model), data.data);
        }
        return static_result(r);
      },
      py::arg("model"), py::arg("data"),
      "Static equilibrium in the settings' load steps: {converged, iterations, residual}.");
  m.def(
      "kinetic_energy",
      [](const Model& model, const PyData& data) {
        return kinetic_energy(model_of(data, model), data.data);
      },
      py::arg("model"), py::arg("data"));
  m.def(
      "component_volumes",
      [](const Model& model, const PyData& data) {
        return component_volumes(model_of(data, model), data.data);
      },
      py::arg("model"), py::arg("data"),
      "m^3 per component with a closed surface (NaN otherwise).");
}

}  // namespace phymul::python
