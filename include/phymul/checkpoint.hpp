// Checkpoints of a run: everything needed to continue it and reproduce the uninterrupted
// results bit for bit (binary, doubles stored as their bits).
#pragma once

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "phymul/data.hpp"
#include "phymul/fem.hpp"
#include "phymul/model.hpp"
#include "phymul/vtk.hpp"

namespace phymul {

// A checkpoint that cannot be used: missing, truncated, corrupt, or from another scene.
class CheckpointError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A run's checkpoint: its Data whole (every member but the workspace) and the bookkeeping of
// the files written so far.
struct Checkpoint {
  std::string scene_file;        // absolute path of the scene it was run from
  std::uint64_t scene_hash = 0;  // of the scene file's bytes
  std::uint64_t model_hash = 0;  // of the compiled model (mesh files included)
  bool static_mode = false;
  Data data;
  long steps_done = 0;           // dynamic mode: explicit steps taken
  double next_frame = 0.0;       // s, dynamic mode: time of the next regular frame
  std::vector<PvdEntry> frames;  // frames written so far (their files are in the directory)
  std::string monitors;          // monitors.csv so far, header included
  fem::SolveState newton;        // a static Newton run (solver: newton): where it stands
};

// The checkpoint's name in an output directory.
std::filesystem::path checkpoint_path(const std::filesystem::path& output_dir);

// FNV-1a, 64 bits: detects a changed scene or model (not an adversary).
std::uint64_t fnv1a(std::string_view bytes, std::uint64_t seed = 0xcbf29ce484222325ULL);
std::uint64_t file_hash(const std::filesystem::path& file);  // throws CheckpointError
std::uint64_t model_hash(const Model& model);

// Written to a temporary name and renamed, so a checkpoint is either whole or absent.
void write_checkpoint(const std::filesystem::path& path, const Checkpoint& checkpoint);
// Every size and the checksum are checked: a damaged file gives CheckpointError naming it
// and what is wrong, never a crash.
Checkpoint read_checkpoint(const std::filesystem::path& path);
Checkpoint parse_checkpoint(std::string_view bytes, const std::string& name);

}  // namespace phymul
