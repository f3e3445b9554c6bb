// The names of Data's members and of the aggregates inside it, for fields::for_each (a
// member added to Data without its name here does not compile).
#pragma once

#include <string>
#include <type_traits>

#include "model/fields.hpp"
#include "phymul/data.hpp"

namespace phymul::fields {

template <>
struct FieldNames<RigidBodyState> {
  static constexpr const char* names[] = {"center", "orientation", "momentum", "angular_momentum"};
};

template <>
struct FieldNames<PairContact> {
  static constexpr const char* names[] = {"pair",    "side",   "node",   "triangle",
                                          "weights", "normal", "impulse"};
};

template <>
struct FieldNames<EmbeddedPoint> {
  static constexpr const char* names[] = {"nodes", "weights"};
};

template <>
struct FieldNames<TrackPoint> {
  static constexpr const char* names[] = {"tissue", "point", "anchor", "length"};
};

template <>
struct FieldNames<PunctureEvent> {
  static constexpr const char* names[] = {"tissue", "time", "depth", "force"};
};

template <>
struct FieldNames<NeedleState> {
  static constexpr const char* names[] = {
      "phase", "contact", "track", "depth", "last_point_depth", "tip_tissue", "force", "punctures"};
};

template <>
struct FieldNames<AndersonHistory> {
  static constexpr const char* names[] = {"h",      "alpha", "held", "count",
                                          "newest", "df",    "dg",   "gram"};
};

template <>
struct FieldNames<StaticProgress> {
  static constexpr const char* names[] = {"load_step",        "iterations", "step_iterations",
                                          "previous_kinetic", "fire_alpha", "fire_downhill"};
};

template <>
struct FieldNames<Schedule> {
  static constexpr const char* names[] = {"times", "values"};
};

template <>
struct FieldNames<Controls> {
  static constexpr const char* names[] = {"applied_force", "obstacle_motion",  "pressure",
                                          "target_volume", "body_translation", "body_rotation",
                                          "needle_depth"};
};

template <>
struct FieldNames<Data> {
  static constexpr const char* names[] = {"time",
                                          "step",
                                          "x",
                                          "v",
                                          "f",
                                          "acceleration",
                                          "rotation",
                                          "cell_rotation",
                                          "shape_memory_energy",
                                          "bodies",
                                          "contact_force",
                                          "pair_contact_force",
                                          "obstacle_touching",
                                          "pair_contacts",
                                          "needles",
                                          "anderson",
                                          "dt",
                                          "stable_dt",
                                          "load_time",
                                          "static_progress",
                                          "controls",
                                          "work"};
};

// The workspace (Data::work) is the one member no visitor saves, compares or copies: no later
// step reads it (workspace.hpp).
template <class T>
inline constexpr bool is_workspace =
    std::is_same_v<std::remove_cv_t<T>, ::phymul::detail::Owned<Workspace>>;

}  // namespace phymul::fields

namespace phymul {

// "" when `data` has every array allocate_data(model) gives it, at that size (pair_contacts:
// at most its reserved capacity); else which member differs, and how.
std::string data_shape_mismatch(const Model& model, const Data& data);

// to = from, member by member but the workspace, each array keeping to's storage (its
// reservations) where it is large enough.
void assign_data(Data& to, const Data& from);

}  // namespace phymul
