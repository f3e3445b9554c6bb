#include "io/run_checkpoint.hpp"

#include <fmt/format.h>

#include <csignal>
#include <cstdio>

#include "model/data_fields.hpp"

namespace phymul {

bool CheckpointClock::due(long step, double time, double dt) {
  bool due = every_.steps > 0 && step - last_step_ >= every_.steps;
  if (every_.time > 0 && time >= next_time_ - 0.5 * dt) {
    due = true;
    while (next_time_ <= time + 0.5 * dt) next_time_ += every_.time;
  }
  if (due) last_step_ = step;
  return due;
}

std::string interrupted_message(const std::filesystem::path& dir) {
  return fmt::format(
      "interrupted; the results up to the last step and a checkpoint are written (continue "
      "with: phymul run --resume {})",
      dir.string());
}

std::optional<Checkpoint> checkpoint_to_resume(const Scene& scene, const RunOptions& options,
                                               std::uint64_t scene_hash) {
  if (!options.resume) return std::nullopt;
  Checkpoint c = read_checkpoint(checkpoint_path(options.output_dir));
  if (c.scene_hash != scene_hash)
    throw CheckpointError(fmt::format(
        "cannot resume in {}: the scene file {} changed since the checkpoint was written "
        "(recorded from {}); resuming needs the same scene, or start a new run",
        options.output_dir.string(), scene.file.string(), c.scene_file));
  return c;
}

void check_checkpoint_model(const Checkpoint& c, const Model& model, const Scene& scene,
                            const RunOptions& options) {
  if (c.model_hash != model_hash(model))
    throw CheckpointError(fmt::format(
        "cannot resume in {}: the model compiled from {} differs from the checkpoint's (a mesh "
        "or data file it reads changed?); start a new run",
        options.output_dir.string(), scene.file.string()));
  const std::string mismatch = data_shape_mismatch(model, c.data);
  if (!mismatch.empty())
    throw CheckpointError(fmt::format(
        "cannot resume in {}: the checkpoint's data does not fit the model compiled from {} "
        "({}); it was written by another phymul or is damaged: start a new run",
        options.output_dir.string(), scene.file.string(), mismatch));
}

void start_or_restore(const Checkpoint* from, Simulator& sim, ResultWriter& out) {
  if (from) {
    sim.restore(from->data);
    out.restore(from->frames, from->monitors);
  } else {
    out.frame(sim);
    out.monitor(sim);
  }
}

void CheckpointWriter::save(Checkpoint c, const Simulator& sim, const ResultWriter& out) {
  c.scene_file = std::filesystem::absolute(scene.file).lexically_normal().string();
  c.scene_hash = scene_hash;
  c.model_hash = model_hash;
  c.static_mode = sim.model().settings.mode == SolveMode::static_equilibrium;
  c.data = sim.data();
  c.frames = out.frame_list();
  c.monitors = out.monitors_text();
  // A checkpoint that cannot be written (disk full) must not cost the run its results.
  try {
    write_checkpoint(checkpoint_path(options.output_dir), c);
  } catch (const std::exception& e) {
    if (!failed)
      std::fprintf(stderr, "warning: %s; the run goes on without a checkpoint\n", e.what());
    failed = true;
  }
}

bool StopCheck::operator()(long steps) {
  if (options_.pause_after_steps > 0 && steps >= options_.pause_after_steps && !paused_) {
    paused_ = true;
    std::raise(SIGSTOP);  // a test's signal, sent meanwhile, is handled on SIGCONT
  }
  return interrupt_requested() ||
         (options_.stop_after_steps > 0 && steps >= options_.stop_after_steps);
}

}  // namespace phymul
