// The trainee app's decisions outside the SDL loop: keys to pedal and scope rates, the free
// space in front of the tip and the depth limit, the course's pivot, the serosa bar's colours,
// the perforation alarm and the session log.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app_alarm.hpp"
#include "app_guidance.hpp"
#include "app_keys.hpp"
#include "app_scope_limits.hpp"
#include "app_session_log.hpp"
#include "test_dir.hpp"

namespace hysim::tools {
namespace {

TEST(TraineeKeys, EitherPedalKeyActivatesTheElectrode) {
  TraineeKeys keys;
  EXPECT_FALSE(pedalDown(keys));
  EXPECT_FALSE(pivotCommand(keys).pedal);
  keys.pedal_c = true;
  EXPECT_TRUE(pedalDown(keys));
  EXPECT_TRUE(pivotCommand(keys).pedal);
  keys = {};
  keys.pedal_shift = true;
  EXPECT_TRUE(pivotCommand(keys).pedal);
}

TEST(TraineeKeys, EachKeyDrivesItsMotion) {
  const KeyRates rates;
  TraineeKeys keys;
  keys.insert = true;
  EXPECT_DOUBLE_EQ(pivotCommand(keys).insert_mm_s, rates.insert_mm_s);
  keys.withdraw = true;  // both: nothing
  EXPECT_DOUBLE_EQ(pivotCommand(keys).insert_mm_s, 0.0);
  keys = {};
  keys.pivot_left = true;
  keys.pivot_up = true;
  keys.roll_right = true;
  keys.loop_out = true;
  const haptics::PivotCommand c = pivotCommand(keys);
  EXPECT_DOUBLE_EQ(c.yaw_rad_s, rates.pivot_rad_s);      // positive yaw: the view turns left
  EXPECT_DOUBLE_EQ(c.pitch_rad_s, -rates.pivot_rad_s);   // negative pitch: the view turns up
  EXPECT_DOUBLE_EQ(c.roll_rad_s, -rates.roll_rad_s);
  EXPECT_DOUBLE_EQ(c.extension_mm_s, rates.loop_mm_s);
  EXPECT_FALSE(c.pedal);
}

// An axis-aligned box surface [-10, 10]^3, triangles counter-clockwise seen from outside the
// tissue, i.e. from inside the box (the box is the cavity).
render::SurfaceMesh cavityBox() {
  render::SurfaceMesh m;
  for (int i = 0; i < 8; ++i) {
    m.positions.push_back((i & 1) ? 10.f : -10.f);
    m.positions.push_back((i & 2) ? 10.f : -10.f);
    m.positions.push_back((i & 4) ? 10.f : -10.f);
  }
  // Outward-from-the-box quads, then reversed so that normals point into the box.
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    for (const int t : {q[0], q[2], q[1], q[0], q[3], q[2]}) m.triangles.push_back(static_cast<std::uint32_t>(t));
  }
  return m;
}

TEST(ScopeLimits, FreeSpaceInFrontOfTheTipInsideAndOutsideTheTissue) {
  const render::SurfaceMesh box = cavityBox();
  EXPECT_NEAR(forwardFreeMm(box, Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 0, 1)), 10.0, 1e-9);
  EXPECT_NEAR(forwardFreeMm(box, Eigen::Vector3d(1, 2, -4), Eigen::Vector3d(1, 0, 0)), 9.0, 1e-9);
  // Beyond the wall the tip is in tissue: no room at all.
  EXPECT_DOUBLE_EQ(forwardFreeMm(box, Eigen::Vector3d(0, 0, 12), Eigen::Vector3d(0, 0, -1)), 0.0);
  EXPECT_TRUE(std::isinf(forwardFreeMm(box, Eigen::Vector3d(0, 0, 12), Eigen::Vector3d(0, 0, 1))));
}

TEST(ScopeLimits, DepthLimitKeepsTheClearanceAndNeverPullsBack) {
  EXPECT_DOUBLE_EQ(depthLimitMm(16.0, 10.0, 2.0), 24.0);
  EXPECT_DOUBLE_EQ(depthLimitMm(16.0, 1.0, 2.0), 16.0);
  EXPECT_TRUE(std::isinf(depthLimitMm(16.0, std::numeric_limits<double>::infinity(), 2.0)));
}

