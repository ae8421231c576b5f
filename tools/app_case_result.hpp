#pragma once
// What a case leaves behind for the debrief when it ends: the session's numbers, the scene's
// assessment of them, the per-pass timeline and the recording to replay.
#include <string>

#include "app_debrief_data.hpp"
#include "app_session.hpp"
#include "hysim/engine/assessment.hpp"

namespace hysim::tools {

struct CaseResult {
  bool ended = false;  // the trainee ended the case (to the debrief) rather than quitting the app
  std::string case_name;
  std::string scene_path;
  bool hands_on = false;
  GuidanceNumbers numbers;
  engine::Assessment assessment;
  PassTimeline timeline;
  std::string recording;          // the session's recording (empty: none)
  std::string recording_problem;  // why there is none
};

// The result of the session `s` (after endSession: its recording is complete).
CaseResult caseResult(const Session& s, bool ended);

}  // namespace hysim::tools
