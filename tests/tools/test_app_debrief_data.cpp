// The debrief's and the progress screen's numbers, prepared apart from ImGui: the assessment's
// rows, the per-pass timeline, the sessions newest first and the per-case score trends.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "app_debrief_data.hpp"
#include "app_progress_data.hpp"

namespace hysim::tools {
namespace {

TEST(DebriefRows, EachItemAgainstItsThreshold) {
  engine::AssessmentSettings settings;  // 80 %, 500 mm3, 0 perforations, 600 s; weights 4:2:3:1
  const engine::Assessment a = engine::assess(settings, {85.0, 600.0, 1, 120.0});
  const std::vector<DebriefRow> rows = debriefRows(a);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0].label, "myoma resected");
  EXPECT_EQ(rows[0].value, "85.0 %");
  EXPECT_EQ(rows[0].threshold, "at least 80.0 %");
  EXPECT_TRUE(rows[0].met);
  EXPECT_DOUBLE_EQ(rows[0].score_pct, 100.0);
  EXPECT_DOUBLE_EQ(rows[0].weight_pct, 40.0);
  EXPECT_EQ(rows[1].label, "healthy tissue removed");
  EXPECT_EQ(rows[1].value, "600.0 mm3");
  EXPECT_EQ(rows[1].threshold, "at most 500.0 mm3");
  EXPECT_FALSE(rows[1].met);
  EXPECT_DOUBLE_EQ(rows[1].score_pct, 80.0);  // 20 % over the limit of a linear loss to 0 at twice it
  EXPECT_EQ(rows[2].label, "perforations");
  EXPECT_EQ(rows[2].value, "1");
  EXPECT_EQ(rows[2].threshold, "at most 0");
  EXPECT_FALSE(rows[2].met);
  EXPECT_DOUBLE_EQ(rows[2].score_pct, 0.0);
  EXPECT_EQ(rows[3].label, "time");
  EXPECT_EQ(rows[3].value, "120 s");
  EXPECT_EQ(rows[3].threshold, "at most 600 s");
  EXPECT_TRUE(rows[3].met);
  EXPECT_DOUBLE_EQ(rows[3].weight_pct, 10.0);
}

TEST(DebriefRows, TheOutcomeIsTheGuidanceNumbers) {
  GuidanceNumbers n;
  n.myoma_resected_pct = 42.0;
  n.healthy_removed_mm3 = 3.5;
  n.perforations = 2;
  n.elapsed_s = 61.0;
  const engine::AssessedOutcome o = assessedOutcome(n);
  EXPECT_DOUBLE_EQ(o.myoma_resected_pct, 42.0);
  EXPECT_DOUBLE_EQ(o.healthy_removed_mm3, 3.5);
  EXPECT_EQ(o.perforations, 2);
  EXPECT_DOUBLE_EQ(o.duration_s, 61.0);
}

engine::PassRecord pass(double time_s, double removed_mm3, double myoma_mm3) {
  engine::PassRecord p;
  p.time_s = time_s;
  p.removed_mm3 = removed_mm3;
  p.removed_myoma_mm3 = myoma_mm3;
  return p;
}

TEST(PassTimeline, CumulativeResectionAndHealthyPerPass) {
  const std::vector<engine::PassRecord> passes = {pass(1.5, 30.0, 25.0), pass(3.0, 50.0, 50.0),
                                                  pass(4.25, 12.0, 0.0)};
  const PassTimeline t = passTimeline(passes, 200.0);
  EXPECT_EQ(t.time_s, (std::vector<float>{1.5f, 3.0f, 4.25f}));
  EXPECT_EQ(t.resected_pct, (std::vector<float>{12.5f, 37.5f, 37.5f}));
  EXPECT_EQ(t.healthy_mm3, (std::vector<float>{5.0f, 0.0f, 12.0f}));
  EXPECT_FLOAT_EQ(t.max_healthy_mm3, 12.0f);
}

