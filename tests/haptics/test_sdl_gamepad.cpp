// The SDL game controller driver against SDL's virtual joystick (no pad, no display): sticks
// in => pose out at explicit read times, pedal and lens buttons, force => rumble values, the
// serosa pulses, unplug and replug. SDL must be able to start its joystick subsystem here;
// if it cannot, these tests fail (they never skip).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "hysim/haptics/sdl_gamepad.hpp"
#include "hysim/haptics/virtual_pad.hpp"

namespace hysim::haptics {
namespace {

class SdlGamepad : public ::testing::Test {
 protected:
  void SetUp() override {
    auto pad = VirtualPad::attach("hysim test pad");
    ASSERT_TRUE(pad.ok()) << "SDL's virtual joystick is needed for these tests and could not be attached: "
                          << pad.error();
    pad_ = std::move(pad.value());
    ASSERT_GE(pad_->deviceIndex(), 0);
    SdlGamepadOptions options;
    options.device_index = pad_->deviceIndex();
    auto device = SdlGamepadDevice::open(start_, 0.0, options);
    ASSERT_TRUE(device.ok()) << device.error();
    device_ = std::move(device.value());
    device_->read(0.0);
  }
  void TearDown() override {
    device_.reset();  // before the pad it reads
    pad_.reset();
  }

  static std::uint16_t rumbleFor(double force_n, double max_n) {
    return static_cast<std::uint16_t>(std::lround(force_n / max_n * 65535.0));
  }

