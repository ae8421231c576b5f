#pragma once
// The progress screen: the trainee's stored sessions newest first (date, case, mode, complete
// or not, resected %, healthy tissue, perforations, score, pass) and per case the score's
// trend with its best, last and mean. A store that cannot be read is a message on the screen.
#include <string>

#include "app_start_screen.hpp"
#include "hysim/render/imgui_layer.hpp"
#include "hysim/render/sdl_window.hpp"

namespace hysim::tools {

// Runs until the trainee goes back (B or Backspace: true) or quits (Esc, the window closed, or
// the exit's time or frames ran out: false). `data_dir`: the sessions' folder (empty: the default).
bool runProgress(render::SdlWindow& window, render::ImGuiLayer& layer, const std::string& data_dir,
                 const std::string& trainee, const StartScreenExit& exit);

}  // namespace hysim::tools