TEST(ScopeLimits, PivotOfACourseIsWhereItsShaftsMeet) {
  const Eigen::Vector3d pivot(1, -2, -32);
  std::vector<haptics::Keyframe> path;
  for (const Eigen::Vector3d& axis : {Eigen::Vector3d(0, 0.3, 1), Eigen::Vector3d(0.1, 0, 1), Eigen::Vector3d(-0.1, 0.1, 1)}) {
    haptics::Keyframe k;
    k.axis = axis.normalized();
    k.tip = pivot + 16.0 * k.axis;
    path.push_back(k);
  }
  EXPECT_LT((pivotOfPath(path) - pivot).norm(), 1e-9);
  path.resize(1);  // one shaft: no meeting point, 16 mm behind the tip
  EXPECT_LT((pivotOfPath(path) - pivot).norm(), 1e-9);
}

TEST(SerosaBar, GreenThenAmberThenRedAtTheMargins) {
  const double margin = 2.0;
  EXPECT_EQ(serosaBar(12.0, margin).level, SerosaLevel::Safe);
  EXPECT_DOUBLE_EQ(serosaBar(12.0, margin).fill, 1.0);
  EXPECT_EQ(serosaBar(4.0, margin).level, SerosaLevel::Safe);
  EXPECT_DOUBLE_EQ(serosaBar(4.0, margin).fill, 0.4);
  EXPECT_EQ(serosaBar(3.99, margin).level, SerosaLevel::Caution);
  EXPECT_EQ(serosaBar(2.0, margin).level, SerosaLevel::Caution);
  EXPECT_EQ(serosaBar(1.99, margin).level, SerosaLevel::Danger);
  EXPECT_EQ(serosaBar(-1.0, margin).level, SerosaLevel::Danger);
  EXPECT_DOUBLE_EQ(serosaBar(-1.0, margin).fill, 0.0);
  EXPECT_EQ(serosaBar(std::numeric_limits<double>::infinity(), margin).level, SerosaLevel::Safe);
}

TEST(PerforationAlarm, RaisedAtTheStepTheEventOpensAndHeldAfterIt) {
  PerforationAlarm alarm;
  EXPECT_FALSE(alarm.observe(0, false, 1.000));
  EXPECT_FALSE(alarm.active(1.000));
  EXPECT_TRUE(alarm.observe(1, true, 1.001));
  EXPECT_DOUBLE_EQ(alarm.raisedAtS(), 1.001);
  EXPECT_TRUE(alarm.active(1.001));
  EXPECT_FALSE(alarm.observe(1, true, 1.500));  // the same event: not raised again
  EXPECT_FALSE(alarm.observe(1, false, 1.501));
  EXPECT_TRUE(alarm.active(1.500 + PerforationAlarm::kHoldS));
  EXPECT_FALSE(alarm.active(1.501 + PerforationAlarm::kHoldS));
  EXPECT_TRUE(alarm.observe(2, true, 5.0));  // a second event
  EXPECT_EQ(alarm.raised(), 2);
}

TEST(SessionLog, OneJsonObjectPerLineNextToTheRecording) {
  EXPECT_EQ(sessionLogPath("/d/2026-11-29-default.hyrec"), "/d/2026-11-29-default.events.jsonl");
  EXPECT_EQ(sessionLogPath("/d/x.bin"), "/d/x.bin.events.jsonl");
  const std::string path = (hysim::testing::testDir("SessionLog") / "s.events.jsonl").string();
  SessionLog log;
  ASSERT_TRUE(log.open(path)) << log.problem();
  log.write(0.0, "session_start", {{"scene", "default"}});
  log.write(1.25, "perforation", {{"count", 1}});
  std::ifstream in(path);
  std::string line;
  std::vector<nlohmann::json> lines;
  while (std::getline(in, line)) lines.push_back(nlohmann::json::parse(line));
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[1]["event"], "perforation");
  EXPECT_DOUBLE_EQ(lines[1]["t_s"].get<double>(), 1.25);
  EXPECT_EQ(lines[1]["count"], 1);
  SessionLog bad;
  EXPECT_FALSE(bad.open("/nonexistent-folder/x.events.jsonl"));
  EXPECT_NE(bad.problem().find("cannot write"), std::string::npos);
}

}  // namespace
}  // namespace hysim::tools
