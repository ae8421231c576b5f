#pragma once
// The debrief after a case: the score and PASS or FAIL, each metric against the scene's
// threshold, the per-pass timeline as plots, and what comes next: replay the session, restart
// the case, back to the cases, or quit. Every button has its key, shown on it.
#include <string>

#include "app_case_result.hpp"
#include "app_start_screen.hpp"
#include "hysim/render/imgui_layer.hpp"
#include "hysim/render/sdl_window.hpp"

namespace hysim::tools {

enum class DebriefAction { Replay, Restart, Cases, Quit };

// Runs until the trainee chooses (keys: P replay, R restart, C cases, Esc quit; the window
// closed or the exit's time or frames ran out: Quit). `message` (e.g. why a replay could not
// play) is shown above the buttons.
DebriefAction runDebrief(render::SdlWindow& window, render::ImGuiLayer& layer, const CaseResult& result,
                         const std::string& message, const StartScreenExit& exit);

}  // namespace hysim::tools
