#include "app_case_result.hpp"

namespace hysim::tools {

CaseResult caseResult(const Session& s, bool ended) {
  CaseResult r;
  r.ended = ended;
  if (!s.sim) return r;
  const engine::Simulation& sim = *s.sim;
  r.case_name = sim.scene().name;
  r.scene_path = sim.scene().path;
  r.hands_on = s.hands_on;
  r.numbers = guidanceNumbers(sim);
  r.assessment = engine::assess(sim.scene().assessment, assessedOutcome(r.numbers));
  r.timeline = passTimeline(sim.passes(), sim.initialMyomaVolume());
  r.recording = s.recording.path();
  r.recording_problem = s.recording.problem();
  return r;
}

}  // namespace hysim::tools
