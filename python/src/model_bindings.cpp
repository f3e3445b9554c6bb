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
  if (d_.busy.exchange(true))
    throw std::runtime_error(
        "this Data is being stepped in another thread; give each thread "
        "its own Data (phymul.Data(model))");
}
Busy::~Busy() { d_.busy = false; }

namespace {

using ModelPtr = std::shared_ptr<const Model>;

// What compile does to a scene edited in Python before compiling: its mesh files read and
// Young's moduli calibrated (prepare_scene), on a copy so the Python scene is left as it was.
ModelPtr compile(const Scene& edited) {
  Scene scene = edited;
  for (ObjectSpec& o : scene.objects)
    if (o.material.young == 0.0) o.calibration.reset();  // K was set directly
  prepare_scene(scene);
  return std::make_shared<const Model>(compile_scene(scene));
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
  d["kind"] = c.kind == ComponentKind::rigid    ? "rigid"
              : c.kind == ComponentKind::active ? "active"
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
  py::class_<PyData, std::shared_ptr<PyData>>(
      m, "Data", "Everything a run changes, made for one Model (phymul.Data(model)).")
      .def(py::init([](std::shared_ptr<Model> model) {
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
