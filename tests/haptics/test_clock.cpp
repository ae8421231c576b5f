#include <gtest/gtest.h>

#include "haptics_test_util.hpp"
#include "hysim/haptics/clock.hpp"

namespace hysim::haptics {
namespace {

using test::kMs;

TEST(FakeClock, SleepJumpsToTheTargetNeverBack) {
  FakeClock clock(5 * kMs);
  EXPECT_EQ(clock.nowNs(), 5 * kMs);
  clock.sleepUntilNs(8 * kMs);
  EXPECT_EQ(clock.nowNs(), 8 * kMs);
  clock.sleepUntilNs(6 * kMs);  // already past
  EXPECT_EQ(clock.nowNs(), 8 * kMs);
  clock.advanceNs(kMs);
  EXPECT_EQ(clock.nowNs(), 9 * kMs);
  clock.setNowNs(0);
  EXPECT_EQ(clock.nowNs(), 0);
  EXPECT_EQ(clock.sleeps(), 2);
}

TEST(FakeClock, InjectedLatenessHitsOneSleep) {
  FakeClock clock;
  clock.injectLatenessNs(3 * kMs, 1);  // the second sleep from now
  clock.sleepUntilNs(1 * kMs);
  EXPECT_EQ(clock.nowNs(), 1 * kMs);
  clock.sleepUntilNs(2 * kMs);
  EXPECT_EQ(clock.nowNs(), 5 * kMs);
  clock.sleepUntilNs(6 * kMs);
  EXPECT_EQ(clock.nowNs(), 6 * kMs);
}

TEST(SteadyClock, MonotonicAndNeverWakesEarly) {
  SteadyClock clock;
  const std::int64_t t0 = clock.nowNs();
  const std::int64_t target = t0 + 2 * kMs;
  clock.sleepUntilNs(target);
  EXPECT_GE(clock.nowNs(), target);
  clock.sleepUntilNs(t0);  // in the past: returns at once
  EXPECT_GE(clock.nowNs(), target);
}

}  // namespace
}  // namespace hysim::haptics
