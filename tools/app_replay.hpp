#pragma once
// Plays a session's recording back in the window: a new simulation of the recorded scene,
// stepped on the recorded device states at real time, its scope view filling the window with
// the trainee's numbers over it. Nothing is recorded or stored.
#include <string>

#include "app_start_screen.hpp"
#include "hysim/render/imgui_layer.hpp"
#include "hysim/render/sdl_window.hpp"

namespace hysim::tools {

struct ReplayEnd {
  bool quit = false;    // the trainee quit the app (Esc, the window closed, or the exit ran out)
  std::string problem;  // why the recording could not be played ("" when it played)
};

// Runs until the trainee goes back (B or Backspace) or quits; Space pauses. The last state is
// held when the recording ends.
ReplayEnd runReplay(render::SdlWindow& window, render::ImGuiLayer& layer, const std::string& recording_path,
                    const StartScreenExit& exit);

}  // namespace hysim::tools
