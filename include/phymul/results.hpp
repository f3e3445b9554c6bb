// The files of a run, as `phymul run` writes them: frames (.vtu and the .pvd listing them,
// which ParaView opens), monitors.csv (a row of energies, residual, volumes, contact forces
// per call), report.json.
#pragma once

#include <chrono>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "phymul/run.hpp"
#include "phymul/simulation.hpp"
#include "phymul/vtk.hpp"

namespace phymul {

class ResultWriter {
 public:
  ResultWriter(std::filesystem::path dir, std::string stem, const Model& model, bool vtk,
               VtuEncoding encoding = VtuEncoding::ascii);
  // One .vtu, listed by the .pvd; with obstacles, their surfaces at that instant too, in
  // <stem>_obstacles_<frame>.vtu listed by <stem>_obstacles.pvd. Each .pvd rewrite creates a
  // file (half a millisecond on the study's machine, more than a binary frame's numbers), so
  // while running they are rewritten for the first frame and then at most every
  // kSeriesInterval of wall-clock time; finish() (or the destructor, on an error) lists all.
  void frame(const Model& model, const Data& data);
  void frame(Simulator& sim) { frame(sim.model(), sim.data()); }
  static constexpr std::chrono::milliseconds kSeriesInterval{500};
  ~ResultWriter();
  // One row of monitors.csv (its residual force uses data's workspace).
  void monitor(const Model& model, Data& data);
  void monitor(Simulator& sim) { monitor(sim.model(), sim.data()); }
  void finish(const RunReport& report);  // monitors.csv complete, report.json
  int frames() const { return int(pvd_.size()); }
  // Checkpoints: what was written so far, and resuming from it (the frames listed must be
  // in the directory; monitors.csv starts over from the recorded text).
  const std::vector<PvdEntry>& frame_list() const { return pvd_; }
  const std::string& monitors_text() const { return monitors_text_; }
  double monitored_time() const { return monitored_time_; }  // s, of the last row; NaN: none
  void restore(std::vector<PvdEntry> frames, const std::string& monitors_text);

 private:
  std::filesystem::path dir_;
  std::string stem_;
  bool vtk_;
  VtuEncoding encoding_;
  bool has_obstacles_;
  bool has_needles_;  // <stem>_needles_<frame>.vtu beside each frame, <stem>_needles.pvd
  std::vector<int> closed_components_;
  std::vector<PvdEntry> pvd_;
  std::ofstream monitors_;
  std::string monitors_text_;  // what monitors_ was given
  double monitored_time_ = std::numeric_limits<double>::quiet_NaN();
  void write_monitors(const std::string& text);
  void write_obstacles(const Model& model, const Data& data, int frame);
  void write_obstacle_pvd();
  void write_series();         // both .pvd
  bool series_stale_ = false;  // frames written since the .pvd last were
  std::chrono::steady_clock::time_point series_written_{};  // {}: not yet by this writer
  std::vector<double> displacement_, velocity_, force_;     // flat xyz buffers for the writer
};

// report.json's text (JSON; non-finite numbers become null).
std::string report_json(const RunReport& report);

}  // namespace phymul
