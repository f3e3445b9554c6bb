// The names of State's members and of the aggregates inside it, for fields::for_each (a
// member added to State without its name here does not compile).
#pragma once

#include <string>

#include "model/fields.hpp"
#include "phymul/model.hpp"

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
struct FieldNames<State> {
  static constexpr const char* names[] = {"time",
                                          "step",
                                          "x",
                                          "v",
                                          "f",
                                          "rotation",
                                          "shape_memory_energy",
                                          "bodies",
                                          "contact_force",
                                          "pair_contact_force",
                                          "obstacle_touching",
                                          "pair_contacts"};
};

}  // namespace phymul::fields

namespace phymul {

// "" when `state` has every array make_state(model) gives it, at that size (pair_contacts: at
// most its reserved capacity); else which member differs, and how.
std::string state_shape_mismatch(const Model& model, const State& state);

// to = from, member by member, each array keeping to's storage (make_state's reservations)
// where it is large enough.
void assign_state(State& to, const State& from);

}  // namespace phymul
