// Runs, result files and studies in Python: the program's own run loop and writer, and the
// studies' tables as JSON (turned into dicts by __init__.py).
#include <pybind11/stl.h>

#include <filesystem>
#include <memory>
#include <string>

#include "bindings.hpp"
#include "phymul/mesh_io.hpp"
#include "phymul/results.hpp"
#include "phymul/run.hpp"
#include "phymul/scene_io.hpp"
#include "phymul/studies/prostate.hpp"
#include "phymul/studies/truthcube.hpp"

namespace phymul::python {
namespace {

// A run's files as `phymul run` writes them; the report comes back as report.json's text.
std::string run(const Scene& edited, const std::string& out, bool progress,
                const std::string& checkpoint_every, bool resume) {
  RunOptions options;
  options.output_dir = out;
  options.progress = progress;
  options.resume = resume;
  if (!checkpoint_every.empty())
    options.checkpoint_every = parse_checkpoint_interval(checkpoint_every);
  RunReport report;
  {
    py::gil_scoped_release release;
    report = run_scene(prepared_copy(edited), options);
  }
  return report_json(report);
}

// ResultWriter with the program's file layout, for frames written from a Python loop.
class Writer {
 public:
  Writer(std::shared_ptr<const Model> model, const std::string& dir, const std::string& stem,
         bool binary)
      : model_(std::move(model)),
        writer_(dir, stem, *model_, true, binary ? VtuEncoding::binary : VtuEncoding::ascii) {}
  void frame(PyData& d) {
    check(d);
    writer_.frame(*model_, d.data);
  }
  void monitor(PyData& d) {
    check(d);
    Busy busy(d);
    writer_.monitor(*model_, d.data);
  }
  void finish(const PyData& d) {
    check(d);
    RunReport report;
    report.steps = d.data.step;
    report.simulated_time = d.data.time;
    report.dt = d.data.dt;
    report.stable_dt = d.data.stable_dt;
    report.nodes = int(d.data.x.size());
    report.frames = writer_.frames();
    writer_.finish(report);
  }

 private:
  void check(const PyData& d) const {
    if (d.model != model_) throw py::value_error("this Data belongs to another Model");
  }
  std::shared_ptr<const Model> model_;
  ResultWriter writer_;
};

std::string truthcube_json(int cells, bool fem, bool volume_constraint, double young,
                           double poisson, const std::string& beads_csv) {
  truthcube::StudyOptions options;
  options.cells = cells;
  options.fem = fem;
  options.volume_constraint = volume_constraint;
  options.young = young;
  options.poisson = poisson;
  py::gil_scoped_release release;
  const auto beads = truthcube::load_beads(beads_csv);
  return truthcube::json(truthcube::run_study(beads, options), options);
}

std::string prostate_json(const std::vector<double>& fillings,
                          const std::vector<std::string>& probes, double prostate_stiffness,
                          bool coarse, const std::string& out) {
  prostate::Options options;
  options.fillings = fillings;
  options.probes.clear();
  for (const std::string& p : probes) {
    if (p == "pressure")
      options.probes.push_back(prostate::Probe::pressure);
    else if (p == "rigid")
      options.probes.push_back(prostate::Probe::rigid);
    else
      throw py::value_error("probe must be 'pressure' or 'rigid' (got '" + p + "')");
  }
  for (double f : fillings)
    if (!(f > 0.0) || !std::isfinite(f))
      throw py::value_error("fillings are volumes in m^3, each > 0");
  if (!(prostate_stiffness > 0.0) || !std::isfinite(prostate_stiffness))
    throw py::value_error("prostate_stiffness must be > 0 N/m");
  options.prostate_stiffness = prostate_stiffness;
  if (coarse) options = prostate::coarse_bladder(options);
  py::gil_scoped_release release;
  return prostate::json(prostate::run_study(options, out));
}

// A mesh file as arrays: points (m), each cell type's node lists, and what reading repaired.
py::dict read_mesh(const std::string& path, double divisor) {
  if (!(divisor > 0.0) || !std::isfinite(divisor))
    throw py::value_error("divisor must be > 0 (1000 for a file in millimetres)");
  std::vector<std::string> notes;
  const Mesh mesh = read_mesh_file(path, divisor, &notes);
  py::array_t<double> points({py::ssize_t(mesh.points.size()), py::ssize_t(3)});
  auto p = points.mutable_unchecked<2>();
  for (size_t i = 0; i < mesh.points.size(); ++i)
    for (int a = 0; a < 3; ++a) p(py::ssize_t(i), a) = mesh.points[i][a];
  std::map<std::string, std::vector<int>> flat;
  for (const Cell& c : mesh.cells)
    for (int i : c.node_span()) flat[cell_type_name(c.type)].push_back(i);
  py::dict cells;
  for (const Cell& c : mesh.cells) {
    const std::string type = cell_type_name(c.type);
    if (cells.contains(type)) continue;
    const std::vector<int>& nodes = flat[type];
    const py::ssize_t n = node_count(c.type);
    py::array_t<int> a({py::ssize_t(nodes.size()) / n, n});
    std::copy(nodes.begin(), nodes.end(), a.mutable_data());
    cells[py::str(type)] = a;
  }
  py::dict out;
  out["points"] = points;
  out["cells"] = cells;
  out["notes"] = notes;
  return out;
}

}  // namespace

void bind_run(py::module_& m) {
  m.def("read_mesh", &read_mesh, py::arg("path"), py::arg("divisor") = 1.0,
        "A mesh file (.vtk, .vtu, .msh, .stl, .obj, .ply, .vtp) as {points, cells: {type: nodes}, "
        "notes}; "
        "coordinates divided by `divisor` (1000 for millimetres).");
  m.def("_run", &run, py::arg("scene"), py::arg("out"), py::arg("progress") = false,
        py::arg("checkpoint_every") = "", py::arg("resume") = false);
  py::class_<Writer>(m, "ResultWriter",
                     "Frames (.vtu + .pvd), monitors.csv and report.json, as `phymul run` "
                     "writes them.")
      .def(py::init<std::shared_ptr<Model>, const std::string&, const std::string&, bool>(),
           py::arg("model"), py::arg("dir"), py::arg("stem") = "frames", py::arg("binary") = false)
      .def("frame", &Writer::frame, py::arg("data"), "Writes the data's positions as a frame.")
      .def("monitor", &Writer::monitor, py::arg("data"), "Appends a row to monitors.csv.")
      .def("finish", &Writer::finish, py::arg("data"),
           "Completes the .pvd and writes report.json.");
  m.def("_truthcube", &truthcube_json, py::arg("cells"), py::arg("fem"),
        py::arg("volume_constraint"), py::arg("young"), py::arg("poisson"), py::arg("beads"));
  m.def("_prostate", &prostate_json, py::arg("fillings"), py::arg("probes"),
        py::arg("prostate_stiffness"), py::arg("coarse"), py::arg("out"));
}

}  // namespace phymul::python