TEST(PassTimeline, ThePlotShowsTheThresholdAndSmallResections) {
  const PassTimeline t = passTimeline({pass(1.0, 10.0, 10.0), pass(2.0, 10.0, 10.0)}, 200.0);  // 10 %
  EXPECT_FLOAT_EQ(resectionPlotTop(t, 25.0), 27.5f);   // the threshold above the resection
  EXPECT_FLOAT_EQ(resectionPlotTop(t, 5.0), 11.0f);    // the resection above the threshold
  EXPECT_FLOAT_EQ(resectionPlotTop(t, 95.0), 100.0f);  // never beyond the whole myoma
  EXPECT_FLOAT_EQ(resectionPlotTop({}, 0.0), 1.0f);
}

TEST(PassTimeline, NoPassesAndNoMyoma) {
  EXPECT_TRUE(passTimeline({}, 100.0).resected_pct.empty());
  const PassTimeline t = passTimeline({pass(1.0, 8.0, 0.0)}, 0.0);  // a diagnostic scene: no myoma
  EXPECT_EQ(t.resected_pct, (std::vector<float>{0.0f}));
  EXPECT_EQ(t.healthy_mm3, (std::vector<float>{8.0f}));
}

SessionRecord session(long long id, const std::string& started, const std::string& case_name, bool complete,
                      double score, bool passed) {
  SessionRecord s;
  s.id = id;
  s.started_utc = started;
  s.case_name = case_name;
  s.complete = complete;
  s.score = score;
  s.passed = passed;
  return s;
}

std::vector<SessionRecord> someSessions() {  // oldest first, as SessionStore::list gives them
  return {session(1, "2026-11-28T09:00:00Z", "default", true, 50.0, false),
          session(2, "2026-11-28T09:30:00Z", "shaving", true, 90.0, true),
          session(3, "2026-11-29T10:00:00Z", "default", false, 0.0, false),  // killed
          session(4, "2026-11-29T10:00:00Z", "default", true, 70.0, false),
          session(5, "2026-11-29T11:00:00Z", "default", true, 100.0, true)};
}

TEST(Progress, NewestFirstByStartThenRow) {
  std::vector<long long> ids;
  for (const SessionRecord& s : newestFirst(someSessions())) ids.push_back(s.id);
  EXPECT_EQ(ids, (std::vector<long long>{5, 4, 3, 2, 1}));
}

TEST(Progress, DateForPeople) {
  EXPECT_EQ(sessionDate("2026-11-29T12:40:05Z"), "2026-11-29 12:40");
  EXPECT_EQ(sessionDate("yesterday"), "yesterday");
  EXPECT_EQ(sessionDate(""), "");
}

TEST(Progress, TrendsPerCaseOverCompleteSessions) {
  const std::vector<CaseTrend> trends = caseTrends(someSessions());
  ASSERT_EQ(trends.size(), 2u);
  const CaseTrend& d = trends[0];
  EXPECT_EQ(d.case_name, "default");
  EXPECT_EQ(d.scores, (std::vector<float>{50.0f, 70.0f, 100.0f}));  // the killed session has no score
  EXPECT_EQ(d.incomplete, 1);
  EXPECT_DOUBLE_EQ(d.best, 100.0);
  EXPECT_DOUBLE_EQ(d.last, 100.0);
  EXPECT_DOUBLE_EQ(d.mean, 220.0 / 3.0);
  EXPECT_EQ(d.passed, 1);
  const CaseTrend& s = trends[1];
  EXPECT_EQ(s.case_name, "shaving");
  EXPECT_EQ(s.scores, (std::vector<float>{90.0f}));
  EXPECT_DOUBLE_EQ(s.best, 90.0);
  EXPECT_DOUBLE_EQ(s.mean, 90.0);
  EXPECT_EQ(s.incomplete, 0);
}

TEST(Progress, OnlyIncompleteSessionsGiveNoScores) {
  const std::vector<CaseTrend> trends = caseTrends({session(1, "2026-11-29T10:00:00Z", "default", false, 0.0, false)});
  ASSERT_EQ(trends.size(), 1u);
  EXPECT_TRUE(trends[0].scores.empty());
  EXPECT_EQ(trends[0].incomplete, 1);
  EXPECT_DOUBLE_EQ(trends[0].best, 0.0);
  EXPECT_DOUBLE_EQ(trends[0].mean, 0.0);
  EXPECT_TRUE(caseTrends({}).empty());
}

}  // namespace
}  // namespace hysim::tools
