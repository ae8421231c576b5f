#include "app_progress_data.hpp"

#include <algorithm>
#include <map>

namespace hysim::tools {

std::vector<SessionRecord> newestFirst(std::vector<SessionRecord> sessions) {
  std::stable_sort(sessions.begin(), sessions.end(), [](const SessionRecord& a, const SessionRecord& b) {
    if (a.started_utc != b.started_utc) return a.started_utc > b.started_utc;
    return a.id > b.id;
  });
  return sessions;
}

std::string sessionDate(const std::string& started_utc) {
  // ISO 8601 as the store writes it: date, 'T', hours and minutes (seconds and zone dropped).
  if (started_utc.size() < 16 || started_utc[10] != 'T') return started_utc;
  return started_utc.substr(0, 10) + " " + started_utc.substr(11, 5);
}

std::vector<CaseTrend> caseTrends(const std::vector<SessionRecord>& sessions) {
  std::vector<SessionRecord> oldest_first = newestFirst(sessions);
  std::reverse(oldest_first.begin(), oldest_first.end());
  std::map<std::string, CaseTrend> by_case;
  for (const SessionRecord& s : oldest_first) {
    CaseTrend& t = by_case[s.case_name];
    t.case_name = s.case_name;
    if (!s.complete) {
      ++t.incomplete;
      continue;
    }
    t.best = t.scores.empty() ? s.score : std::max(t.best, s.score);
    t.last = s.score;
    t.mean += s.score;  // a sum until divided below
    t.scores.push_back(static_cast<float>(s.score));
    t.passed += s.passed ? 1 : 0;
  }
  std::vector<CaseTrend> trends;
  for (auto& [name, t] : by_case) {
    if (!t.scores.empty()) t.mean /= static_cast<double>(t.scores.size());
    trends.push_back(std::move(t));
  }
  return trends;
}

}  // namespace hysim::tools
