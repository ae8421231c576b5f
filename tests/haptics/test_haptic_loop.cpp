#include <gtest/gtest.h>

#include <limits>

#include "haptics_test_util.hpp"
#include "hysim/haptics/haptic_loop.hpp"

namespace hysim::haptics {
namespace {

using test::kMs;
constexpr std::int64_t kT0 = 5000 * kMs;  // the fake clock's start: any time works

HapticLoopOptions quickEngage() {
  HapticLoopOptions o;
  o.safety.ramp_s = 0.0;
  return o;
}

// A loop driven by explicit tick times; ticks 0..2 (no model) engage the safety.
struct Rig {
  explicit Rig(HapticLoopOptions options = quickEngage()) : loop(test::standingDevice(), clock, options) {}
  void tickAt(std::int64_t t_ns) { loop.tick(kT0 + t_ns); }
  void engage() {
    for (int i = 0; i < 3; ++i) tickAt(i * kMs);
    ASSERT_EQ(loop.safetyState(), SafetyState::Engaged);
  }
  Eigen::Vector3d force() { return loop.device().lastForce(); }

  FakeClock clock{kT0};
  HapticLoop loop;
};

LocalForceModel pushAndSpring(std::int64_t step) {
  LocalForceModel m;
  m.step = step;
  m.f0_n = {0.5, 0, 0};
  m.stiffness_n_per_mm = -0.1 * Eigen::Matrix3d::Identity();
  m.x_ref_mm = {0, 0, -2};  // the device stands at the origin: spring force (0, 0, -0.2)
  return m;
}

TEST(HapticLoop, PublishesDeviceStateWithDeviceTime) {
  HapticLoopOptions o;
  o.start_time_s = 2.0;
  FakeClock clock(kT0);
  HapticLoop loop(test::standingDevice({1, 2, 3}), clock, o);
  DeviceState state;
  EXPECT_FALSE(loop.latestState(state));
  loop.tick(kT0);
  loop.tick(kT0 + 250 * kMs);
  ASSERT_TRUE(loop.latestState(state));
  EXPECT_DOUBLE_EQ(state.time_s, 2.25);
  EXPECT_EQ(state.pose.tip, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(loop.stats().ticks, 2);
}

TEST(HapticLoop, ExactPeriodsGiveExactStatistics) {
  FakeClock clock(kT0);
  HapticLoop loop(test::standingDevice(), clock);
  loop.runTicks(1000);
  const HapticStats s = loop.stats();
  EXPECT_EQ(s.ticks, 1000);
  EXPECT_EQ(s.period_p50_us, 1000.0);
  EXPECT_EQ(s.period_p99_us, 1000.0);
  EXPECT_EQ(s.period_max_us, 1000.0);
  EXPECT_EQ(s.overruns, 0);
  EXPECT_EQ(s.resyncs, 0);
  EXPECT_EQ(clock.nowNs(), kT0 + 999 * kMs);  // absolute deadlines: no drift
}

TEST(HapticLoop, ShortOverrunIsCaughtUpOnSchedule) {
  FakeClock clock(kT0);
  HapticLoop loop(test::standingDevice(), clock);
  clock.injectLatenessNs(2 * kMs, 500);
  loop.runTicks(1000);
  const HapticStats s = loop.stats();
  EXPECT_EQ(s.ticks, 1000);
  EXPECT_EQ(s.overruns, 1);
  EXPECT_EQ(s.resyncs, 0);
  EXPECT_EQ(s.period_max_us, 3000.0);
  EXPECT_EQ(s.period_p50_us, 1000.0);
  EXPECT_EQ(clock.nowNs(), kT0 + 999 * kMs);  // the two missed slots were run back to back
}

TEST(HapticLoop, LongOverrunResynchronisesInsteadOfBursting) {
  FakeClock clock(kT0);
  HapticLoop loop(test::standingDevice(), clock);
  clock.injectLatenessNs(10 * kMs, 500);
  loop.runTicks(1000);
  const HapticStats s = loop.stats();
  EXPECT_EQ(s.overruns, 1);
  EXPECT_EQ(s.resyncs, 1);
  EXPECT_EQ(s.period_max_us, 11000.0);
  // One tick per slot after the jump: the last tick comes 10 ms after the nominal time.
  EXPECT_EQ(clock.nowNs(), kT0 + 1009 * kMs);
}

TEST(HapticLoop, NoForceWhenTheFirstCommandIsLarge) {
  Rig rig(HapticLoopOptions{});
  for (int i = 0; i < 100; ++i) {
    rig.loop.publishModel(pushAndSpring(i));  // |F| > 0.2 N from the start: no jolt
    rig.tickAt(i * kMs);
    ASSERT_TRUE(rig.force().isZero());
  }
  EXPECT_EQ(rig.loop.safetyState(), SafetyState::WaitingForSmall);
}

TEST(HapticLoop, RampsInThroughTheLoopAndClampsToTheDevice) {
  Rig rig(HapticLoopOptions{});  // 1 s ramp
  LocalForceModel m;
  m.f0_n = {0.1, 0, 0};
  for (int i = 0; i <= 502; ++i) {  // a new step every tick, as a running simulation does
    m.step = i;
    rig.loop.publishModel(m);
    rig.tickAt(i * kMs);
  }
  EXPECT_EQ(rig.loop.safetyState(), SafetyState::Ramping);  // the ramp started at tick 2
  EXPECT_NEAR(rig.force().x(), 0.05, 1e-12);
  m.f0_n = {0, 50, 0};
  for (int i = 503; i <= 1002; ++i) {
    m.step = i;
    rig.loop.publishModel(m);
    rig.tickAt(i * kMs);
  }
  EXPECT_EQ(rig.loop.safetyState(), SafetyState::Engaged);
  EXPECT_NEAR(rig.force().y(), 3.0, 1e-12);  // the device's max_force_n
  EXPECT_EQ(rig.loop.stats().ticks_clamped, 500);
}

TEST(HapticLoop, WatchdogFadesF0AndKeepsTheSpring) {
  Rig rig;
  rig.engage();
  rig.loop.publishModel(pushAndSpring(0));
  rig.tickAt(3 * kMs);
  const Eigen::Vector3d full(0.5, 0, -0.2), spring(0, 0, -0.2);
  EXPECT_TRUE(rig.force().isApprox(full));
  for (int i = 4; i <= 53; ++i) rig.tickAt(i * kMs);  // 50 ms of silence: still full
  EXPECT_TRUE(rig.force().isApprox(full));
  for (int i = 54; i <= 58; ++i) rig.tickAt(i * kMs);
  EXPECT_TRUE(rig.force().isApprox(Eigen::Vector3d(0.25, 0, -0.2)));
  for (int i = 59; i <= 63; ++i) rig.tickAt(i * kMs);  // 10 ms of fading: F0 gone
  EXPECT_EQ(rig.force(), spring);
  rig.loop.publishModel(pushAndSpring(0));  // the same step again is no sign of life
  rig.tickAt(64 * kMs);
  EXPECT_EQ(rig.force(), spring);
  rig.loop.publishModel(pushAndSpring(1));  // a new step brings F0 back within fade_s
  for (int i = 65; i <= 74; ++i) rig.tickAt(i * kMs);
  EXPECT_TRUE(rig.force().isApprox(full));
}

TEST(HapticLoop, NonFiniteModelLatchesAFaultAndZeroForce) {
  Rig rig;
  rig.engage();
  rig.loop.publishModel(pushAndSpring(0));
  rig.tickAt(3 * kMs);
  ASSERT_FALSE(rig.force().isZero());
  LocalForceModel bad = pushAndSpring(1);
  bad.f0_n.y() = std::numeric_limits<double>::quiet_NaN();
  rig.loop.publishModel(bad);
  rig.tickAt(4 * kMs);
  EXPECT_TRUE(rig.force().isZero());
  EXPECT_EQ(rig.loop.safetyState(), SafetyState::Fault);
  EXPECT_EQ(rig.loop.faultReason(), FaultReason::NonFiniteCommand);
  rig.loop.publishModel(pushAndSpring(2));  // a good model does not clear the fault
  rig.tickAt(5 * kMs);
  EXPECT_TRUE(rig.force().isZero());
  EXPECT_EQ(rig.loop.stats().faults, 1);
  rig.loop.resetSafety();
  rig.tickAt(6 * kMs);
  EXPECT_EQ(rig.loop.safetyState(), SafetyState::WaitingForSmall);
  EXPECT_EQ(rig.loop.faultReason(), FaultReason::None);
}

TEST(HapticLoop, EStopZeroesTheForceAtTheNextTick) {
  Rig rig;
  rig.engage();
  rig.loop.publishModel(pushAndSpring(0));
  rig.tickAt(3 * kMs);
  ASSERT_FALSE(rig.force().isZero());
  rig.loop.eStop();
  rig.tickAt(4 * kMs);
  EXPECT_TRUE(rig.force().isZero());
  EXPECT_EQ(rig.loop.safetyState(), SafetyState::EStopped);
  rig.loop.resetSafety();
  rig.tickAt(5 * kMs);
  EXPECT_EQ(rig.loop.safetyState(), SafetyState::WaitingForSmall);
}

TEST(HapticLoop, StiffModelsAreLimitedToTheDevice) {
  Rig rig;
  rig.engage();
  LocalForceModel m;
  m.step = 0;
  m.stiffness_n_per_mm = -10.0 * Eigen::Matrix3d::Identity();
  m.x_ref_mm = {-1, 0, 0};  // 1 mm displacement: 10 N asked, at most 1 N/mm * 1 mm allowed
  rig.loop.publishModel(m);
  rig.tickAt(3 * kMs);
  EXPECT_LT(rig.force().x(), 0.0);
  EXPECT_LE(rig.force().norm(), 1.0 + 1e-12);
}

}  // namespace
}  // namespace hysim::haptics
