// The Python module's parts (one file each): scenes, models and data, runs and studies.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <atomic>
#include <memory>
#include <thread>

#include "phymul/data.hpp"
#include "phymul/model.hpp"
#include "phymul/scene.hpp"

namespace phymul::python {

namespace py = pybind11;

// A Data with the Model it was made for (kept alive by it) and a flag that refuses two
// threads stepping it at once, which would race on every array.
struct PyData {
  std::shared_ptr<const Model> model;
  Data data;
  std::atomic<bool> busy{false};
  std::atomic<std::thread::id> owner{};  // the thread holding busy
  py::object controller;  // f(model, data) before each step of phymul.step; null: none
};

// Holds PyData::busy for a call; RuntimeError when another thread holds it. The thread that
// holds it may enter again (a controller, called between steps, sets the controls).
class Busy {
 public:
  explicit Busy(PyData& d);
  ~Busy();
  Busy(const Busy&) = delete;
  Busy& operator=(const Busy&) = delete;

 private:
  PyData& d_;
  bool nested_ = false;
};

// A NumPy view of `count` rows of `columns` T at `data` (row stride: `stride` bytes) whose
// base is `owner`: the array keeps it alive. Read-only unless `writable`.
template <class T>
py::array view(const T* data, size_t count, size_t columns, size_t stride, py::handle owner,
               bool writable) {
  std::vector<py::ssize_t> shape{py::ssize_t(count)}, strides{py::ssize_t(stride)};
  if (columns > 0) {
    shape.push_back(py::ssize_t(columns));
    strides.push_back(py::ssize_t(sizeof(T)));
  }
  py::array a(py::dtype::of<T>(), shape, strides, data, owner);
  if (!writable) a.attr("setflags")(py::arg("write") = false);
  return a;
}

// A copy of a scene edited in Python, made ready to compile: a Young's modulus set to zero
// (stiffness set directly) drops its calibration, then prepare_scene reads the mesh files and
// calibrates what changed.
Scene prepared_copy(const Scene& edited);

void bind_scene(py::module_& m);
void bind_model(py::module_& m);
void bind_run(py::module_& m);

}  // namespace phymul::python
