// What the relaxation/dynamics run and the Newton run share about checkpoints: when the next
// one is due, which one to resume from, writing one, and a real signal for the tests.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "phymul/checkpoint.hpp"
#include "phymul/results.hpp"
#include "phymul/run.hpp"
#include "phymul/simulation.hpp"

namespace phymul {

// Decides when the next checkpoint is due; starts counting from where the run starts.
class CheckpointClock {
 public:
  CheckpointClock(const CheckpointInterval& every, long step, double time)
      : every_(every), last_step_(step), next_time_(time + every.time) {}
  bool due(long step, double time, double dt);

 private:
  CheckpointInterval every_;
  long last_step_;
  double next_time_;
};

// "interrupted; ... (continue with: phymul run --resume DIR)".
std::string interrupted_message(const std::filesystem::path& dir);

// The checkpoint in the output directory when resuming, after checking that the scene file is
// the one it was written from (CheckpointError otherwise).
std::optional<Checkpoint> checkpoint_to_resume(const Scene& scene, const RunOptions& options,
                                               std::uint64_t scene_hash);

// That the checkpoint belongs to this model (its hash, its state's arrays): CheckpointError
// naming what differs otherwise.
void check_checkpoint_model(const Checkpoint& c, const Model& model, const Scene& scene,
                            const RunOptions& options);

// A resumed run's simulator and writer as the checkpoint left them, or a new run's first
// frame and monitors row.
void start_or_restore(const Checkpoint* from, Simulator& sim, ResultWriter& out);

// Writes the checkpoint of a run; a failure (disk full) warns once and the run goes on.
struct CheckpointWriter {
  const Scene& scene;
  const RunOptions& options;
  std::uint64_t scene_hash, model_hash;
  bool failed = false;

  void save(Checkpoint c, const Simulator& sim, const ResultWriter& out);
};

// Whether a run should stop at this step (or iteration): an interruption, or the tests'
// --stop-after; --pause-after holds the process there first (SIGSTOP), once.
class StopCheck {
 public:
  explicit StopCheck(const RunOptions& options) : options_(options) {}
  bool operator()(long steps);

 private:
  const RunOptions& options_;
  bool paused_ = false;
};

}  // namespace phymul
