#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "hysim/haptics/filters.hpp"

namespace hysim::haptics {
namespace {

DeviceState at(double t, const Eigen::Vector3d& tip) {
  DeviceState s;
  s.time_s = t;
  s.pose.tip = tip;
  return s;
}

TEST(MotionScale, ScalesPositionsAndVelocitiesAboutTheCentreNotTurns) {
  MotionScale scale{0.5, {10, 0, 0}};
  DeviceState s = at(0.0, {20, 4, 0});
  s.velocity_mm_s = {8, 0, 0};
  s.angular_velocity_rad_s = {0, 0, 1};
  const DeviceState out = scale.apply(s);
  EXPECT_EQ(out.pose.tip, Eigen::Vector3d(15, 2, 0));
  EXPECT_EQ(out.velocity_mm_s, Eigen::Vector3d(4, 0, 0));
  EXPECT_EQ(out.angular_velocity_rad_s, s.angular_velocity_rad_s);
}

TEST(PoseTransform, MapsTheDeviceFrameIntoTheWorldAndForcesBack) {
  PoseTransform t;
  t.rotation = Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.translation_mm = {0, 0, -50};
  DeviceState s = at(0.0, {10, 0, 0});
  s.velocity_mm_s = {1, 0, 0};
  const DeviceState out = t.apply(s);
  EXPECT_TRUE(out.pose.tip.isApprox(Eigen::Vector3d(0, 10, -50), 1e-12));
  EXPECT_TRUE(out.velocity_mm_s.isApprox(Eigen::Vector3d(0, 1, 0), 1e-12));
  EXPECT_TRUE(out.pose.rotation.isApprox(t.rotation, 1e-12));  // the device's identity turns with it
  // A world force along +y is the device's +x.
  EXPECT_TRUE(t.forceToDevice({0, 2, 0}).isApprox(Eigen::Vector3d(2, 0, 0), 1e-12));
}

TEST(MotionLimit, SmoothMotionPassesUnchanged) {
  MotionLimit limit(500.0, 6.0, 100.0);
  for (int i = 0; i <= 100; ++i) {
    DeviceState s = at(1e-3 * i, {0.1 * i, 0, 0});  // 100 mm/s
    s.pose.rotation = Eigen::AngleAxisd(1e-3 * i, Eigen::Vector3d::UnitY()).toRotationMatrix();  // 1 rad/s
    s.pose.extension_mm = 0.01 * i;                                                                // 10 mm/s
    const DeviceState out = limit.apply(s);
    EXPECT_EQ(out.pose.tip, s.pose.tip);
    EXPECT_EQ(out.pose.rotation, s.pose.rotation);
    EXPECT_EQ(out.pose.extension_mm, s.pose.extension_mm);
  }
  EXPECT_EQ(limit.limitedReads(), 0);
}

TEST(MotionLimit, AJumpIsSpreadOverTheFollowingReads) {
  MotionLimit limit(500.0, 6.0, 100.0);
  limit.apply(at(0.0, {0, 0, 0}));
  // The device's data jumps 100 mm (a glitch): the tool moves 0.5 mm per millisecond towards it.
  DeviceState out = limit.apply(at(1e-3, {100, 0, 0}));
  EXPECT_NEAR(out.pose.tip.x(), 0.5, 1e-12);
  EXPECT_NEAR(out.velocity_mm_s.x(), 500.0, 1e-9);
  for (int i = 2; i <= 10; ++i) out = limit.apply(at(1e-3 * i, {100, 0, 0}));
  EXPECT_NEAR(out.pose.tip.x(), 5.0, 1e-9);
  EXPECT_EQ(limit.limitedReads(), 10);
  limit.reset();  // e.g. after a reconnect, the new position is taken as it is
  EXPECT_EQ(limit.apply(at(0.02, {100, 0, 0})).pose.tip.x(), 100.0);
}

TEST(MotionLimit, TurnsAndExtensionAreLimitedToo) {
  MotionLimit limit(500.0, 6.0, 100.0);
  limit.apply(at(0.0, {0, 0, 0}));
  DeviceState s = at(1e-3, {0, 0, 0});
  s.pose.rotation = Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  s.pose.extension_mm = 10.0;
  const DeviceState out = limit.apply(s);
  EXPECT_NEAR(Eigen::AngleAxisd(out.pose.rotation).angle(), 6e-3, 1e-9);
  EXPECT_NEAR(out.pose.extension_mm, 0.1, 1e-12);
  EXPECT_EQ(limit.limitedReads(), 1);
}

TEST(FilteredDevice, ScalesTransformsLimitsAndSendsForcesBack) {
  Keyframe a, b;
  a.tip = {0, 0, 0};
  b.time_s = 1.0;
  b.tip = {100, 0, 0};  // 100 mm/s in the device's frame
  PoseTransform t;
  t.rotation = Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  auto inner = std::make_unique<ScriptedDevice>(Trajectory({a, b}));
  ScriptedDevice* raw = inner.get();
  FilteredDevice device(std::move(inner), MotionScale{0.5, {0, 0, 0}}, t, MotionLimit(500.0, 6.0, 100.0));
  device.read(0.0);
  const DeviceState s = device.read(0.5);
  EXPECT_TRUE(s.pose.tip.isApprox(Eigen::Vector3d(0, 25, 0), 1e-9));
  EXPECT_TRUE(s.velocity_mm_s.isApprox(Eigen::Vector3d(0, 50, 0), 1e-6));
  device.commandForce({0, 1, 0});
  EXPECT_TRUE(raw->lastForce().isApprox(Eigen::Vector3d(1, 0, 0), 1e-12));
  EXPECT_EQ(device.lastForce(), Eigen::Vector3d(0, 1, 0));
  EXPECT_TRUE(device.connected());
}

}  // namespace
}  // namespace hysim::haptics
