#include "phymul/results.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "io/needle_output.hpp"
#include "io/obstacle_surface.hpp"

namespace phymul {
namespace {

std::string json_number(double v) { return std::isfinite(v) ? fmt::format("{}", v) : "null"; }

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\')
      out += '\\', out += c;
    else if (c == '\n')
      out += "\\n";
    else if (static_cast<unsigned char>(c) < 0x20)
      out += fmt::format("\\u{:04x}", int(c));
    else
      out += c;
  }
  return out + "\"";
}

// The needles' frames go beside the body's, at the same times (needle_output.hpp).
std::string needle_frame_name(const std::string& stem, size_t frame) {
  return fmt::format("{}_needles_{:06d}.vtu", stem, frame);
}

}  // namespace

ResultWriter::ResultWriter(std::filesystem::path dir, std::string stem, const Model& model,
                           bool vtk, VtuEncoding encoding)
    : dir_(std::move(dir)),
      stem_(std::move(stem)),
      vtk_(vtk),
      encoding_(encoding),
      has_obstacles_(!model.obstacles.empty()),
      has_needles_(!model.needles.empty()) {
  for (int c = 0; c < int(model.components.size()); ++c)
    if (!model.components[c].boundary.empty()) closed_components_.push_back(c);
  const auto path = dir_ / "monitors.csv.tmp";
  monitors_.open(path);
  if (!monitors_) throw std::runtime_error(fmt::format("cannot write {}", path.string()));
  std::string header = "time_s,kinetic_energy_J,shape_memory_energy_J,max_residual_force_N";
  for (int c : closed_components_) header += ",volume_" + model.components[c].name + "_m3";
  for (const RigidBody& b : model.rigid_bodies)  // how far each rigid body has moved
    header += ",displacement_" + model.components[b.component].name + "_m";
  // The force each obstacle exerts on the body, averaged over the last step (Data).
  for (size_t k = 0; k < model.obstacles.size(); ++k) {
    const std::string& name = model.obstacles[k].name;
    const std::string label = name.empty() ? fmt::format("obstacle{}", k) : name;
    for (const char* axis : {"x", "y", "z"}) header += ",contact_" + label + '_' + axis + "_N";
  }
  // The force the second object of each contact pair exerts on the first.
  for (const ContactPair& pair : model.contact_pairs) {
    const std::string label = model.components[size_t(pair.components[0])].name + "_" +
                              model.components[size_t(pair.components[1])].name;
    for (const char* axis : {"x", "y", "z"}) header += ",contact_" + label + '_' + axis + "_N";
  }
  header += needle_monitor_header(model);
  write_monitors(header + '\n');
  const size_t n = model.rest_position.size() * 3;
  displacement_.resize(n);
  velocity_.resize(n);
  force_.resize(n);
}

void ResultWriter::frame(const Model& m, const Data& s) {
  if (!vtk_) return;
  for (int i = 0; i < m.node_count(); ++i)
    for (int a = 0; a < 3; ++a) {
      displacement_[3 * i + a] = s.x[i][a] - m.rest_position[i][a];
      velocity_[3 * i + a] = s.v[i][a];
      force_[3 * i + a] = s.f[i][a];
    }
  const PointField points[] = {
      {"displacement", 3, displacement_}, {"velocity", 3, velocity_}, {"force", 3, force_}};
  const CellField cells[] = {{"component", m.cell_component}};
  const std::string name = fmt::format("{}_{:06d}.vtu", stem_, pvd_.size());
  write_vtu(dir_ / name, s.x, m.cells, points, cells, encoding_);
  write_obstacles(m, s, int(pvd_.size()));
  if (has_needles_) write_needle_frame(dir_ / needle_frame_name(stem_, pvd_.size()), m, s);
  pvd_.push_back({s.time, name});
  series_stale_ = true;
  const auto now = std::chrono::steady_clock::now();
  const bool never = series_written_ == std::chrono::steady_clock::time_point{};
  if (never || now - series_written_ >= kSeriesInterval) {
    write_series();
    series_written_ = now;
  }
}