  ToolPose start_;  // at the origin, looking along +z
  std::unique_ptr<VirtualPad> pad_;
  std::unique_ptr<SdlGamepadDevice> device_;
};

TEST_F(SdlGamepad, OpensTheVirtualPadAsAController) {
  EXPECT_TRUE(device_->connected());
  EXPECT_TRUE(device_->isController());
  EXPECT_EQ(device_->padName(), "hysim test pad");
  EXPECT_EQ(device_->mapping().layout, PadLayout::Controller);
  EXPECT_FALSE(device_->hasConstantForce());  // a virtual pad has motors, no force channel
  EXPECT_EQ(device_->counters().disconnects, 0);
  EXPECT_EQ(device_->counters().reconnects, 0);
}

TEST_F(SdlGamepad, FullForwardStickForHalfASecondAdvancesGainTimesHalfASecond) {
  const double gain = device_->mapping().advance.gain;
  pad_->setStick(pad::kLeftY, -1.0);  // up
  device_->read(0.0);                 // takes the new command; no time has passed
  const DeviceState s = device_->read(0.5);
  EXPECT_NEAR(s.pose.tip.z(), 0.5 * gain, 1e-9);
  EXPECT_NEAR(s.pose.tip.x(), 0.0, 1e-12);
  EXPECT_NEAR(s.pose.tip.y(), 0.0, 1e-12);
  EXPECT_NEAR(s.velocity_mm_s.z(), gain, 1e-9);
  // Back to centre: the tool stays.
  pad_->setStick(pad::kLeftY, 0.0);
  EXPECT_NEAR(device_->read(1.0).pose.tip.z(), 0.5 * gain, 1e-9);
}

TEST_F(SdlGamepad, DeadZoneHoldsTheToolAndIsRescaledBeyond) {
  const GamepadMapping& m = device_->mapping();
  pad_->setStick(pad::kLeftX, 0.9 * m.pan_x.dead_zone);  // resting off-centre
  device_->read(0.0);
  EXPECT_EQ(device_->read(1.0).pose.tip.x(), 0.0);
  // Halfway between the zone's edge and full: half speed.
  pad_->setStick(pad::kLeftX, m.pan_x.dead_zone + 0.5 * (1.0 - m.pan_x.dead_zone));
  device_->read(1.0);
  EXPECT_NEAR(device_->read(2.0).pose.tip.x(), 0.5 * m.pan_x.gain, 2e-3);  // 16-bit axis
}

TEST_F(SdlGamepad, RightStickTurnsTheScopeAndTriggersMoveTheLoop) {
  const GamepadMapping& m = device_->mapping();
  pad_->setStick(pad::kRightX, 1.0);  // like the D key: negative yaw
  device_->read(0.0);
  DeviceState s = device_->read(0.5);
  const double angle = -0.5 * m.yaw.gain;
  const Eigen::Vector3d axis = s.pose.rotation.col(2);
  EXPECT_NEAR(axis.x(), std::sin(angle), 1e-9);
  EXPECT_NEAR(axis.z(), std::cos(angle), 1e-9);
  EXPECT_NEAR(s.pose.tip.norm(), 0.0, 1e-12);  // turning does not move the tip
  pad_->setStick(pad::kRightX, 0.0);
  pad_->setTrigger(pad::kRightTrigger, 1.0);
  device_->read(0.5);
  s = device_->read(1.5);
  EXPECT_NEAR(s.pose.extension_mm, m.loop_extend.gain, 1e-9);
  EXPECT_NEAR(s.extension_velocity_mm_s, m.loop_extend.gain, 1e-9);
  pad_->setTrigger(pad::kRightTrigger, 0.0);
  pad_->setTrigger(pad::kLeftTrigger, 1.0);
  device_->read(1.5);
  EXPECT_NEAR(device_->read(1.7).pose.extension_mm, m.loop_extend.gain - 0.2 * m.loop_retract.gain, 1e-9);
}

TEST_F(SdlGamepad, PedalButtonAndLensToggleOnPress) {
  pad_->setButton(pad::kRightShoulder, true);
  DeviceState s = device_->read(0.1);
  EXPECT_TRUE(s.pose.pedal);
  EXPECT_EQ(s.buttons & 1u, 1u);
  pad_->setButton(pad::kRightShoulder, false);
  s = device_->read(0.2);
  EXPECT_FALSE(s.pose.pedal);
  EXPECT_EQ(s.buttons, 0u);

  EXPECT_EQ(device_->lensDeg(), 30);
  pad_->setButton(pad::kY, true);
  s = device_->read(0.3);
  EXPECT_EQ(device_->lensDeg(), 0);  // 30 -> 0
  EXPECT_EQ(s.buttons & 2u, 2u);     // bit 1: the lens button held
  device_->read(0.4);                // still held: no second step
  EXPECT_EQ(device_->lensDeg(), 0);
  pad_->setButton(pad::kY, false);
  device_->read(0.5);
  pad_->setButton(pad::kY, true);
  device_->read(0.6);
  EXPECT_EQ(device_->lensDeg(), 12);
  pad_->setButton(pad::kY, false);
  device_->read(0.7);
  pad_->setButton(pad::kY, true);
  device_->read(0.8);
  EXPECT_EQ(device_->lensDeg(), 30);
}

TEST_F(SdlGamepad, ContactForceDrivesTheLowMotorWithoutSpamming) {
  const double max_n = device_->info().max_force_n;
  pad_->clearRumbles();
  device_->commandForce({0, 0, 0.5 * max_n});
  ASSERT_EQ(pad_->rumbles().size(), 1u);
  EXPECT_EQ(pad_->lastRumble().low, rumbleFor(0.5 * max_n, max_n));
  EXPECT_EQ(pad_->lastRumble().high, 0);
  // A change below kRumbleStep is not sent; a larger one is.
  device_->commandForce({0, 0.005 * max_n, 0.5 * max_n});
  EXPECT_EQ(pad_->rumbles().size(), 1u);
  device_->commandForce({0.3 * max_n, 0, 0.4 * max_n});  // |F| = 0.5 max: the same level
  EXPECT_EQ(pad_->rumbles().size(), 1u);
  device_->commandForce({0, 0, -0.75 * max_n});  // the direction does not matter to a motor
  ASSERT_EQ(pad_->rumbles().size(), 2u);
  EXPECT_EQ(pad_->lastRumble().low, rumbleFor(0.75 * max_n, max_n));
  // Above the device's maximum: clamped, full motor.
  device_->commandForce({0, 0, 10 * max_n});
  EXPECT_NEAR(device_->lastForce().norm(), max_n, 1e-12);
  EXPECT_EQ(pad_->lastRumble().low, 0xFFFF);
  // Contact lost: the motor stops at once, even from a small level.
  device_->commandForce({0, 0, 0.02 * max_n});
  device_->commandForce({0, 0, 0});
  EXPECT_EQ(pad_->lastRumble().low, 0);
  EXPECT_EQ(pad_->lastRumble().high, 0);
  // A NaN never reaches a motor.
  device_->commandForce({std::nan(""), 0, 0});
  EXPECT_EQ(device_->lastForce(), Eigen::Vector3d::Zero());
  EXPECT_EQ(pad_->lastRumble().low, 0);
}

TEST_F(SdlGamepad, NearTheSerosaTheHighMotorPulsesOnReadTime) {
  const double max_n = device_->info().max_force_n;
  device_->commandForce({0, 0, 0.25 * max_n});
  device_->setSerosaWarning(true);
  // On for the first 100 ms of every 200 ms.
  for (double t : {1.05, 1.25, 1.45}) {
    device_->read(t);
    EXPECT_EQ(pad_->lastRumble().high, SdlGamepadDevice::kSerosaPulse) << t;
    EXPECT_EQ(pad_->lastRumble().low, rumbleFor(0.25 * max_n, max_n)) << t;  // the force cue goes on
  }
  for (double t : {1.15, 1.35, 1.55}) {
    device_->read(t);
    EXPECT_EQ(pad_->lastRumble().high, 0) << t;
    EXPECT_EQ(pad_->lastRumble().low, rumbleFor(0.25 * max_n, max_n)) << t;
  }
  device_->read(1.65);
  EXPECT_EQ(pad_->lastRumble().high, SdlGamepadDevice::kSerosaPulse);
  device_->setSerosaWarning(false);
  device_->read(1.66);
  EXPECT_EQ(pad_->lastRumble().high, 0);
}

TEST_F(SdlGamepad, UnplugFreezesTheToolZeroesTheForceAndReplugResumes) {
  const double gain = device_->mapping().advance.gain;
  pad_->setStick(pad::kLeftY, -1.0);
  pad_->setButton(pad::kRightShoulder, true);
  device_->read(0.0);
  DeviceState s = device_->read(1.0);
  ASSERT_NEAR(s.pose.tip.z(), gain, 1e-9);
  ASSERT_TRUE(s.pose.pedal);
  device_->commandForce({0, 0, 1.0});

  ASSERT_TRUE(pad_->unplug().ok());
  s = device_->read(1.5);
  EXPECT_FALSE(device_->connected());
  EXPECT_EQ(device_->counters().disconnects, 1);
  EXPECT_EQ(device_->counters().reconnects, 0);
  EXPECT_FALSE(s.pose.pedal);  // the pedal lets go
  EXPECT_EQ(s.buttons, 0u);
  EXPECT_EQ(s.velocity_mm_s, Eigen::Vector3d::Zero());
  EXPECT_EQ(device_->lastForce(), Eigen::Vector3d::Zero());
  // While unplugged the tool stays where it was last seen (the stick was still pushed) and no
  // force is kept.
  EXPECT_NEAR(s.pose.tip.z(), gain, 1e-9);
  s = device_->read(3.0);
  EXPECT_NEAR(s.pose.tip.z(), gain, 1e-9);
  device_->commandForce({0, 0, 2.0});
  EXPECT_EQ(device_->lastForce(), Eigen::Vector3d::Zero());
  const double frozen_z = s.pose.tip.z();
  EXPECT_NEAR(device_->read(4.0).pose.tip.z(), frozen_z, 1e-12);

  // Plugged in again, stick and pedal still held: the tool moves on from where it froze, but
  // the held pedal does not cut until it was let go once.
  ASSERT_TRUE(pad_->plugIn().ok());
  s = device_->read(4.0);
  EXPECT_TRUE(device_->connected());
  EXPECT_EQ(device_->counters().reconnects, 1);
  EXPECT_EQ(device_->counters().disconnects, 1);
  EXPECT_FALSE(s.pose.pedal);
  s = device_->read(4.5);
  EXPECT_NEAR(s.pose.tip.z(), frozen_z + 0.5 * gain, 1e-9);
  pad_->setButton(pad::kRightShoulder, false);
  EXPECT_FALSE(device_->read(4.6).pose.pedal);
  pad_->setButton(pad::kRightShoulder, true);
  EXPECT_TRUE(device_->read(4.7).pose.pedal);
  // The force cue works again on the new connection.
  const double max_n = device_->info().max_force_n;
  device_->commandForce({0, 0, 0.5 * max_n});
  EXPECT_EQ(pad_->lastRumble().low, rumbleFor(0.5 * max_n, max_n));
}

TEST_F(SdlGamepad, UnplugTwiceCountsTwice) {
  for (int i = 0; i < 2; ++i) {
    ASSERT_TRUE(pad_->unplug().ok());
    device_->read(1.0 + i);
    EXPECT_FALSE(device_->connected());
    ASSERT_TRUE(pad_->plugIn().ok());
    device_->read(1.5 + i);
    EXPECT_TRUE(device_->connected());
  }
  EXPECT_EQ(device_->counters().disconnects, 2);
  EXPECT_EQ(device_->counters().reconnects, 2);
}

TEST_F(SdlGamepad, ClosingTheDeviceStopsTheMotors) {
  device_->commandForce({0, 0, 1.0});
  ASSERT_NE(pad_->lastRumble().low, 0);
  device_.reset();
  EXPECT_EQ(pad_->lastRumble().low, 0);
  EXPECT_EQ(pad_->lastRumble().high, 0);
}

// The same pad read as a raw joystick when the mapping says so, with a mapping's own gain.
TEST(SdlGamepadRaw, JoystickLayoutMappingReadsRawAxesWithItsGain) {
  auto pad = VirtualPad::attach("hysim raw pad");
  ASSERT_TRUE(pad.ok()) << "SDL's virtual joystick is needed for this test: " << pad.error();
  auto mapping = parseGamepadMapping("layout: joystick\nadvance: { gain: 20 }\n", "raw.yaml");
  ASSERT_TRUE(mapping.ok()) << mapping.error();
  SdlGamepadOptions options;
  options.device_index = (*pad)->deviceIndex();
  options.mapping = *mapping;
  auto device = SdlGamepadDevice::open(ToolPose{}, 0.0, options);
  ASSERT_TRUE(device.ok()) << device.error();
  EXPECT_FALSE((*device)->isController());
  EXPECT_EQ((*device)->mapping().advance.gain, 20.0);
  (*pad)->setStick(1, -1.0);  // raw axis 1, up
  (*pad)->setButton(0, true); // raw button 0: the pedal
  (*device)->read(0.0);
  const DeviceState s = (*device)->read(0.5);
  EXPECT_NEAR(s.pose.tip.z(), 10.0, 1e-9);
  EXPECT_TRUE(s.pose.pedal);
  device->reset();
}

TEST(SdlGamepadOpen, NoPadAtTheIndexIsAnError) {
  SdlGamepadOptions options;
  options.device_index = 57;
  auto device = SdlGamepadDevice::open(ToolPose{}, 0.0, options);
  ASSERT_FALSE(device.ok());
  EXPECT_NE(device.error().find("57"), std::string::npos) << device.error();
}

}  // namespace
}  // namespace hysim::haptics
