// hysim-app: the trainee window. The start screen (or the command line) picks a case; the case
// runs with its simulation on its own thread, paced to real time (app_case_loop.cpp), the
// hysteroscope view (SDL2 + OpenGL 3.3) and an ImGui panel with the trainee's guidance.
#include <CLI/CLI.hpp>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "app_case_loop.hpp"
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
  double max_fps = 40.0;
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

// The scene to run: the command line's, else the case the trainee starts on the start screen
// (empty: the trainee quit there). The start screen also sets the mode and the trainee's name.
std::string chooseScene(const AppArgs& args, tools::AppWindow& w, bool& hands_on, std::string& trainee) {
  if (!args.scene.empty()) return args.scene;
  const std::vector<tools::CaseInfo> cases = tools::listCases(fs::path(tools::defaultScenePath()).parent_path().string());
  const tools::StartChoice choice =
      tools::runStartScreen(*w.window, *w.layer, cases, trainee, {args.quit_after_s, args.frames, args.screenshot});
  if (choice.quit) return {};
  hands_on = choice.hands_on;
  if (!choice.trainee.empty()) trainee = choice.trainee;
  return cases[choice.index].path;
}

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
  std::string trainee = !args.trainee.empty() ? args.trainee : (user != nullptr ? user : "");
  bool hands_on = false;
  const std::string scene_path = chooseScene(args, *opened, hands_on, trainee);
  if (scene_path.empty()) return 0;
  tools::CaseOptions options;
  options.frames = args.frames;
  options.quit_after_s = args.quit_after_s;
  options.screenshot = args.screenshot;
  options.alarm_screenshot = args.alarm_screenshot;
  options.paused = args.paused;
  options.gamepad = args.gamepad;
  options.record = args.record;
  options.trainee = trainee;
  options.data_dir = args.data_dir;
  options.hands_on = hands_on;
  options.max_fps = args.max_fps;
  options.input = args.input.empty() ? nullptr : &input;
  return tools::runCase(options, scene_path, *opened);
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
