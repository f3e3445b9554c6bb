// The names of Checkpoint's members and of the aggregates in it, for fields::for_each (the
// checkpoint file holds each member of each, in order: a member added without its name here
// does not compile).
#pragma once

#include "model/data_fields.hpp"
#include "phymul/checkpoint.hpp"

namespace phymul {

namespace fields {

template <>
struct FieldNames<PvdEntry> {
  static constexpr const char* names[] = {"time", "file"};
};

template <>
struct FieldNames<Checkpoint> {
  static constexpr const char* names[] = {"scene_file", "scene_hash", "model_hash", "static_mode",
                                          "data",       "steps_done", "next_frame", "frames",
                                          "monitors",   "newton"};
};

template <>
struct FieldNames<fem::SolveState> {
  static constexpr const char* names[] = {
      "load_steps_done", "newton_iterations",   "load_factor",      "displacement",
      "curvature",       "curvature_increment", "factored_tangent", "energy",
      "internal_force",  "tangent_ff",          "tangent_fp",       "mode_amplitudes"};
};

}  // namespace fields

}  // namespace phymul
