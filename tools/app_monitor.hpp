#pragma once
// Watches a trainee's session step by step: raises the perforation alarm at the step the
// engine opens an event, and writes the session's events (pedal, passes, perforations, the
// scope stopped at the wall) to the session log. Outside the SDL loop, so tests drive it.
#include <cstddef>

#include "app_alarm.hpp"
#include "app_session_log.hpp"
#include "hysim/engine/simulation.hpp"

namespace hysim::tools {

class SessionMonitor {
 public:
  explicit SessionMonitor(SessionLog* log = nullptr) : log_(log) {}

  // After every step. True when this step raised the alarm.
  bool afterStep(const engine::Simulation& sim);
  // Once per frame: whether the keyboard scope was stopped at the wall (logged when it starts).
  void scopeLimited(bool limited, double time_s);
  const PerforationAlarm& alarm() const { return alarm_; }

 private:
  void logPedal(const engine::Simulation& sim);
  void logPasses(const engine::Simulation& sim);
  void logPerforation(const engine::Simulation& sim, bool raised);

  SessionLog* log_;
  PerforationAlarm alarm_;
  bool pedal_ = false;
  bool perforating_ = false;
  bool scope_limited_ = false;
  std::size_t passes_seen_ = 0;
};

// Steps up to `n` fixed steps, each watched by `monitor`; stops right after a step that raised
// the alarm, so the frame shows it at once. Returns the steps done.
int stepWatched(engine::Simulation& sim, SessionMonitor& monitor, int n);

}  // namespace hysim::tools