void ResultWriter::write_series() {
  write_pvd(dir_ / (stem_ + ".pvd"), pvd_);
  write_obstacle_pvd();
  if (has_needles_) {
    std::vector<PvdEntry> entries;
    for (size_t k = 0; k < pvd_.size(); ++k)
      entries.push_back({pvd_[k].time, needle_frame_name(stem_, k)});
    write_pvd(dir_ / (stem_ + "_needles.pvd"), entries);
  }
  series_stale_ = false;
}

// A run that ends by an exception still leaves its series listing every frame written.
ResultWriter::~ResultWriter() {
  if (!series_stale_) return;
  try {
    write_series();
  } catch (const std::exception&) {  // a second failure must not end the program
  }
}

namespace {

std::string obstacle_frame_name(const std::string& stem, size_t frame) {
  return fmt::format("{}_obstacles_{:06d}.vtu", stem, frame);
}

}  // namespace

void ResultWriter::write_obstacles(const Model& m, const Data& s, int frame) {
  if (!has_obstacles_) return;
  write_obstacle_surfaces(dir_ / obstacle_frame_name(stem_, size_t(frame)), m.obstacles,
                          s.controls.obstacle_motion, s.load_time, s.x, encoding_);
}

// The obstacles' frames are named after the body's, at the same times, so their list
// follows from the body's (and from a checkpoint's).
void ResultWriter::write_obstacle_pvd() {
  if (!has_obstacles_) return;
  std::vector<PvdEntry> entries;
  for (size_t k = 0; k < pvd_.size(); ++k)
    entries.push_back({pvd_[k].time, obstacle_frame_name(stem_, k)});
  write_pvd(dir_ / (stem_ + "_obstacles.pvd"), entries);
}

void ResultWriter::monitor(const Model& m, Data& s) {
  const std::vector<double> volumes = component_volumes(m, s);
  std::string row = fmt::format("{},{},{},{}", s.time, kinetic_energy(m, s), s.shape_memory_energy,
                                max_residual_force(m, s));
  for (int c : closed_components_) row += fmt::format(",{}", volumes[c]);
  for (size_t b = 0; b < m.rigid_bodies.size(); ++b)
    row += fmt::format(",{}", (s.bodies[b].center - m.rigid_bodies[b].rest_center).norm());
  for (const Vec3& f : s.contact_force) row += fmt::format(",{},{},{}", f.x(), f.y(), f.z());
  for (const Vec3& f : s.pair_contact_force) row += fmt::format(",{},{},{}", f.x(), f.y(), f.z());
  row += needle_monitor_row(m, s);
  write_monitors(row + '\n');
  monitored_time_ = s.time;
}

void ResultWriter::write_monitors(const std::string& text) {
  monitors_ << text;
  monitors_text_ += text;
}

void ResultWriter::restore(std::vector<PvdEntry> frames, const std::string& monitors_text) {
  auto require = [&](const std::string& file) {
    if (!std::filesystem::is_regular_file(dir_ / file))
      throw std::runtime_error(fmt::format(
          "cannot resume in {}: frame {} of the checkpoint is missing", dir_.string(), file));
  };
  for (size_t k = 0; k < frames.size() && vtk_; ++k) {
    require(frames[k].file);
    if (has_obstacles_) require(obstacle_frame_name(stem_, k));
    if (has_needles_) require(needle_frame_name(stem_, k));
  }
  pvd_ = std::move(frames);
  const auto path = dir_ / "monitors.csv.tmp";
  monitors_.close();
  monitors_.open(path, std::ios::trunc);
  if (!monitors_) throw std::runtime_error(fmt::format("cannot write {}", path.string()));
  monitors_text_.clear();
  write_monitors(monitors_text);
}

void ResultWriter::finish(const RunReport& report) {
  if (series_stale_) write_series();
  monitors_.close();
  if (!monitors_) throw std::runtime_error("cannot finish monitors.csv in " + dir_.string());
  std::filesystem::rename(dir_ / "monitors.csv.tmp", dir_ / "monitors.csv");
  write_file_atomically(dir_ / "report.json", [&](std::ostream& o) { o << report_json(report); });
}

