#include "phymul/schedule.hpp"

#include <gtest/gtest.h>

namespace phymul {
using Vec3 = Eigen::Vector3d;
namespace {

TEST(Schedule, InterpolatesLinearlyAndHolds) {
  const Schedule s{{0.5, 1.5, 3.5}, {Vec3(0, 0, 0), Vec3(2, -4, 1), Vec3(2, 0, 0)}};
  EXPECT_EQ(s.at(-1.0), Vec3(0, 0, 0));  // held before the first event
  EXPECT_EQ(s.at(0.5), Vec3(0, 0, 0));
  EXPECT_TRUE(s.at(1.0).isApprox(Vec3(1, -2, 0.5), 1e-15));
  EXPECT_EQ(s.at(1.5), Vec3(2, -4, 1));
  EXPECT_TRUE(s.at(3.0).isApprox(Vec3(2, -1, 0.25), 1e-15));
  EXPECT_EQ(s.at(3.5), Vec3(2, 0, 0));
  EXPECT_EQ(s.at(100.0), Vec3(2, 0, 0));  // held after the last event
}

TEST(Schedule, ConstantAndEmpty) {
  EXPECT_EQ(Schedule::constant(Vec3(1, 2, 3)).at(42.0), Vec3(1, 2, 3));
  EXPECT_EQ(Schedule{}.at(1.0), Vec3::Zero());
}

}  // namespace
}  // namespace phymul
