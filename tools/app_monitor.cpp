#include "app_monitor.hpp"

namespace hysim::tools {

bool SessionMonitor::afterStep(const engine::Simulation& sim) {
  const bool raised = alarm_.observe(sim.perforations(), sim.perforating(), sim.state().time);
  if (log_ != nullptr) {
    logPedal(sim);
    logPasses(sim);
    logPerforation(sim, raised);
  }
  perforating_ = sim.perforating();
  return raised;
}

void SessionMonitor::scopeLimited(bool limited, double time_s) {
  if (limited && !scope_limited_ && log_ != nullptr) log_->write(time_s, "scope_at_wall");
  scope_limited_ = limited;
}

void SessionMonitor::logPedal(const engine::Simulation& sim) {
  const bool pedal = sim.deviceState().pose.pedal;
  if (pedal != pedal_) log_->write(sim.state().time, pedal ? "pedal_down" : "pedal_up");
  pedal_ = pedal;
}

void SessionMonitor::logPasses(const engine::Simulation& sim) {
  for (; passes_seen_ < sim.passes().size(); ++passes_seen_) {
    const engine::PassRecord& p = sim.passes()[passes_seen_];
    log_->write(sim.state().time, "pass",
                {{"pass", passes_seen_ + 1}, {"chips", p.chips}, {"myoma_mm3", p.removed_myoma_mm3},
                 {"healthy_mm3", p.removed_mm3 - p.removed_myoma_mm3}, {"cut_failed", p.cut_failed}});
  }
}

void SessionMonitor::logPerforation(const engine::Simulation& sim, bool raised) {
  if (raised) {
    log_->write(sim.state().time, "perforation",
                {{"count", sim.perforations()}, {"serosa_mm", sim.serosaClearanceMm()}});
  } else if (perforating_ && !sim.perforating()) {
    const auto& events = sim.perforationEvents();
    nlohmann::json details = nlohmann::json::object();
    if (!events.empty()) details["min_distance_mm"] = events.back().min_distance_mm;
    log_->write(sim.state().time, "perforation_end", details);
  }
}

int stepWatched(engine::Simulation& sim, SessionMonitor& monitor, int n) {
  for (int i = 0; i < n; ++i) {
    sim.step();
    if (monitor.afterStep(sim)) return i + 1;
  }
  return n;
}

}  // namespace hysim::tools
