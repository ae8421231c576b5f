// The keyboard scope that pivots at the cervix: the shaft stays on the trocar, insertion stops
// at the depth limit without pulling back, the tilt stays in its cone, roll keeps the tip.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "hysim/haptics/pivot_device.hpp"

namespace hysim::haptics {
namespace {

const Eigen::Vector3d kTrocar(0, 0, -32);

ToolPose startPose() {
  ToolPose p;
  p.tip = Eigen::Vector3d(0, 0, -16);
  p.rotation = frameFromAxisUp(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 1, 0));
  return p;
}

// Distance of `p` from the line through `a` along unit `d`.
double offLine(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& d) {
  return (p - a).cross(d).norm();
}

DeviceState hold(PivotScopeDevice& dev, const PivotCommand& c, double from_s, double seconds) {
  dev.setCommand(c);
  DeviceState s;
  for (int i = 1; i <= static_cast<int>(std::lround(seconds * 1000)); ++i) s = dev.read(from_s + 1e-3 * i);
  return s;
}

TEST(PivotScopeDevice, ShaftStaysOnTheTrocarWhileTurningAndInserting) {
  PivotScopeDevice dev(kTrocar, startPose(), 0.0, Eigen::Vector3d(0, 0, 1));
  PivotCommand c;
  c.yaw_rad_s = 0.2;
  c.pitch_rad_s = -0.1;
  c.insert_mm_s = 3.0;
  const DeviceState s = hold(dev, c, 0.0, 1.0);
  EXPECT_LT(offLine(kTrocar, s.pose.tip, s.pose.rotation.col(2)), 1e-9);
  EXPECT_NEAR((s.pose.tip - kTrocar).norm(), 19.0, 1e-9);
  EXPECT_GT(std::fabs(s.pose.tip.x()), 1.0);  // the tip swung sideways about the trocar
  EXPECT_TRUE(s.pose.rotation.isUnitary(1e-9));
}

TEST(PivotScopeDevice, InsertionStopsAtTheDepthLimitAndWithdrawsFreely) {
  PivotScopeDevice dev(kTrocar, startPose(), 0.0, Eigen::Vector3d(0, 0, 1));
  dev.setDepthLimit(20.0);
  PivotCommand in;
  in.insert_mm_s = 10.0;
  DeviceState s = hold(dev, in, 0.0, 2.0);  // 20 mm wanted, 4 allowed
  EXPECT_DOUBLE_EQ(dev.depth(), 20.0);
  EXPECT_TRUE(dev.depthLimited());
  EXPECT_NEAR(s.pose.tip.z(), -12.0, 1e-9);
  // A limit below the current depth (tissue moved towards the tip) does not pull back.
  dev.setDepthLimit(18.0);
  s = hold(dev, in, 2.0, 0.5);
  EXPECT_DOUBLE_EQ(dev.depth(), 20.0);
  PivotCommand out;
  out.insert_mm_s = -10.0;
  hold(dev, out, 2.5, 0.5);
  EXPECT_NEAR(dev.depth(), 15.0, 1e-9);
  EXPECT_FALSE(dev.depthLimited());
  hold(dev, out, 3.0, 5.0);  // never behind the trocar
  EXPECT_DOUBLE_EQ(dev.depth(), PivotLimits{}.min_depth_mm);
}

TEST(PivotScopeDevice, TiltStaysWithinTheConeButTurnsBack) {
  PivotScopeDevice dev(kTrocar, startPose(), 0.0, Eigen::Vector3d(0, 0, 1));
  PivotCommand c;
  c.yaw_rad_s = 0.5;
  DeviceState s = hold(dev, c, 0.0, 3.0);  // 1.5 rad wanted
  const double tilt = std::acos(s.pose.rotation.col(2).z());
  EXPECT_LE(tilt, PivotLimits{}.max_tilt_rad + 1e-3);
  EXPECT_GT(tilt, PivotLimits{}.max_tilt_rad - 1e-3);
  EXPECT_TRUE(dev.tiltLimited());
  c.yaw_rad_s = -0.5;
  s = hold(dev, c, 3.0, 0.2);
  EXPECT_LT(std::acos(s.pose.rotation.col(2).z()), tilt - 0.05);
  EXPECT_FALSE(dev.tiltLimited());
}

TEST(PivotScopeDevice, RollTurnsAboutTheShaftOnly) {
  PivotScopeDevice dev(kTrocar, startPose(), 0.0, Eigen::Vector3d(0, 0, 1));
  PivotCommand c;
  c.roll_rad_s = 1.0;
  const DeviceState s = hold(dev, c, 0.0, 0.5);
  EXPECT_LT((s.pose.tip - startPose().tip).norm(), 1e-9);
  EXPECT_NEAR(std::acos(s.pose.rotation.col(1).dot(Eigen::Vector3d(0, 1, 0))), 0.5, 1e-6);
  EXPECT_NEAR(s.angular_velocity_rad_s.z(), 1.0, 1e-6);
}

TEST(PivotScopeDevice, PedalAndLoopFollowTheCommand) {
  PivotScopeDevice dev(kTrocar, startPose(), 0.0, Eigen::Vector3d(0, 0, 1));
  PivotCommand c;
  c.pedal = true;
  c.extension_mm_s = 5.0;
  DeviceState s = hold(dev, c, 0.0, 1.0);
  EXPECT_TRUE(s.pose.pedal);
  EXPECT_EQ(s.buttons, 1u);
  EXPECT_NEAR(s.pose.extension_mm, 5.0, 1e-9);
  c.pedal = false;
  s = hold(dev, c, 1.0, 10.0);
  EXPECT_FALSE(s.pose.pedal);
  EXPECT_DOUBLE_EQ(s.pose.extension_mm, PivotLimits{}.max_extension_mm);
}

TEST(PivotScopeDevice, StartsOnTheLineFromTheTrocarThroughTheTip) {
  ToolPose p = startPose();
  p.tip = Eigen::Vector3d(0, 5, -16.8);  // the default course's first pose: axis off the line
  PivotScopeDevice dev(kTrocar, p, 0.0, Eigen::Vector3d(0, 0, 1));
  const DeviceState s = dev.read(0.0);
  EXPECT_LT((s.pose.tip - p.tip).norm(), 1e-9);
  EXPECT_LT(offLine(kTrocar, s.pose.tip, s.pose.rotation.col(2)), 1e-9);
}

TEST(PivotScopeDevice, SideRoomStopsATurnIntoTheWallButNotOneAway) {
  PivotScopeDevice dev(kTrocar, startPose(), 0.0, Eigen::Vector3d(0, 0, 1));
  const double inf = std::numeric_limits<double>::infinity();
  dev.setSideRoom(startPose().tip, {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(-1, 0, 0), Eigen::Vector3d(0, 1, 0),
                                    Eigen::Vector3d(0, -1, 0)},
                  {inf, inf, 1.0, inf});
  PivotCommand up;
  up.pitch_rad_s = -0.3;  // the view, and the tip, turn up
  DeviceState s = hold(dev, up, 0.0, 1.0);  // 4.8 mm wanted, 1 mm of room
  EXPECT_LE(s.pose.tip.y(), 1.0);
  EXPECT_GT(s.pose.tip.y(), 0.9);
  EXPECT_TRUE(dev.sideLimited());
  PivotCommand down;
  down.pitch_rad_s = 0.3;
  s = hold(dev, down, 1.0, 0.5);
  EXPECT_LT(s.pose.tip.y(), -1.0);
  EXPECT_FALSE(dev.sideLimited());
}

}  // namespace
}  // namespace hysim::haptics
