#pragma once
// The instructor's assessment of a resection (a scene's `assessment:` section, schema in
// scenes/README.md): thresholds a trainee must meet to pass and weights that turn the
// outcome into a score from 0 to 100.
#include <string>
#include <vector>

namespace hysim::engine {

struct AssessmentWeights {
  double resection = 0.4;  // how much of the myoma came out
  double healthy = 0.2;    // how little healthy tissue did
  double safety = 0.3;     // no more perforations than allowed
  double time = 0.1;       // within the time limit
};

struct AssessmentSettings {
  double min_resected_pct = 80.0;          // of the myoma's volume
  double max_healthy_removed_mm3 = 500.0;  // healthy tissue (every non-myoma material)
  int perforations_allowed = 0;
  double time_limit_s = 600.0;
  AssessmentWeights weights;
};

// What a session or run achieved, in the assessment's terms.
struct AssessedOutcome {
  double myoma_resected_pct = 0.0;
  double healthy_removed_mm3 = 0.0;
  int perforations = 0;
  double duration_s = 0.0;
};

// One threshold: the value against it, whether it is met, and its part of the score.
struct AssessmentItem {
  std::string name;       // resection, healthy, safety, time
  std::string unit;       // %, mm3, count, s
  double value = 0.0;
  double threshold = 0.0;
  bool at_least = false;  // the value must be >= threshold (else <=)
  bool passed = false;
  double score = 0.0;     // 0..1
  double weight = 0.0;
};

struct Assessment {
  double score = 0.0;  // 0..100: the weighted mean of the items' scores
  bool passed = false;  // every threshold met
  std::vector<AssessmentItem> items;
};

// Each item scores 1 when its threshold is met; short of it the resection scores the fraction
// reached, the healthy tissue and the time lose linearly to 0 at twice their limit, and a
// perforation beyond those allowed scores 0.
Assessment assess(const AssessmentSettings& settings, const AssessedOutcome& outcome);

// A few lines for people: score, pass or fail, each item against its threshold.
std::string assessmentText(const Assessment& assessment);

}  // namespace hysim::engine
