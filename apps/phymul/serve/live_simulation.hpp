// The simulation behind `phymul serve`: one thread steps a Data in real time, as fast as it
// can, or not at all, takes the controls the clients send between two steps, and publishes
// what they draw (positions, the colour scalar, monitors) into preallocated snapshots. A
// client reads the latest snapshot whenever it likes: nothing it does waits on a step.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "phymul/data.hpp"
#include "phymul/model.hpp"

namespace phymul::serve {

enum class Pace { realtime, fast };

// What a client asks of the simulation; checked by the protocol before it gets here.
struct Control {
  enum class Op {
    play,
    pause,
    step,
    reset,
    pace,
    drag,
    release,
    move_obstacle,
    set_pressure,
    set_target_volume,
    set_force
  };
  Op op = Op::play;
  int index = -1;  // node (drag, set_force), obstacle, pressure load or volume constraint
  int count = 1;   // step: how many
  Vec3 vector = Vec3::Zero();  // drag: target (m); move_obstacle: translation (m); force (N)
  double value = 0.0;          // Pa, m^3, or drag stiffness (N/m)
  Pace pace = Pace::realtime;
};

// One published state of the run. Its arrays are sized once (make_snapshot) and only
// overwritten, so publishing allocates nothing.
struct Snapshot {
  long sequence = 0;  // bumped at each publication
  double time = 0.0;  // s
  long steps = 0;
  bool paused = false;
  Pace pace = Pace::realtime;
  double real_time_factor = 0.0;  // simulated s per wall-clock s, over the last half second
  int drag_node = -1;
  std::vector<float> positions;             // m, 3 per node
  std::vector<float> displacement;          // m, per node: |x - X|, the colour
  std::vector<float> obstacle_translation;  // m, 3 per obstacle
  std::vector<double> pressure;             // Pa, per pressure load
  std::vector<double> target_volume;        // m^3, per volume constraint
  std::vector<double> monitors;             // per LiveSimulation::monitor_names()
  std::array<char, 512> error{};            // why the run stopped ("" while fine)
};

class LiveSimulation {
 public:
  // Takes the model; the Data starts as make_data's (paused or not).
  LiveSimulation(Model model, bool paused, Pace pace);
  ~LiveSimulation();
  LiveSimulation(const LiveSimulation&) = delete;
  LiveSimulation& operator=(const LiveSimulation&) = delete;

  void start();  // the stepping thread
  void stop();   // joins it

  // Whether anyone is watching: the stepping thread publishes frames only then.
  void set_watched(bool watched) { watched_ = watched; }
  // False when too many controls are waiting (the client is told to slow down).
  bool submit(const Control& control);
  // Copies the latest snapshot into `into` when it is newer than into.sequence; true if so.
  bool latest(Snapshot& into);
  Snapshot make_snapshot() const;  // sized for this model

  const Model& model() const { return model_; }
  double dt() const { return dt_; }
  const std::vector<std::string>& monitor_names() const { return monitor_names_; }
  // N/m: the drag spring on a node when the client names none, and the most it may ask for.
  double drag_stiffness(int node) const { return drag_stiffness_[size_t(node)]; }

 private:
  void loop();
  void apply(const Control& c);
  void take_controls();
  bool advance();  // one step; false when it failed (the run pauses, the error published)
  void publish();
  void fill(Snapshot& s) const;
  void anchor();  // real time restarts from here
  void ramp(Schedule& s, const Vec3& value, double duration) const;

  Model model_;
  Data data_, initial_;
  double dt_ = 0.0;
  std::vector<std::string> monitor_names_;
  std::vector<double> drag_stiffness_;
  std::vector<Vec3> user_force_;  // N per node (set_force), added to the drag spring

  // Owned by the stepping thread.
  bool paused_ = false;
  Pace pace_ = Pace::realtime;
  int pending_steps_ = 0;
  int drag_node_ = -1;
  Vec3 drag_target_ = Vec3::Zero();
  double drag_k_ = 0.0;
  std::string error_;
  std::chrono::steady_clock::time_point anchor_wall_, last_publish_, rate_wall_;
  double anchor_time_ = 0.0, rate_time_ = 0.0, real_time_factor_ = 0.0;
  std::vector<Control> working_;

  // Shared with the clients' thread.
  std::mutex controls_mutex_;
  std::condition_variable wake_;
  std::vector<Control> pending_;
  std::mutex snapshot_mutex_;
  Snapshot back_, middle_;  // back_: written by the stepping thread; middle_: the latest
  std::atomic<bool> stop_{false}, watched_{false};
  std::thread thread_;
};

}  // namespace phymul::serve
