#pragma once
// One trainee session: a simulation from the scene, its recording and event log, and the
// monitor that watches every step and raises the perforation alarm. A reset ends one session
// and starts the next.
#include <Eigen/Core>
#include <memory>
#include <string>

#include "app_beep.hpp"
#include "app_guidance_panel.hpp"
#include "app_monitor.hpp"
#include "app_recording.hpp"
#include "app_session_log.hpp"
#include "app_session_store.hpp"
#include "hysim/engine/simulation.hpp"
#include "hysim/haptics/pivot_device.hpp"

namespace hysim::tools {

struct Session {
  std::unique_ptr<engine::Simulation> sim;
  AppRecording recording;
  SessionLog log;
  std::unique_ptr<SessionMonitor> monitor;
  haptics::PivotScopeDevice* scope = nullptr;  // the keyboard scope, owned by sim while in use
  bool hands_on = false;                        // hands-on mode, or the trainee took the scope
  AppSessionStore* store = nullptr;             // where sessions are stored (not owned)
};

// A fresh simulation, recorded into `record_path` (empty: a new file in the recordings folder)
// with its event log beside the recording.
Status startSession(Session& s, const engine::Scene& scene, const std::string& record_path);
// Logs the session's totals and closes its log and recording.
void endSession(Session& s);
// After a frame's steps: what the trainee's guidance shows; the alarm's sound while it is on.
GuidanceView guidanceView(Session& s, AlarmSound& sound, Eigen::Matrix<double, Eigen::Dynamic, 3>& wire);

}  // namespace hysim::tools
