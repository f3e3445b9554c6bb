#include "live_simulation.hpp"

#include <pthread.h>

#include <algorithm>
#include <cstring>

#include "phymul/mesh.hpp"
#include "phymul/simulation.hpp"

namespace phymul::serve {
namespace {

using Clock = std::chrono::steady_clock;
constexpr auto kPublishInterval = std::chrono::microseconds(16667);  // 60 frames a second
constexpr double kRateWindow = 0.5;  // s of wall-clock time per real-time factor
constexpr double kMostBehind = 0.1;  // s: a run further behind real time stops catching up
constexpr size_t kMostPendingControls = 256;
// The drag spring is this share of the node's elastic row sum: it moves the node visibly yet
// raises the highest frequency by under 5 %, inside the margin `dt: auto` keeps.
constexpr double kDragShare = 0.1;
constexpr double kObstacleSpeed = 0.05;  // m/s: how fast a moved obstacle travels
constexpr double kLoadRamp = 0.1;        // s over which a new pressure is reached
constexpr double kVolumeRate = 2.0;      // 1/s: a target volume changes by at most 200 % a second

double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

}  // namespace

LiveSimulation::LiveSimulation(Model model, bool paused, Pace pace)
    : model_(std::move(model)), paused_(paused), pace_(pace) {
  if (!finalized(model_)) finalize(model_);
  data_ = make_data(model_);
  data_.controls.applied_force.assign(size_t(model_.node_count()), Vec3::Zero());
  initial_ = data_;
  dt_ = data_.dt;
  user_force_.assign(size_t(model_.node_count()), Vec3::Zero());
  drag_stiffness_ = stiffness_row_sums(model_);
  for (double& k : drag_stiffness_) k *= kDragShare;
  for (size_t k = 0; k < model_.obstacles.size(); ++k) {
    const std::string& n = model_.obstacles[k].name;
    monitor_names_.push_back((n.empty() ? "obstacle" + std::to_string(k) : n) + " force (N)");
  }
  for (const PressureLoad& p : model_.pressures)
    monitor_names_.push_back(model_.components[size_t(p.component)].name + " pressure (kPa)");
  for (const VolumeConstraint& v : model_.volumes)
    monitor_names_.push_back(v.component + " volume (mL)");
  monitor_names_.push_back("kinetic energy (mJ)");
  working_.reserve(kMostPendingControls);
  pending_.reserve(kMostPendingControls);
  back_ = make_snapshot();
  middle_ = make_snapshot();
  publish();
}

LiveSimulation::~LiveSimulation() { stop(); }

Snapshot LiveSimulation::make_snapshot() const {
  Snapshot s;
  const size_t n = size_t(model_.node_count());
  s.positions.assign(3 * n, 0.0f);
  s.displacement.assign(n, 0.0f);
  s.obstacle_translation.assign(3 * model_.obstacles.size(), 0.0f);
  s.pressure.assign(model_.pressures.size(), 0.0);
  s.target_volume.assign(model_.volumes.size(), 0.0);
  s.monitors.assign(monitor_names_.size(), 0.0);
  return s;
}

void LiveSimulation::start() {
  thread_ = std::thread([this] { loop(); });
}

void LiveSimulation::stop() {
  stop_ = true;
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

bool LiveSimulation::submit(const Control& control) {
  {
    std::lock_guard lock(controls_mutex_);
    if (pending_.size() >= kMostPendingControls) return false;
    pending_.push_back(control);
  }
  wake_.notify_all();
  return true;
}

bool LiveSimulation::latest(Snapshot& into) {
  std::lock_guard lock(snapshot_mutex_);
  if (middle_.sequence <= into.sequence) return false;
  into = middle_;  // equal sizes: copies, allocates nothing
  return true;
}

void LiveSimulation::anchor() {
  anchor_wall_ = rate_wall_ = Clock::now();
  anchor_time_ = rate_time_ = data_.time;
}

void LiveSimulation::loop() {
  pthread_setname_np(pthread_self(), "phymul-sim");  // for top, and the load test's CPU time
  anchor();
  while (!stop_) {
    take_controls();
    const bool running = error_.empty() && (!paused_ || pending_steps_ > 0);
    if (!running) {
      real_time_factor_ = 0.0;
      std::unique_lock lock(controls_mutex_);
      wake_.wait_for(lock, std::chrono::milliseconds(50),
                     [this] { return stop_ || !pending_.empty(); });
      anchor();
      continue;
    }
    if (pending_steps_ > 0) {  // single steps while paused
      if (!advance() || --pending_steps_ == 0) publish();
      continue;
    }
    const Clock::time_point now = Clock::now();
    if (pace_ == Pace::realtime) {
      const double due = anchor_time_ + seconds(now - anchor_wall_);
      if (due - data_.time > kMostBehind) anchor();  // too slow: run on from here
      if (data_.time + dt_ > due) {                  // ahead of the clock: wait, or for a control
        if (watched_ && now - last_publish_ >= kPublishInterval) publish();
        const auto wait = std::chrono::duration<double>(data_.time + dt_ - due);
        std::unique_lock lock(controls_mutex_);
        wake_.wait_for(lock, std::min<std::chrono::duration<double>>(wait, kPublishInterval),
                       [this] { return stop_ || !pending_.empty(); });
        continue;
      }
    }
    advance();
    if (watched_ && now - last_publish_ >= kPublishInterval) publish();
  }
}

// The controls that came since the last look, applied in order between two steps.
void LiveSimulation::take_controls() {
  {
    std::lock_guard lock(controls_mutex_);
    working_.swap(pending_);  // both keep their capacity: no allocation
  }
  for (const Control& c : working_) apply(c);
  if (!working_.empty()) publish();
  working_.clear();
}

void LiveSimulation::ramp(Schedule& s, const Vec3& value, double duration) const {
  const Vec3 now = s.empty() ? value : Vec3(s.at(data_.time));
  s.times.resize(2);  // capacity kept from the first time: allocation only then
  s.values.resize(2);
  s.times[0] = data_.time;
  s.times[1] = data_.time + std::max(duration, dt_);
  s.values[0] = now;
  s.values[1] = value;
}

void LiveSimulation::apply(const Control& c) {
  using Op = Control::Op;
  Controls& controls = data_.controls;
  switch (c.op) {
    case Op::play:
      paused_ = false;
      error_.clear();
      anchor();
      break;
    case Op::pause:
      paused_ = true;
      pending_steps_ = 0;
      break;
    case Op::step:
      paused_ = true;
      error_.clear();
      pending_steps_ += c.count;
      break;
    case Op::reset:
      data_ = initial_;
      drag_node_ = -1;
      std::fill(user_force_.begin(), user_force_.end(), Vec3::Zero());
      error_.clear();
      pending_steps_ = 0;
      anchor();
      break;
    case Op::pace:
      pace_ = c.pace;
      anchor();
      break;
    case Op::drag:
      if (drag_node_ >= 0)
        controls.applied_force[size_t(drag_node_)] = user_force_[size_t(drag_node_)];
      drag_node_ = c.index;
      drag_target_ = c.vector;
      drag_k_ =
          c.value > 0.0 ? std::min(c.value, drag_stiffness(c.index)) : drag_stiffness(c.index);
      break;
    case Op::release:
      if (drag_node_ >= 0)
        controls.applied_force[size_t(drag_node_)] = user_force_[size_t(drag_node_)];
      drag_node_ = -1;
      break;
    case Op::move_obstacle: {
      Schedule& s = controls.obstacle_motion[size_t(c.index)];
      const double distance = (c.vector - s.at(data_.time)).norm();
      ramp(s, c.vector, distance / kObstacleSpeed);
      break;
    }
    case Op::set_pressure:
      ramp(controls.pressure[size_t(c.index)], Vec3(c.value, 0, 0), kLoadRamp);
      break;
    case Op::set_target_volume: {
      Schedule& s = controls.target_volume[size_t(c.index)];
      const double now = target_volume(model_, controls, size_t(c.index), data_.time);
      if (s.empty()) s = Schedule::constant(Vec3(now, 0, 0));
      ramp(s, Vec3(c.value, 0, 0), std::abs(c.value - now) / (kVolumeRate * now));
      break;
    }
    case Op::set_force:
      user_force_[size_t(c.index)] = c.vector;
      controls.applied_force[size_t(c.index)] = c.vector;
      break;
  }
}

bool LiveSimulation::advance() {
  if (drag_node_ >= 0) {  // the spring from the node to the pointer, at this step's start
    const size_t n = size_t(drag_node_);
    data_.controls.applied_force[n] = user_force_[n] + drag_k_ * (drag_target_ - data_.x[n]);
  }
  try {
    step(model_, data_);
  } catch (const std::exception& e) {  // unstable: data_ is as before the step
    error_ = e.what();
    paused_ = true;
    pending_steps_ = 0;
    publish();
    return false;
  }
  const Clock::time_point now = Clock::now();
  if (const double wall = seconds(now - rate_wall_); wall >= kRateWindow) {
    real_time_factor_ = (data_.time - rate_time_) / wall;
    rate_wall_ = now;
    rate_time_ = data_.time;
  }
  return true;
}

void LiveSimulation::fill(Snapshot& s) const {
  s.time = data_.time;
  s.steps = data_.step;
  s.paused = paused_ || !error_.empty();
  s.pace = pace_;
  s.real_time_factor = s.paused ? 0.0 : real_time_factor_;
  s.drag_node = drag_node_;
  for (size_t i = 0; i < data_.x.size(); ++i) {
    for (int a = 0; a < 3; ++a) s.positions[3 * i + size_t(a)] = float(data_.x[i][a]);
    s.displacement[i] = float((data_.x[i] - model_.rest_position[i]).norm());
  }
  const Controls& controls = data_.controls;
  size_t m = 0;
  for (size_t k = 0; k < model_.obstacles.size(); ++k) {
    const Vec3 t = controls.obstacle_motion[k].at(data_.time);
    for (int a = 0; a < 3; ++a) s.obstacle_translation[3 * k + size_t(a)] = float(t[a]);
    s.monitors[m++] = k < data_.contact_force.size() ? data_.contact_force[k].norm() : 0.0;
  }
  for (size_t k = 0; k < model_.pressures.size(); ++k) {
    s.pressure[k] = controls.pressure[k].at(data_.time).x();
    s.monitors[m++] = s.pressure[k] * 1e-3;
  }
  for (size_t k = 0; k < model_.volumes.size(); ++k) {
    s.target_volume[k] = target_volume(model_, controls, k, data_.time);
    s.monitors[m++] = enclosed_volume(data_.x, model_.volumes[k].triangles) * 1e6;
  }
  s.monitors[m] = kinetic_energy(model_, data_) * 1e3;
  const size_t n = std::min(error_.size(), s.error.size() - 1);
  std::memcpy(s.error.data(), error_.data(), n);
  s.error[n] = '\0';
}

void LiveSimulation::publish() {
  last_publish_ = Clock::now();
  fill(back_);
  std::lock_guard lock(snapshot_mutex_);
  back_.sequence = middle_.sequence + 1;
  std::swap(back_, middle_);  // swaps the arrays' buffers: no copy, no allocation
}

}  // namespace phymul::serve