namespace {

std::string json_vector(const Eigen::Vector3d& v) {
  return fmt::format("[{}, {}, {}]", json_number(v.x()), json_number(v.y()), json_number(v.z()));
}

// The fields only a Newton run has (RunReport::newton).
std::string newton_fields(const RunReport& r) {
  if (!r.newton) return "";
  return fmt::format(
      ",\n  \"solver\": \"newton\",\n  \"newton_iterations\": {},\n  \"load_steps\": {},\n"
      "  \"load_steps_done\": {},\n  \"support_reaction_N\": {},\n  \"applied_load_N\": {}",
      r.steps, r.load_steps, r.load_steps_done, json_vector(r.support_reaction),
      json_vector(r.applied_load));
}

// What each shape-memory object given `young` made of it (RunReport::stiffness_calibrations).
std::string calibration_fields(const RunReport& r) {
  if (r.stiffness_calibrations.empty()) return "";
  std::string s = ",\n  \"stiffness_from_young\": [";
  for (size_t k = 0; k < r.stiffness_calibrations.size(); ++k) {
    const StiffnessCalibration& c = r.stiffness_calibrations[k];
    s += fmt::format(
        "{}\n    {{\"object\": {}, \"young_Pa\": {}, \"poisson\": {}, \"axis\": \"{}\", "
        "\"strain\": {}, \"held_nodes\": {}, \"pushed_nodes\": {}, \"fem_force_N\": {}, "
        "\"stiffness_N_per_m\": {}, \"alpha\": {}, \"displacement_rms\": {}, "
        "\"displacement_max\": {}}}",
        k ? "," : "", json_string(c.component), json_number(c.young), json_number(c.poisson),
        "xyz"[c.axis], json_number(c.strain), c.held, c.pushed, json_number(c.fem_force),
        json_number(c.stiffness), json_number(c.alpha), json_number(c.displacement_rms),
        json_number(c.displacement_max));
  }
  return s + "\n  ]";
}

// Each needle's punctures (RunReport::punctures), in scenes with needles.
std::string puncture_fields(const RunReport& r) {
  if (!r.needles) return "";
  std::string s = ",\n  \"needle_punctures\": [";
  for (size_t k = 0; k < r.punctures.size(); ++k) {
    const NeedlePuncture& p = r.punctures[k];
    s += fmt::format(
        "{}\n    {{\"needle\": {}, \"object\": {}, \"time_s\": {}, \"depth_m\": {}, "
        "\"force_N\": {}}}",
        k ? "," : "", json_string(p.needle), json_string(p.object), json_number(p.time),
        json_number(p.depth), json_number(p.force));
  }
  return s + (r.punctures.empty() ? "]" : "\n  ]");
}

}  // namespace

std::string report_json(const RunReport& r) {
  return fmt::format(
      "{{\n  \"status\": {},\n  \"message\": {},\n  \"mode\": {},\n  \"steps\": {},\n  "
      "\"simulated_time_s\": {},\n"
      "  \"wall_time_s\": {},\n  \"ns_per_node_per_step\": {},\n  \"real_time_factor\": {},\n  "
      "\"step_wall_time_s\": {},\n  \"stepping_real_time_factor\": {},\n  \"dt_s\": {},\n"
      "  \"stable_dt_s\": {},\n  \"nodes\": {},\n  \"threads\": {},\n  \"frames\": {},\n"
      "  \"converged\": {},\n"
      "  \"final_residual_force_N\": {}{}{}{}\n}}\n",
      json_string(r.status), json_string(r.message), json_string(r.mode), r.steps,
      json_number(r.simulated_time), json_number(r.wall_time), json_number(r.ns_per_node_per_step),
      json_number(r.real_time_factor), json_number(r.step_wall_time),
      json_number(r.stepping_real_time_factor), json_number(r.dt), json_number(r.stable_dt),
      r.nodes, r.threads, r.frames, r.converged ? "true" : "false", json_number(r.residual),
      newton_fields(r), calibration_fields(r), puncture_fields(r));
}

}  // namespace phymul
