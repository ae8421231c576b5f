#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <set>
#include <string>

#include "haptics_test_util.hpp"
#include "hysim/haptics/force_safety.hpp"

namespace hysim::haptics {
namespace {

using test::kMs;
constexpr std::int64_t kS = 1000 * kMs;
const Eigen::Vector3d kSmall(0.1, 0, 0);  // below the 0.2 N engage threshold
const Eigen::Vector3d kLarge(1, 0, 0);

// Feeds `n` small commands, one per millisecond from t_ns; returns the time after them.
std::int64_t feedSmall(ForceSafety& s, int n, std::int64_t t_ns) {
  for (int i = 0; i < n; ++i, t_ns += kMs) EXPECT_TRUE(s.filter(kSmall, t_ns).isZero());
  return t_ns;
}

TEST(ForceSafety, WaitsForThreeConsecutiveSmallTicks) {
  ForceSafety s;
  EXPECT_EQ(s.state(), SafetyState::WaitingForSmall);
  EXPECT_TRUE(s.filter(kLarge, 0).isZero());
  feedSmall(s, 2, kMs);
  EXPECT_TRUE(s.filter(kLarge, 3 * kMs).isZero());  // a large one restarts the count
  feedSmall(s, 2, 4 * kMs);
  EXPECT_EQ(s.state(), SafetyState::WaitingForSmall);
  EXPECT_TRUE(s.filter(kSmall, 6 * kMs).isZero());  // third in a row: ramp starts from zero
  EXPECT_EQ(s.state(), SafetyState::Ramping);
}

TEST(ForceSafety, RampsLinearlyThenEngages) {
  ForceSafety s;
  const std::int64_t start = feedSmall(s, 3, 0) - kMs;  // the ramp starts at the third tick
  ASSERT_EQ(s.state(), SafetyState::Ramping);
  EXPECT_NEAR(s.filter(kLarge, start + kS / 4).x(), 0.25, 1e-12);
  EXPECT_NEAR(s.filter(kLarge, start + kS / 2).x(), 0.5, 1e-12);
  EXPECT_EQ(s.state(), SafetyState::Ramping);
  EXPECT_NEAR(s.filter(kLarge, start + kS).x(), 1.0, 1e-12);
  EXPECT_EQ(s.state(), SafetyState::Engaged);
  EXPECT_EQ(s.filter(Eigen::Vector3d(0, 2, 0), start + 2 * kS), Eigen::Vector3d(0, 2, 0));
}

TEST(ForceSafety, ZeroRampEngagesAtOnce) {
  ForceSafetyOptions o;
  o.ramp_s = 0.0;
  ForceSafety s(o);
  feedSmall(s, 3, 0);
  EXPECT_EQ(s.state(), SafetyState::Engaged);
  EXPECT_EQ(s.filter(kLarge, 3 * kMs), kLarge);
}

TEST(ForceSafety, ClampsMagnitudeKeepingDirection) {
  ForceSafetyOptions o;
  o.max_force_n = 2.0;
  ForceSafety s(o);
  const std::int64_t start = feedSmall(s, 3, 0) - kMs;
  const Eigen::Vector3d huge(30, 40, 0);
  const Eigen::Vector3d ramping = s.filter(huge, start + kS / 2);  // 25 N, clamped to 2
  EXPECT_NEAR(ramping.norm(), 2.0, 1e-12);
  EXPECT_TRUE(ramping.normalized().isApprox(huge.normalized()));
  const Eigen::Vector3d engaged = s.filter(huge, start + 2 * kS);
  EXPECT_NEAR(engaged.norm(), 2.0, 1e-12);
  EXPECT_TRUE(engaged.normalized().isApprox(huge.normalized()));
  EXPECT_EQ(s.ticksClamped(), 2);
}

TEST(ForceSafety, NonFiniteCommandLatchesAFault) {
  ForceSafety s;
  feedSmall(s, 3, 0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(s.filter(Eigen::Vector3d(nan, 0, 0), 2 * kS).isZero());
  EXPECT_EQ(s.state(), SafetyState::Fault);
  EXPECT_EQ(s.faultReason(), FaultReason::NonFiniteCommand);
  EXPECT_TRUE(s.filter(kSmall, 3 * kS).isZero());  // latched
  EXPECT_TRUE(s.filter(kLarge, 4 * kS).isZero());
  EXPECT_EQ(s.faults(), 1);
  s.reset();
  EXPECT_EQ(s.state(), SafetyState::WaitingForSmall);
  EXPECT_EQ(s.faultReason(), FaultReason::None);
  EXPECT_EQ(s.faults(), 1);  // counters survive a reset
}

TEST(ForceSafety, InfiniteCommandFaultsEvenWhileWaiting) {
  ForceSafety s;
  EXPECT_TRUE(s.filter(Eigen::Vector3d(0, std::numeric_limits<double>::infinity(), 0), 0).isZero());
  EXPECT_EQ(s.state(), SafetyState::Fault);
}

TEST(ForceSafety, EStopLatchesUntilReset) {
  ForceSafety s;
  const std::int64_t start = feedSmall(s, 3, 0) - kMs;
  EXPECT_NEAR(s.filter(kLarge, start + 2 * kS).x(), 1.0, 1e-12);
  s.eStop();
  EXPECT_EQ(s.state(), SafetyState::EStopped);
  EXPECT_TRUE(s.filter(kLarge, start + 3 * kS).isZero());
  EXPECT_TRUE(s.filter(kSmall, start + 4 * kS).isZero());  // small commands don't re-engage
  EXPECT_EQ(s.state(), SafetyState::EStopped);
  s.reset();
  EXPECT_EQ(s.state(), SafetyState::WaitingForSmall);
  EXPECT_TRUE(s.filter(kLarge, start + 5 * kS).isZero());  // and the engage sequence again
}

TEST(ForceSafety, EStopOverridesAFault) {
  ForceSafety s;
  s.filter(Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0, 0), 0);
  s.eStop();
  EXPECT_EQ(s.state(), SafetyState::EStopped);
  EXPECT_TRUE(s.filter(kSmall, kMs).isZero());
}

TEST(ForceSafety, NamesForTheApp) {
  std::set<std::string> names;
  for (SafetyState st : {SafetyState::WaitingForSmall, SafetyState::Ramping, SafetyState::Engaged, SafetyState::Fault,
                         SafetyState::EStopped}) {
    names.insert(safetyStateName(st));
  }
  EXPECT_EQ(names.size(), 5u);
  EXPECT_STRNE(faultReasonName(FaultReason::None), faultReasonName(FaultReason::NonFiniteCommand));
}

}  // namespace
}  // namespace hysim::haptics
