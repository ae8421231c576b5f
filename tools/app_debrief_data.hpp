#pragma once
// What the debrief screen shows, prepared without ImGui so that tests check the numbers: the
// assessment's items as rows (value against threshold, met or not) and the per-pass timeline
// (cumulative myoma resected and healthy tissue removed by each committed pass).
#include <string>
#include <vector>

#include "app_guidance.hpp"
#include "hysim/engine/assessment.hpp"
#include "hysim/engine/pass_record.hpp"

namespace hysim::tools {

// The session's numbers in the assessment's terms (the store scores sessions the same way).
engine::AssessedOutcome assessedOutcome(const GuidanceNumbers& numbers);

// One assessment item for people: "myoma resected", "85.0 %", "at least 80.0 %", met.
struct DebriefRow {
  std::string label;
  std::string value;
  std::string threshold;
  bool met = false;
  double score_pct = 0.0;   // the item's part score, 0..100
  double weight_pct = 0.0;  // its weight among all items', 0..100
};
std::vector<DebriefRow> debriefRows(const engine::Assessment& assessment);

// Per committed pass, in order: the myoma resected so far (% of the initial myoma; 0 when the
// scene has none) and the healthy tissue that pass removed (mm3, chips' volume less myoma).
struct PassTimeline {
  std::vector<float> time_s;
  std::vector<float> resected_pct;  // cumulative
  std::vector<float> healthy_mm3;   // per pass
  float max_healthy_mm3 = 0.0f;     // the largest pass's, for the plot's scale
};
PassTimeline passTimeline(const std::vector<engine::PassRecord>& passes, double initial_myoma_mm3);

// The top of the resection plot: a tenth above the threshold or the last value, whichever is
// higher (at most 100 %, at least 1 %), so that the bars read against the target rather than
// against the whole myoma.
float resectionPlotTop(const PassTimeline& timeline, double min_resected_pct);

}  // namespace hysim::tools
