#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "hysim/haptics/device.hpp"

namespace hysim::haptics {
namespace {

TEST(Trajectory, ArcMoveStaysOnTheCircle) {
  Keyframe a, b;
  a.tip = {10, 0, 0};
  b.time_s = 1.0;
  b.tip = {0, 10, 0};
  b.move = Keyframe::Move::Arc;
  b.arc_center = {0, 0, 0};
  ASSERT_TRUE(validArc(a.tip, b.tip, b.arc_center));
  const Trajectory t({a, b});
  for (double s : {0.1, 0.25, 0.5, 0.9}) EXPECT_NEAR(t.sample(s).tip.norm(), 10.0, 1e-12) << s;
  const Eigen::Vector3d mid = t.sample(0.5).tip;
  EXPECT_NEAR(mid.x(), 10.0 / std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(mid.y(), 10.0 / std::sqrt(2.0), 1e-12);
}

TEST(Trajectory, ArcValidity) {
  EXPECT_FALSE(validArc({1, 0, 0}, {-1, 0, 0}, {0, 0, 0}));  // 180 degrees: plane undefined
  EXPECT_FALSE(validArc({1, 0, 0}, {2, 0, 0}, {0, 0, 0}));   // same direction
  EXPECT_FALSE(validArc({0, 0, 0}, {1, 0, 0}, {0, 0, 0}));   // an end at the centre
  EXPECT_TRUE(validArc({1, 0, 0}, {0, 2, 0}, {0, 0, 0}));    // radius may change
}

TEST(SafeForce, ClampsAndRejectsNonFinite) {
  EXPECT_NEAR(safeForce({3, 4, 0}, 1.0).norm(), 1.0, 1e-12);
  EXPECT_NEAR(safeForce({3, 4, 0}, 1.0).x(), 0.6, 1e-12);
  EXPECT_EQ(safeForce({0.1, 0, 0}, 1.0), Eigen::Vector3d(0.1, 0, 0));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(safeForce({nan, 0, 0}, 1.0), Eigen::Vector3d::Zero());
  EXPECT_EQ(safeForce({std::numeric_limits<double>::infinity(), 0, 0}, 1.0), Eigen::Vector3d::Zero());
}

TEST(ScriptedDevice, VelocityPedalAndForce) {
  Keyframe a, b, c;
  a.tip = {0, 0, 0};
  b.time_s = 2.0;
  b.tip = {0, 0, 20};  // 10 mm/s along z
  b.extension_mm = 4.0;
  b.pedal = true;
  c.time_s = 3.0;
  c.tip = {0, 0, 20};
  ScriptedDevice device(Trajectory({a, b, c}));
  const DeviceState s = device.read(1.0);
  EXPECT_NEAR(s.velocity_mm_s.z(), 10.0, 1e-9);
  EXPECT_NEAR(s.extension_velocity_mm_s, 2.0, 1e-9);
  EXPECT_NEAR(s.angular_velocity_rad_s.norm(), 0.0, 1e-12);
  EXPECT_EQ(s.buttons, 0u);
  EXPECT_EQ(device.read(2.5).buttons, 1u);  // pedal pressed from keyframe b on
  EXPECT_TRUE(device.read(2.5).pose.pedal);
  device.commandForce({0, 0, 100});
  EXPECT_NEAR(device.lastForce().norm(), device.info().max_force_n, 1e-12);
}

}  // namespace
}  // namespace hysim::haptics

namespace hysim::haptics {
namespace {

TEST(ManualDevice, IntegratesRateCommandsInTheScopeFrame) {
  ToolPose start;
  start.tip = {0, 0, -20};
  start.rotation = frameFromAxisUp({0, 0, 1}, {0, 1, 0});
  ManualDevice device(start, 1.0);
  ManualCommand forward;
  forward.velocity_scope_mm_s = {0, 0, 10};  // along the axis
  forward.extension_mm_s = 2.0;
  device.setCommand(forward);
  DeviceState s = device.read(1.5);
  EXPECT_NEAR(s.pose.tip.z(), -15.0, 1e-12);
  EXPECT_NEAR(s.pose.extension_mm, 1.0, 1e-12);
  ManualCommand turn;
  turn.yaw_rad_s = 3.14159265358979323846 / 2;  // 90 degrees in 1 s about up (+y)
  device.setCommand(turn);
  s = device.read(2.5);
  EXPECT_NEAR(s.pose.rotation.col(2).x(), 1.0, 1e-9);  // the axis now points along +x
  EXPECT_NEAR(s.pose.tip.z(), -15.0, 1e-12);           // turning does not move the tip
  EXPECT_NEAR((s.pose.rotation.transpose() * s.pose.rotation - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);
  // Reading the same time again changes nothing; time never runs backwards.
  const DeviceState again = device.read(2.0);
  EXPECT_EQ(again.pose.tip, s.pose.tip);
}

}  // namespace
}  // namespace hysim::haptics
