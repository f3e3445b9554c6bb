// Runs, result files and studies in Python: the program's own run loop and writer, and the
// studies' tables as JSON (turned into dicts by __init__.py).
#include <pybind11/stl.h>

#include <filesystem>
#include <memory>
#include <string>

#include "bindings.hpp"
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
  Scene scene = edited;
  for (ObjectSpec& o : scene.objects)
    if (o.material.young == 0.0) o.calibration.reset();
  RunOptions options;
  options.output_dir = out;
  options.progress = progress;
  options.resume = resume;
  if (!checkpoint_every.empty())
    options.checkpoint_every = parse_checkpoint_interval(checkpoint_every);
  RunReport report;
  {
    py::gil_scoped_release release;
    prepare_scene(scene);
    report = run_scene(scene, options);
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

}  // namespace

void bind_run(py::module_& m) {
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
