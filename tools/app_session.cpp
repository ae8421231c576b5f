#include "app_session.hpp"

#include <cstdio>

#include "app_guidance.hpp"

namespace hysim::tools {

Status startSession(Session& s, const engine::Scene& scene, const std::string& record_path) {
  auto created = engine::Simulation::create(scene);
  if (!created.ok()) return Error{created.error()};
  s.sim = std::move(created.value());
  s.scope = nullptr;
  s.recording.start(scene, *s.sim, record_path);
  if (!s.recording.path().empty() && !s.log.open(sessionLogPath(s.recording.path()))) {
    std::printf("hysim-app: %s\n", s.log.problem().c_str());
  }
  s.monitor = std::make_unique<SessionMonitor>(&s.log);
  s.log.write(0.0, "session_start", {{"scene", scene.name}, {"recording", s.recording.path()}});
  if (s.store != nullptr) s.store->begin(scene, s.recording.path(), s.hands_on);
  return Status::Ok();
}

void endSession(Session& s) {
  if (!s.sim) return;
  const GuidanceNumbers g = guidanceNumbers(*s.sim);
  s.log.write(s.sim->state().time, "session_end",
              {{"myoma_resected_pct", g.myoma_resected_pct}, {"healthy_removed_mm3", g.healthy_removed_mm3},
               {"electrode_active_s", g.electrode_active_s}, {"chips", g.chips}, {"passes", g.passes},
               {"perforations", g.perforations}, {"alarms", s.monitor->alarm().raised()}});
  s.log.close();
  s.recording.finish();
  if (s.store != nullptr) s.store->finish(s.sim->scene(), g, s.hands_on);
}

GuidanceView guidanceView(Session& s, AlarmSound& sound, Eigen::Matrix<double, Eigen::Dynamic, 3>& wire) {
  GuidanceView v;
  const engine::Simulation& sim = *s.sim;
  v.numbers = guidanceNumbers(sim);
  v.serosa_mm = serosaDistanceMm(sim, wire);
  v.margin_mm = sim.scene().safety.perforation_margin_mm;
  v.cutting = sim.deviceState().pose.pedal;
  v.alarm = s.monitor->alarm().active(sim.state().time);
  v.scope_at_wall = s.scope != nullptr && (s.scope->depthLimited() || s.scope->sideLimited());
  s.monitor->scopeLimited(v.scope_at_wall, sim.state().time);
  if (v.alarm) sound.beep();
  return v;
}

}  // namespace hysim::tools
