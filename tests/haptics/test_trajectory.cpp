#include <gtest/gtest.h>

#include "hysim/haptics/trajectory.hpp"

namespace hysim::haptics {
namespace {

TEST(Trajectory, InterpolatesPositionExtensionAndHoldsEnds) {
  Keyframe a, b;
  a.time_s = 1.0;
  a.tip = {0, 0, 0};
  b.time_s = 3.0;
  b.tip = {10, 0, 0};
  b.extension_mm = 4.0;
  b.pedal = true;
  const Trajectory t({b, a});  // unsorted input is sorted
  EXPECT_DOUBLE_EQ(t.sample(2.0).tip.x(), 5.0);
  EXPECT_DOUBLE_EQ(t.sample(2.0).extension_mm, 2.0);
  EXPECT_FALSE(t.sample(2.0).pedal);
  EXPECT_TRUE(t.sample(3.0).pedal);
  EXPECT_DOUBLE_EQ(t.sample(-5.0).tip.x(), 0.0);
  EXPECT_DOUBLE_EQ(t.sample(50.0).tip.x(), 10.0);
}

TEST(Trajectory, SlerpsOrientationAndKeepsAFrame) {
  Keyframe a, b;
  a.axis = {0, 0, 1};
  a.up = {0, 1, 0};
  b.time_s = 1.0;
  b.axis = {1, 0, 0};
  b.up = {0, 1, 0};
  const Trajectory t({a, b});
  const Eigen::Matrix3d r = t.sample(0.5).rotation;
  EXPECT_NEAR((r.transpose() * r - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);
  EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
  EXPECT_NEAR(r.col(2).dot(Eigen::Vector3d(1, 0, 1).normalized()), 1.0, 1e-12);  // halfway
  EXPECT_NEAR(r.col(1).dot(Eigen::Vector3d::UnitY()), 1.0, 1e-12);
}

TEST(Trajectory, FrameFromAxisUpOrthogonalises) {
  const Eigen::Matrix3d r = frameFromAxisUp({0, 0, 2}, {0, 1, 1});
  EXPECT_NEAR(r.col(1).dot(Eigen::Vector3d::UnitY()), 1.0, 1e-12);
  EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
  const Eigen::Matrix3d p = frameFromAxisUp({0, 0, 1}, {0, 0, 1});  // degenerate up
  EXPECT_NEAR(p.determinant(), 1.0, 1e-12);
}

}  // namespace
}  // namespace hysim::haptics
