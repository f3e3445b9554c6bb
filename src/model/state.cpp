#include <fmt/format.h>

#include "model/state_fields.hpp"

namespace phymul {
namespace {

// Every array of `got` against the same one of `made` (make_state's), nested ones included.
template <class T>
void compare_shape(const T& made, const T& got, const std::string& path, std::string& mismatch) {
  if (!mismatch.empty()) return;
  if constexpr (fields::is_vector<T>) {
    // An array make_state leaves empty with room reserved is a list of at most that many.
    const bool list = made.empty() && made.capacity() > 0;
    if (list ? got.size() > made.capacity() : got.size() != made.size()) {
      mismatch = fmt::format("'{}' has {} entries where the model {} {}", path, got.size(),
                             list ? "allows at most" : "has", list ? made.capacity() : made.size());
      return;
    }
    if constexpr (fields::is_vector<typename T::value_type>)
      for (size_t k = 0; k < made.size(); ++k)
        compare_shape(made[k], got[k], fmt::format("{}[{}]", path, k), mismatch);
  } else if constexpr (std::is_same_v<T, State>) {
    fields::for_each_pair(made, got, [&](std::string_view name, const auto& a, const auto& b) {
      compare_shape(a, b, path + "." + std::string(name), mismatch);
    });
  }
}

template <class T>
void assign_member(T& to, const T& from) {
  if constexpr (fields::is_vector<T>)
    to.assign(from.begin(), from.end());  // keeps to's storage when it is large enough
  else
    to = from;
}

}  // namespace

std::string state_shape_mismatch(const Model& model, const State& state) {
  std::string mismatch;
  compare_shape(make_state(model), state, "state", mismatch);
  return mismatch;
}

void assign_state(State& to, const State& from) {
  fields::for_each_pair(to, from,
                        [](std::string_view, auto& a, const auto& b) { assign_member(a, b); });
}

}  // namespace phymul
