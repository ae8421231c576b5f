// The default course's tolerant outcomes, against tests/data/golden/default_course.json: an
// unintended change of course fails here with a table of what moved, not only as a changed
// state hash. After an intended change, run
//   ./build/tools/hysim run scenes/default.yaml --report out/report.json
// and update the golden values from the report (passes, per_pass chips summed,
// myoma_resected_pct, healthy_removed_mm3, perforations, warnings, per_pass q_min's minimum,
// |volume_drift_mm3|, assessment.score).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "hysim/engine/run.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/simulation.hpp"

namespace hysim::engine {
namespace {

std::map<std::string, double> outcomes(const RunReport& r) {
  const RunSummary s = summarize(r);
  double q_min = 1.0;
  int chips = 0;
  for (const PassRecord& p : r.passes) {
    q_min = std::min(q_min, p.q_min);
    chips += p.chips;
  }
  return {{"passes", s.passes},
          {"chips", chips},
          {"myoma_resected_pct", s.myoma_resected_pct},
          {"healthy_removed_mm3", s.healthy_removed_mm3},
          {"perforations", s.perforations},
          {"warnings", r.warnings},
          {"q_min_over_passes", q_min},
          {"volume_drift_abs_mm3", std::abs(s.volume_drift_mm3)},
          {"assessment_score", s.assessment.score}};
}

// One line per golden entry: its rule, the run's value and whether it holds.
bool compare(const nlohmann::json& golden, const std::map<std::string, double>& now, std::string* table) {
  bool all = true;
  char line[200];
  for (const auto& [key, rule] : golden.items()) {
    if (!rule.is_object()) continue;
    const auto it = now.find(key);
    const double v = it == now.end() ? NAN : it->second;
    bool ok = false;
    std::string wanted;
    if (rule.contains("value")) {
      ok = std::abs(v - rule["value"].get<double>()) <= rule["abs"].get<double>();
      wanted = std::to_string(rule["value"].get<double>()) + " +- " + std::to_string(rule["abs"].get<double>());
    } else if (rule.contains("min")) {
      ok = v >= rule["min"].get<double>();
      wanted = ">= " + std::to_string(rule["min"].get<double>());
    } else {
      ok = v <= rule["max"].get<double>();
      wanted = "<= " + std::to_string(rule["max"].get<double>());
    }
    std::snprintf(line, sizeof(line), "%-22s %-28s %14.6g  %s\n", key.c_str(), wanted.c_str(), v, ok ? "ok" : "MOVED");
    *table += line;
    all = all && ok;
  }
  return all;
}

TEST(GoldenRun, DefaultCourseOutcomesStayPut) {
  std::ifstream in(std::string(HYSIM_TEST_DATA_DIR) + "/golden/default_course.json");
  ASSERT_TRUE(in) << "tests/data/golden/default_course.json ships with the repository";
  const nlohmann::json golden = nlohmann::json::parse(in);
  auto scene = loadScene(std::string(HYSIM_SOURCE_DIR) + "/scenes/default.yaml");
  ASSERT_TRUE(scene.ok()) << scene.error();
  auto sim = Simulation::create(*scene);
  ASSERT_TRUE(sim.ok()) << sim.error();
  auto report = run(**sim, RunOptions{});
  ASSERT_TRUE(report.ok()) << report.error();
  std::string table;
  const bool held = compare(golden, outcomes(*report), &table);
  EXPECT_TRUE(held) << "the default course moved (state_hash " << hashHex(report->state_hash) << "):\n" << table;
  std::printf("%s", table.c_str());
}

}  // namespace
}  // namespace hysim::engine
