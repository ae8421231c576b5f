#include "app_debrief_data.hpp"

#include <algorithm>
#include <cstdio>

namespace hysim::tools {
namespace {

// The trainee's name of an assessment item and the unit its numbers are shown in.
struct ItemWords {
  const char* label;
  const char* unit;
  int decimals;
};

ItemWords wordsFor(const engine::AssessmentItem& item) {
  if (item.name == "resection") return {"myoma resected", "%", 1};
  if (item.name == "healthy") return {"healthy tissue removed", "mm3", 1};
  if (item.name == "safety") return {"perforations", "", 0};
  if (item.name == "time") return {"time", "s", 0};
  return {item.name.c_str(), item.unit.c_str(), 1};
}

std::string number(double v, int decimals, const char* unit) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f%s%s", decimals, v, unit[0] != '\0' ? " " : "", unit);
  return text;
}

}  // namespace

engine::AssessedOutcome assessedOutcome(const GuidanceNumbers& n) {
  return {n.myoma_resected_pct, n.healthy_removed_mm3, n.perforations, n.elapsed_s};
}

std::vector<DebriefRow> debriefRows(const engine::Assessment& a) {
  double weights = 0.0;
  for (const engine::AssessmentItem& i : a.items) weights += i.weight;
  std::vector<DebriefRow> rows;
  for (const engine::AssessmentItem& i : a.items) {
    const ItemWords w = wordsFor(i);
    DebriefRow r;
    r.label = w.label;
    r.value = number(i.value, w.decimals, w.unit);
    r.threshold = std::string(i.at_least ? "at least " : "at most ") + number(i.threshold, w.decimals, w.unit);
    r.met = i.passed;
    r.score_pct = 100.0 * i.score;
    r.weight_pct = weights > 0.0 ? 100.0 * i.weight / weights : 0.0;
    rows.push_back(std::move(r));
  }
  return rows;
}

PassTimeline passTimeline(const std::vector<engine::PassRecord>& passes, double initial_myoma_mm3) {
  PassTimeline t;
  double myoma = 0.0;
  for (const engine::PassRecord& p : passes) {
    myoma += p.removed_myoma_mm3;
    const double healthy = std::max(0.0, p.removed_mm3 - p.removed_myoma_mm3);
    t.time_s.push_back(static_cast<float>(p.time_s));
    t.resected_pct.push_back(initial_myoma_mm3 > 0.0 ? static_cast<float>(100.0 * myoma / initial_myoma_mm3) : 0.0f);
    t.healthy_mm3.push_back(static_cast<float>(healthy));
    t.max_healthy_mm3 = std::max(t.max_healthy_mm3, static_cast<float>(healthy));
  }
  return t;
}

float resectionPlotTop(const PassTimeline& t, double min_resected_pct) {
  const double last = t.resected_pct.empty() ? 0.0 : t.resected_pct.back();
  return static_cast<float>(std::clamp(1.1 * std::max(last, min_resected_pct), 1.0, 100.0));
}

}  // namespace hysim::tools
