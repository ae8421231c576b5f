#include "run_session.hpp"

#include <filesystem>
#include <iostream>

namespace hysim::tools {

Status beginRunSession(const std::string& data_dir, const std::string& trainee, const std::string& mode,
                       const engine::Scene& scene, const std::string& recording, RunSession& session) {
  session.store = std::make_unique<SessionStore>(data_dir.empty() ? defaultDataFolder() : data_dir);
  if (Status st = session.store->open(); !st.ok()) std::cerr << "hysim: warning: " << st.error() << "\n";
  SessionRecord& r = session.record;
  r.trainee = trainee;
  r.case_name = scene.name;
  r.scene = scene.path;
  r.mode = mode;
  r.recording = recording;
  if (Status st = session.store->begin(r); !st.ok()) {
    std::error_code ec;
    if (r.file.empty() || !std::filesystem::exists(r.file, ec)) return st;
    std::cerr << "hysim: warning: " << st.error() << "\n";
  }
  return Status::Ok();
}

void finishRunSession(const engine::RunReport& report, RunSession& session) {
  if (!session.store) return;
  const engine::RunSummary s = engine::summarize(report);
  SessionRecord& r = session.record;
  r.duration_s = report.steps * report.dt;
  r.myoma_resected_pct = s.myoma_resected_pct;
  r.healthy_removed_mm3 = s.healthy_removed_mm3;
  r.perforations = s.perforations;
  r.electrode_active_s = s.electrode_active_s;
  r.passes = s.passes;
  r.score = s.assessment.score;
  r.passed = s.assessment.passed && !report.partial;  // a run stopped early passes nothing
  if (Status st = session.store->finish(r, !report.partial); !st.ok()) std::cerr << "hysim: " << st.error() << "\n";
}

}  // namespace hysim::tools
