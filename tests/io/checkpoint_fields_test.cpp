// Every member of a checkpoint, and of the Data inside it, survives writing and reading:
// each is filled with a value of its own (the visitor finds them all, not a hand-kept list),
// written, read back and compared member by member.
#include "io/checkpoint_fields.hpp"

#include <gtest/gtest.h>

#include <string>
#include <type_traits>
#include <vector>

#include "support/process.hpp"

namespace phymul {
namespace {

// Gives every scalar a value of its own (1, 2, 3, ...), every array two entries.
struct Filler {
  int next = 1;
  template <class T>
  void operator()(T& v) {
    if constexpr (fields::is_workspace<T>) {
      return;  // not saved
    } else if constexpr (std::is_same_v<T, bool>) {
      v = true;
    } else if constexpr (std::is_arithmetic_v<T>) {
      v = T(next++);
    } else if constexpr (std::is_same_v<T, std::string>) {
      v = std::to_string(next++);
    } else if constexpr (std::is_same_v<T, Eigen::Quaterniond>) {
      v = Eigen::Quaterniond(next, next + 1, next + 2, next + 3);
      next += 4;
    } else if constexpr (std::is_base_of_v<Eigen::MatrixBase<T>, T>) {
      for (Eigen::Index k = 0; k < v.size(); ++k) v.data()[k] = next++;
    } else if constexpr (fields::is_vector<T>) {
      v.resize(2);
      for (auto& e : v) (*this)(e);
    } else if constexpr (fields::is_array<T>) {
      for (auto& e : v) (*this)(e);
    } else {
      fields::for_each(v, [&](std::string_view, auto& member) { (*this)(member); });
    }
  }
};

template <class T>
void expect_equal(const T& a, const T& b, const std::string& path) {
  if constexpr (fields::is_workspace<T>) {
    return;  // not saved
  } else if constexpr (std::is_same_v<T, Eigen::Quaterniond>) {
    EXPECT_EQ(a.coeffs(), b.coeffs()) << path;
  } else if constexpr (fields::is_vector<T> || fields::is_array<T>) {
    ASSERT_EQ(a.size(), b.size()) << path;
    for (size_t k = 0; k < a.size(); ++k) expect_equal(a[k], b[k], path + "[]");
  } else if constexpr (std::is_arithmetic_v<T> || std::is_same_v<T, std::string> ||
                       std::is_base_of_v<Eigen::MatrixBase<T>, T>) {
    EXPECT_EQ(a, b) << path;
  } else {
    fields::for_each_pair(a, b, [&](std::string_view name, const auto& x, const auto& y) {
      expect_equal(x, y, path + "." + std::string(name));
    });
  }
}

TEST(CheckpointFields, EveryMemberSurvivesWritingAndReading) {
  Checkpoint c;
  Filler{}(c);
  c.frames = {{1.0, "scene_000001.vtu"}, {2.0, "scene_000002.vtu"}};  // plain names only
  c.data.obstacle_touching.assign(c.data.x.size(), 7);  // per node, as the reader checks
  testing::TempDir dir;
  write_checkpoint(dir.path() / "c.bin", c);
  const Checkpoint back = read_checkpoint(dir.path() / "c.bin");
  expect_equal(c, back, "checkpoint");
  // And the filler reached the members: the last of them is not at its default.
  EXPECT_FALSE(back.newton.mode_amplitudes.empty());
  EXPECT_FALSE(back.data.pair_contacts.empty());
  EXPECT_NE(back.data.pair_contacts[1].impulse, 0.0);
}

TEST(CheckpointFields, DataMembersAreCountedAndNamed) {
  static_assert(fields::count<Data> == std::size(fields::FieldNames<Data>::names));
  std::vector<std::string> names;
  Data s;
  fields::for_each(s, [&](std::string_view name, auto&) { names.emplace_back(name); });
  ASSERT_EQ(names.size(), fields::count<Data>);
  EXPECT_EQ(names.front(), "time");
  EXPECT_EQ(names.back(), "work");
}

}  // namespace
}  // namespace phymul
