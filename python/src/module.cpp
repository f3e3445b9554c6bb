// phymul's Python module: scenes, compiled models, Data with NumPy views of its arrays,
// stepping with the GIL released, runs and studies (docs/python.md).
#include "bindings.hpp"
#include "phymul/checkpoint.hpp"
#include "phymul/mesh_io.hpp"
#include "phymul/scene.hpp"
#include "phymul/simulation.hpp"

PYBIND11_MODULE(_phymul, m) {
  namespace py = pybind11;
  m.doc() = "phymul: soft organs simulated with the Phymul local shape memory model";
  // SceneError carries the checker's "file:line:column: message" lines (see __init__.py).
  static py::exception<phymul::SceneError> scene_error(m, "SceneError", PyExc_ValueError);
  static py::exception<phymul::InstabilityError> instability(m, "InstabilityError",
                                                             PyExc_RuntimeError);
  static py::exception<phymul::CheckpointError> checkpoint_error(m, "CheckpointError",
                                                                 PyExc_RuntimeError);
  static py::exception<phymul::MeshFileError> mesh_error(m, "MeshFileError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const phymul::SceneError& e) {
      py::list lines;
      for (const auto& d : e.diagnostics()) lines.append(d.str());
      py::object error = py::handle(scene_error.ptr())(py::str(e.what()));
      error.attr("diagnostics") = lines;
      PyErr_SetObject(scene_error.ptr(), error.ptr());
    } catch (const phymul::InstabilityError& e) {
      py::object error = py::handle(instability.ptr())(py::str(e.what()));
      error.attr("node") = e.node;
      error.attr("time") = e.time;
      PyErr_SetObject(instability.ptr(), error.ptr());
    } catch (const phymul::CheckpointError& e) {
      checkpoint_error(e.what());
    } catch (const phymul::MeshFileError& e) {
      mesh_error(e.what());
    }
  });
  phymul::python::bind_scene(m);
  phymul::python::bind_model(m);
  phymul::python::bind_run(m);
}
