#include <gtest/gtest.h>

#include <limits>

#include "haptics_test_util.hpp"
#include "hysim/haptics/haptic_loop.hpp"
#include "hysim/haptics/mirrored_device.hpp"

namespace hysim::haptics {
namespace {

TEST(MirroredDevice, ReadsTheNewestPublishedStateAndKeepsIt) {
  MirroredDevice d;
  EXPECT_EQ(d.read(0.0).pose.tip, Eigen::Vector3d::Zero());  // nothing published yet
  DeviceState s;
  s.pose.tip = {1, 2, 3};
  s.velocity_mm_s = {0, 0, 5};
  d.publish(s);
  s.pose.tip = {4, 5, 6};
  d.publish(s);
  EXPECT_EQ(d.read(123.0).pose.tip, Eigen::Vector3d(4, 5, 6));  // the newest, whatever the time
  EXPECT_EQ(d.read(124.0).pose.tip, Eigen::Vector3d(4, 5, 6));  // and again with nothing new
  EXPECT_EQ(d.read(124.0).velocity_mm_s, Eigen::Vector3d(0, 0, 5));
}

TEST(MirroredDevice, KeepsTheCommandedForceClampedAndFinite) {
  MirroredDevice d;
  d.commandForce({0, 0, 10});
  EXPECT_EQ(d.lastForce(), Eigen::Vector3d(0, 0, 3));  // max_force_n
  EXPECT_DOUBLE_EQ(d.renderedForceN(), 3.0);
  d.commandForce({std::numeric_limits<double>::quiet_NaN(), 0, 0});
  EXPECT_EQ(d.lastForce(), Eigen::Vector3d::Zero());
  EXPECT_DOUBLE_EQ(d.renderedForceN(), 0.0);
}

// A haptic loop on a mirrored device renders the coupling force the model gives at the
// mirrored position (once the safety gate has ramped in).
TEST(MirroredDevice, AHapticLoopRendersTheModelAtTheMirroredState) {
  auto owned = std::make_unique<MirroredDevice>();
  MirroredDevice& device = *owned;
  FakeClock clock;
  HapticLoopOptions options;
  options.safety.ramp_s = 0.0;
  HapticLoop loop(std::move(owned), clock, options);
  DeviceState s;
  s.pose.tip = {0, 0, 2};
  device.publish(s);
  LocalForceModel m;
  m.stiffness_n_per_mm = -0.5 * Eigen::Matrix3d::Identity();  // a spring towards the origin
  for (int i = 0; i < 10; ++i) {
    m.step = i;
    loop.publishModel(m);
    loop.tick(i * test::kMs);
  }
  EXPECT_EQ(loop.safetyState(), SafetyState::WaitingForSmall);  // 1 N from the start: not engaged
  s.pose.tip = {0, 0, 0.1};  // the hand comes back near the origin: small force, engage
  device.publish(s);
  for (int i = 10; i < 20; ++i) {
    m.step = i;
    loop.publishModel(m);
    loop.tick(i * test::kMs);
  }
  EXPECT_EQ(loop.safetyState(), SafetyState::Engaged);
  EXPECT_NEAR(device.renderedForceN(), 0.05, 1e-12);
  DeviceState seen;
  ASSERT_TRUE(loop.latestState(seen));
  EXPECT_EQ(seen.pose.tip, Eigen::Vector3d(0, 0, 0.1));
}

}  // namespace
}  // namespace hysim::haptics
