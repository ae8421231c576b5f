#include "hysim/engine/assessment.hpp"

#include <algorithm>
#include <cstdio>

namespace hysim::engine {
namespace {

// 1 at or below `limit`, falling linearly to 0 at twice the limit (at once for a zero limit).
double withinLimit(double value, double limit) {
  if (value <= limit) return 1.0;
  if (!(limit > 0.0)) return 0.0;
  return std::clamp(1.0 - (value - limit) / limit, 0.0, 1.0);
}

AssessmentItem item(const char* name, const char* unit, double value, double threshold, bool at_least, double score,
                    double weight) {
  AssessmentItem i;
  i.name = name;
  i.unit = unit;
  i.value = value;
  i.threshold = threshold;
  i.at_least = at_least;
  i.passed = at_least ? value >= threshold : value <= threshold;
  i.score = i.passed ? 1.0 : score;
  i.weight = weight;
  return i;
}

}  // namespace

Assessment assess(const AssessmentSettings& s, const AssessedOutcome& o) {
  Assessment a;
  const double resection = s.min_resected_pct > 0.0 ? std::clamp(o.myoma_resected_pct / s.min_resected_pct, 0.0, 1.0) : 1.0;
  a.items.push_back(item("resection", "%", o.myoma_resected_pct, s.min_resected_pct, true, resection, s.weights.resection));
  a.items.push_back(item("healthy", "mm3", o.healthy_removed_mm3, s.max_healthy_removed_mm3, false,
                         withinLimit(o.healthy_removed_mm3, s.max_healthy_removed_mm3), s.weights.healthy));
  a.items.push_back(item("safety", "count", o.perforations, s.perforations_allowed, false, 0.0, s.weights.safety));
  a.items.push_back(item("time", "s", o.duration_s, s.time_limit_s, false, withinLimit(o.duration_s, s.time_limit_s),
                         s.weights.time));
  double sum = 0.0, weights = 0.0;
  a.passed = true;
  for (const AssessmentItem& i : a.items) {
    sum += i.weight * i.score;
    weights += i.weight;
    a.passed = a.passed && i.passed;
  }
  a.score = weights > 0.0 ? 100.0 * sum / weights : 0.0;
  return a;
}

std::string assessmentText(const Assessment& a) {
  std::string text;
  char line[160];
  std::snprintf(line, sizeof(line), "assessment        %s, score %.0f of 100\n", a.passed ? "PASS" : "FAIL", a.score);
  text += line;
  for (const AssessmentItem& i : a.items) {
    std::snprintf(line, sizeof(line), "  %-10s %10.1f %-5s (%s %.1f) %s\n", i.name.c_str(), i.value, i.unit.c_str(),
                  i.at_least ? "at least" : "at most", i.threshold, i.passed ? "met" : "NOT met");
    text += line;
  }
  return text;
}

}  // namespace hysim::engine
