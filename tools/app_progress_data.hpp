#pragma once
// What the progress screen shows, prepared without ImGui so that tests check it: a trainee's
// stored sessions newest first, and per case the score's trend over the finished sessions
// (an incomplete session, killed or still running, has no score and is left out of trends).
#include <string>
#include <vector>

#include "session_store.hpp"

namespace hysim::tools {

// The sessions newest first (by start time, then by row id for sessions started in one second).
std::vector<SessionRecord> newestFirst(std::vector<SessionRecord> sessions);

// "2026-11-29 12:40" from "2026-11-29T12:40:05Z"; anything else is shown as it is.
std::string sessionDate(const std::string& started_utc);

struct CaseTrend {
  std::string case_name;
  std::vector<float> scores;  // the complete sessions', oldest first
  int incomplete = 0;         // sessions of the case that did not finish
  double best = 0.0, last = 0.0, mean = 0.0;  // of `scores` (0 when there is none)
  int passed = 0;             // complete sessions that passed
};
// One trend per case, by case name.
std::vector<CaseTrend> caseTrends(const std::vector<SessionRecord>& sessions);

}  // namespace hysim::tools
