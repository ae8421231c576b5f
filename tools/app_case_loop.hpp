#pragma once
// One case in the trainee window, from its scene to the trainee leaving it: the sessions (a
// reset starts the next), the simulation stepped on its own thread (engine::SimThread), and
// the frame loop that draws the scope view, the panel and the alarm.
#include <memory>
#include <string>

#include "app_case_result.hpp"
#include "app_gamepad.hpp"
#include "app_input_player.hpp"
#include "hysim/render/imgui_layer.hpp"
#include "hysim/render/sdl_window.hpp"

namespace hysim::tools {

// The window and its ImGui layer, made before any scene: the start screen draws in them too.
struct AppWindow {
  std::unique_ptr<render::SdlWindow> window;
  std::unique_ptr<render::ImGuiLayer> layer;
};

struct CaseOptions {
  long frames = -1;              // leave after this many frames (-1: never)
  double quit_after_s = -1.0;    // leave after this much wall time (-1: never)
  std::string screenshot;        // PNG of the last frame, written on leaving
  std::string alarm_screenshot;  // PNG of the first frame that shows the perforation alarm
  bool paused = false;
  GamepadArgs gamepad;
  std::string record;    // the first session's recording; empty: a new file in the recordings folder
  std::string trainee;   // whose sessions are stored
  std::string data_dir;  // the sessions' data folder; empty: the default
  bool hands_on = false;
  // Frames per second at most (0: as many as the machine draws): a software GL would otherwise
  // draw as fast as it can and take the simulation thread's core.
  double max_fps = 32.0;
  InputPlayer* input = nullptr;  // scripted input, whose sim events the frame loop plays; null: none
};

// Runs the case until the trainee quits or ends it (Enter, or the panel's button: the debrief
// follows); `result` is what the debrief shows. Returns the process's exit status.
int runCase(const CaseOptions& options, const std::string& scene_path, AppWindow& w, CaseResult& result);

}  // namespace hysim::tools
