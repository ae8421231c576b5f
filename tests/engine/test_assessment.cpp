// The assessment's score: exact cases for each item, the weights, and pass only when every
// threshold is met.
#include "hysim/engine/assessment.hpp"

#include <gtest/gtest.h>

namespace hysim::engine {
namespace {

AssessmentSettings settings() {
  AssessmentSettings s;
  s.min_resected_pct = 80.0;
  s.max_healthy_removed_mm3 = 500.0;
  s.perforations_allowed = 0;
  s.time_limit_s = 600.0;
  s.weights = {0.4, 0.2, 0.3, 0.1};
  return s;
}

const AssessmentItem& itemNamed(const Assessment& a, const std::string& name) {
  for (const AssessmentItem& i : a.items)
    if (i.name == name) return i;
  throw std::runtime_error("no item " + name);
}

TEST(Assessment, EveryThresholdMetScoresFullAndPasses) {
  const Assessment a = assess(settings(), {91.0, 338.0, 0, 96.7});
  EXPECT_TRUE(a.passed);
  EXPECT_DOUBLE_EQ(a.score, 100.0);
  ASSERT_EQ(a.items.size(), 4u);
  EXPECT_EQ(itemNamed(a, "resection").value, 91.0);
  EXPECT_TRUE(itemNamed(a, "resection").at_least);
  EXPECT_FALSE(itemNamed(a, "healthy").at_least);
}

TEST(Assessment, ShortOfEachThresholdScoresItsPart) {
  // Half the resection asked for, 1.5x the healthy and time limits, one perforation too many.
  const Assessment a = assess(settings(), {40.0, 750.0, 1, 900.0});
  EXPECT_FALSE(a.passed);
  EXPECT_DOUBLE_EQ(itemNamed(a, "resection").score, 0.5);
  EXPECT_DOUBLE_EQ(itemNamed(a, "healthy").score, 0.5);
  EXPECT_DOUBLE_EQ(itemNamed(a, "safety").score, 0.0);
  EXPECT_DOUBLE_EQ(itemNamed(a, "time").score, 0.5);
  for (const AssessmentItem& i : a.items) EXPECT_FALSE(i.passed) << i.name;
  EXPECT_NEAR(a.score, 100.0 * (0.4 * 0.5 + 0.2 * 0.5 + 0.3 * 0.0 + 0.1 * 0.5), 1e-12);
}

TEST(Assessment, OneMissedThresholdFailsWhateverTheScore) {
  const Assessment a = assess(settings(), {100.0, 0.0, 0, 601.0});
  EXPECT_FALSE(a.passed);
  EXPECT_GT(a.score, 99.0);
  EXPECT_FALSE(itemNamed(a, "time").passed);
}

TEST(Assessment, LimitsAndWeightsAtTheirEdges) {
  AssessmentSettings s = settings();
  s.max_healthy_removed_mm3 = 0.0;  // no healthy tissue at all: any scores 0
  s.perforations_allowed = 2;
  s.weights = {0.0, 1.0, 0.0, 0.0};  // only the healthy tissue counts
  Assessment a = assess(s, {10.0, 0.5, 2, 10.0});
  EXPECT_DOUBLE_EQ(itemNamed(a, "healthy").score, 0.0);
  EXPECT_TRUE(itemNamed(a, "safety").passed);
  EXPECT_DOUBLE_EQ(a.score, 0.0);
  a = assess(s, {10.0, 0.0, 3, 2000.0});  // twice the time limit and beyond scores 0
  EXPECT_DOUBLE_EQ(a.score, 100.0);
  EXPECT_FALSE(a.passed);
  EXPECT_DOUBLE_EQ(itemNamed(a, "time").score, 0.0);
  EXPECT_DOUBLE_EQ(itemNamed(a, "resection").score, 0.125);
}

TEST(Assessment, TextNamesEveryItemAndTheVerdict) {
  const std::string text = assessmentText(assess(settings(), {40.0, 750.0, 1, 900.0}));
  EXPECT_NE(text.find("FAIL"), std::string::npos) << text;
  for (const char* name : {"resection", "healthy", "safety", "time"}) EXPECT_NE(text.find(name), std::string::npos) << name;
  EXPECT_NE(text.find("NOT met"), std::string::npos);
}

}  // namespace
}  // namespace hysim::engine
