#pragma once
// The start screen: the trainee's name, the cases (scenes/) with their FIGO type, difficulty
// and description, and how to play the chosen one (the scripted demo or hands-on).
#include <string>
#include <vector>

#include "app_cases.hpp"
#include "hysim/render/imgui_layer.hpp"
#include "hysim/render/sdl_window.hpp"

namespace hysim::tools {

struct StartChoice {
  bool quit = false;      // the trainee left (Esc, Quit, the window closed, or quit_after_s)
  bool progress = false;  // the trainee asked for the progress screen (P)
  int index = -1;         // the case started (or selected, with progress)
  bool hands_on = false;
  std::string trainee;
};

struct StartScreenExit {
  double quit_after_s = -1.0;  // leave after this much wall time (< 0: never)
  long frames = -1;            // leave after this many frames (< 0: never)
  std::string screenshot;      // PNG of the last frame when leaving that way
};

// Runs until a case is started, the progress screen is asked for or the trainee quits. Keys:
// Up/Down choose, Enter starts, H toggles hands-on, P progress, Esc quits. `last` is what the
// screen opens with: the trainee's name, and the case and mode chosen before (index -1: the first).
StartChoice runStartScreen(render::SdlWindow& window, render::ImGuiLayer& layer, const std::vector<CaseInfo>& cases,
                           const StartChoice& last, const StartScreenExit& exit);

}  // namespace hysim::tools
