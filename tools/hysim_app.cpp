// hysim-app: the trainee window. The start screen (or the command line) picks a case; the case
// runs with its simulation on its own thread, paced to real time (app_case_loop.cpp), the
// hysteroscope view (SDL2 + OpenGL 3.3) and an ImGui panel with the trainee's guidance. Around
// the case: the start screen (and the progress screen from it) before, the debrief (and the
// session's replay) after, in turn until the trainee quits.
#include <CLI/CLI.hpp>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "app_case_loop.hpp"
#include "app_case_result.hpp"
#include "app_debrief.hpp"
#include "app_progress.hpp"
#include "app_replay.hpp"
#include "app_input_player.hpp"
#include "app_input_script.hpp"
#include "app_cases.hpp"
#include "app_start_screen.hpp"
#include "tool_common.hpp"
#include "hysim/render/imgui_layer.hpp"
#include "hysim/render/sdl_window.hpp"

namespace fs = std::filesystem;
using namespace hysim;

namespace {

int fail(const std::string& message) {
  std::cerr << "hysim-app: " << message << "\n";
  return 1;
}

struct AppArgs {
  std::string scene;
  int frames = -1;            // quit after this many frames (-1: never)
  double quit_after_s = -1.0; // quit after this much wall time (-1: never)
  std::string screenshot;     // PNG of the last frame, written on exit
  std::string alarm_screenshot;  // PNG of the first frame that shows the perforation alarm
  int width = 1024;
  int height = 768;
  bool no_vsync = false;
  bool paused = false;
  tools::GamepadArgs gamepad;
  std::string record;  // the session's recording; empty: a new file in the recordings folder
  std::string trainee;   // whose sessions are stored; empty: $USER, else "trainee"
  std::string data_dir;  // the sessions' data folder; empty: the default
  std::string input;     // a scripted input file; empty: none
  double max_fps = 32.0;
};

Result<tools::AppWindow> openWindow(const AppArgs& args) {
  render::SdlWindowOptions options;
  options.title = "hysim";
  options.width = args.width;
  options.height = args.height;
  options.vsync = !args.no_vsync;
  auto window = render::SdlWindow::create(options);
  if (!window.ok()) return Error{window.error()};
  auto layer = render::ImGuiLayer::create(**window);
  if (!layer.ok()) return Error{layer.error()};
  return tools::AppWindow{std::move(window.value()), std::move(layer.value())};
}

// Where the trainee is between screens: the start screen's choices, the case, its result.
struct AppFlow {
  std::vector<tools::CaseInfo> cases;
  tools::StartChoice choice;  // the trainee, the case and the mode
  std::string scene_path;
  std::string record;         // --record, for the first case only (later ones get new files)
  tools::CaseResult result;
  std::string message;        // for the debrief: why the replay could not play
  tools::InputPlayer* input = nullptr;  // scripted input (--input); null: none
};

// Scripted input's clocks for the screens start when they first open.
void entering(const AppFlow& flow, const char* screen) {
  if (flow.input != nullptr) flow.input->enterScreen(screen);
}

enum class Next { Start, Case, Debrief, Quit };

tools::StartScreenExit screenExit(const AppArgs& args) { return {args.quit_after_s, args.frames, args.screenshot}; }

// The start screen, and the progress screen from it, until a case is chosen or the trainee quits.
Next startScreen(const AppArgs& args, tools::AppWindow& w, AppFlow& flow) {
  if (flow.cases.empty()) {
    flow.cases = tools::listCases(fs::path(tools::defaultScenePath()).parent_path().string());
  }
  while (true) {
    entering(flow, "start");
    const tools::StartChoice c = tools::runStartScreen(*w.window, *w.layer, flow.cases, flow.choice, screenExit(args));
    if (!c.trainee.empty()) flow.choice.trainee = c.trainee;
    flow.choice.index = c.index;
    flow.choice.hands_on = c.hands_on;
    if (c.quit) return Next::Quit;
    if (!c.progress) break;
    entering(flow, "progress");
    if (!tools::runProgress(*w.window, *w.layer, args.data_dir, flow.choice.trainee, screenExit(args))) {
      return Next::Quit;
    }
  }
  flow.scene_path = flow.cases[flow.choice.index].path;
  return Next::Case;
}

// The case's options from the command line and the start screen's choices.
tools::CaseOptions caseOptions(const AppArgs& args, const AppFlow& flow) {
  tools::CaseOptions options;
  options.frames = args.frames;
  options.quit_after_s = args.quit_after_s;
  options.screenshot = args.screenshot;
  options.alarm_screenshot = args.alarm_screenshot;
  options.paused = args.paused;
  options.gamepad = args.gamepad;
  options.record = flow.record;
  options.trainee = flow.choice.trainee;
  options.data_dir = args.data_dir;
  options.hands_on = flow.choice.hands_on;
  options.max_fps = args.max_fps;
  options.input = flow.input;
  return options;
}

Next playCase(const AppArgs& args, tools::AppWindow& w, AppFlow& flow, int& rc) {
  const tools::CaseOptions options = caseOptions(args, flow);
  flow.record.clear();  // a second case must not overwrite the first one's recording
  flow.result = {};
  flow.message.clear();
  rc = tools::runCase(options, flow.scene_path, w, flow.result);
  return rc == 0 && flow.result.ended ? Next::Debrief : Next::Quit;
}

// The debrief, and the replay from it, until the trainee restarts, goes back or quits.
Next debrief(const AppArgs& args, tools::AppWindow& w, AppFlow& flow) {
  while (true) {
    entering(flow, "debrief");
    switch (tools::runDebrief(*w.window, *w.layer, flow.result, flow.message, screenExit(args))) {
      case tools::DebriefAction::Restart: return Next::Case;
      case tools::DebriefAction::Cases: return Next::Start;
      case tools::DebriefAction::Quit: return Next::Quit;
      case tools::DebriefAction::Replay: break;
    }
    entering(flow, "replay");
    const tools::ReplayEnd end = tools::runReplay(*w.window, *w.layer, flow.result.recording, screenExit(args));
    if (end.quit) return Next::Quit;
    flow.message = end.problem;
    if (!end.problem.empty()) std::printf("hysim-app: %s\n", end.problem.c_str());
  }
}

// The screens in turn: a case given on the command line first, else the start screen; after a
// case its debrief, and from there the case again or the start screen, until the trainee quits.
int runApp(const AppArgs& args) {
  auto opened = openWindow(args);
  if (!opened.ok()) return fail(opened.error());
  tools::InputPlayer input;
  if (!args.input.empty()) {
    auto script = tools::loadInputScript(args.input);
    if (!script.ok()) return fail(script.error());
    if (Status s = input.start(std::move(script.value()), *opened->window); !s.ok()) return fail(s.error());
  }
  const char* user = std::getenv("USER");
  AppFlow flow;
  flow.input = args.input.empty() ? nullptr : &input;
  flow.choice.trainee = !args.trainee.empty() ? args.trainee : (user != nullptr ? user : "");
  flow.scene_path = args.scene;
  flow.record = args.record;
  Next next = args.scene.empty() ? Next::Start : Next::Case;
  int rc = 0;
  while (next != Next::Quit) {
    switch (next) {
      case Next::Start: next = startScreen(args, *opened, flow); break;
      case Next::Case: next = playCase(args, *opened, flow, rc); break;
      case Next::Debrief: next = debrief(args, *opened, flow); break;
      case Next::Quit: break;
    }
  }
  return rc;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"hysim-app: hysteroscopy training simulator window (SDL2 + ImGui)"};
  AppArgs args;
  app.add_option("scene", args.scene, "Scene file (default: scenes/default.yaml)")->check(CLI::ExistingFile);
  app.add_option("--frames", args.frames, "Quit after N frames")->check(tools::finiteRange(1, 1e9));
  app.add_option("--quit-after-s", args.quit_after_s, "Quit after S seconds of wall time")
      ->check(tools::finiteRange(0, 1e6));
  app.add_option("--screenshot", args.screenshot, "Save the last window frame as PNG on exit");
  app.add_option("--alarm-screenshot", args.alarm_screenshot,
                 "Save the first frame that shows the perforation alarm as PNG");
  app.add_option("--width", args.width, "Window width")->check(CLI::Range(320, 16384));
  app.add_option("--height", args.height, "Window height")->check(CLI::Range(240, 16384));
  app.add_flag("--no-vsync", args.no_vsync, "Do not wait for the display's refresh");
  app.add_flag("--paused", args.paused, "Start paused");
  app.add_flag("--gamepad", args.gamepad.force,
               "Drive the scope with a game controller (used by default when one is attached)");
  app.add_flag("--no-gamepad", args.gamepad.disable, "Keyboard only, even when a game controller is attached");
  app.add_option("--gamepad-mapping", args.gamepad.mapping_file,
                 "Game controller mapping file (YAML, see haptics/README.md); implies --gamepad")
      ->check(CLI::ExistingFile);
  app.add_flag("--virtual-pad", args.gamepad.virtual_pad,
               "Attach a software game controller (no input; shows the controller panel without a pad)");
  app.add_option("--trainee", args.trainee, "Store the sessions as this trainee's (default: $USER)");
  app.add_option("--data-dir", args.data_dir,
                 "The sessions' data folder (default: $HYSIM_DATA_DIR, $XDG_DATA_HOME/hysim or ~/.local/share/hysim)");
  app.add_option("--record", args.record,
                 "Record the session into this file (default: a new file in the recordings folder, "
                 "$HYSIM_DATA_DIR or ~/.local/share/hysim, /recordings)");
  app.add_option("--input", args.input,
                 "Play a scripted input file into the window (timed keys, text, captures; see render/README.md)");
  app.add_option("--max-fps", args.max_fps, "Draw at most this many frames per second (0: no limit)")
      ->capture_default_str()
      ->check(tools::finiteRange(0, 1000));
  CLI11_PARSE(app, argc, argv);
  return runApp(args);
}
