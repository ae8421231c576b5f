#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "haptics_test_util.hpp"
#include "hysim/haptics/haptic_loop.hpp"

namespace hysim::haptics {
namespace {

// Only counts are checked: wall-clock bounds are not reliable on a loaded CI machine.
TEST(HapticThread, RunsTicksWhileOtherThreadsTalkToIt) {
  HapticLoop loop(test::standingDevice({4, 5, 6}));
  loop.start();
  EXPECT_TRUE(loop.running());
  LocalForceModel m;
  DeviceState state;
  long reads = 0;
  const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(100);
  for (std::int64_t step = 0; std::chrono::steady_clock::now() < until; ++step) {
    m.step = step;
    m.f0_n = {0.01, 0, 0};
    loop.publishModel(m);
    if (loop.latestState(state)) {
      ++reads;
      EXPECT_EQ(state.pose.tip, Eigen::Vector3d(4, 5, 6));
    }
    (void)loop.stats();
    (void)loop.safetyState();
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  loop.stop();
  EXPECT_FALSE(loop.running());
  const HapticStats s = loop.stats();
  EXPECT_GT(s.ticks, 10);
  EXPECT_GT(reads, 0);
  EXPECT_GT(s.period_max_us, 0.0);
  EXPECT_EQ(s.faults, 0);
  loop.stop();  // twice is harmless
}

TEST(HapticThread, RestartsAndStopsOnDestruction) {
  auto loop = std::make_unique<HapticLoop>(test::standingDevice());
  loop->start();
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  loop->stop();
  const long first = loop->stats().ticks;
  EXPECT_GT(first, 0);
  loop->start();
  loop->start();  // already running: no second thread
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  loop->eStop();
  loop.reset();  // joins the running thread
}

TEST(HapticThread, EStopFromAnotherThreadTakesEffect) {
  HapticLoop loop(test::standingDevice());
  loop.start();
  loop.eStop();
  for (int i = 0; i < 5000 && loop.safetyState() != SafetyState::EStopped; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  loop.stop();
  EXPECT_EQ(loop.safetyState(), SafetyState::EStopped);
  EXPECT_TRUE(loop.device().lastForce().isZero());
}

}  // namespace
}  // namespace hysim::haptics
