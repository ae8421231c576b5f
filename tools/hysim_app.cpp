// hysim-app: the trainee window. Loads a scene, runs the fixed-step simulation paced to
// real time, shows the hysteroscope view (SDL2 + OpenGL 3.3) and an ImGui panel with the
// numbers a trainee and an instructor watch. Around the case: the start screen (and the
// progress screen from it) before, the debrief (and the session's replay) after, in turn
// until the trainee quits.
//
// Pacing is this program's job (the physics never reads the wall clock): wall time is
// accumulated and the scene's fixed dt is stepped as often as due, with the catch-up
// capped so a slow machine runs in slow motion instead of freezing the window.
#include <SDL.h>
#include <imgui.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "hysim/engine/run.hpp"
#include "app_beep.hpp"
#include "app_gamepad.hpp"
#include "app_guidance.hpp"
#include "app_guidance_panel.hpp"
#include "app_haptics.hpp"
#include "app_keys.hpp"
#include "app_monitor.hpp"
#include "app_pivot_scope.hpp"
#include "app_panel.hpp"
#include "app_recording.hpp"
#include "app_session.hpp"
#include "app_session_log.hpp"
#include "app_start_screen.hpp"
#include "app_cases.hpp"
#include "app_case_result.hpp"
#include "app_debrief.hpp"
#include "app_progress.hpp"
#include "app_replay.hpp"
#include "tool_common.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/simulation.hpp"
#include "hysim/render/image.hpp"
#include "hysim/render/imgui_layer.hpp"
#include "hysim/render/renderer.hpp"
#include "hysim/render/sdl_window.hpp"

namespace fs = std::filesystem;
using namespace hysim;
using Clock = std::chrono::steady_clock;

namespace {

int fail(const std::string& message) {
  std::cerr << "hysim-app: " << message << "\n";
  return 1;
}


double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

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
};

// Median of the last kWindow step times, without allocating per frame.
class StepTimes {
 public:
  static constexpr int kWindow = 100;
  void add(double us) {
    ring_[next_] = us;
    next_ = (next_ + 1) % kWindow;
    count_ = std::min(count_ + 1, kWindow);
  }
  double median() {
    if (count_ == 0) return 0.0;
    std::copy(ring_.begin(), ring_.begin() + count_, scratch_.begin());
    auto mid = scratch_.begin() + count_ / 2;
    std::nth_element(scratch_.begin(), mid, scratch_.begin() + count_);
    return *mid;
  }
  void clear() { count_ = next_ = 0; }

 private:
  std::array<double, kWindow> ring_{};
  std::array<double, kWindow> scratch_{};
  int count_ = 0;
  int next_ = 0;
};

// Fixed-step pacing: wall time in, number of steps due out.
struct Pacer {
  double dt = 1e-3;
  double speed = 1.0;               // simulated seconds per wall second (slow motion < 1)
  double max_frame_s = 0.1;         // at most this much simulated time per frame...
  double step_budget_s = 1.0 / 15;  // ...and at most this much wall time stepping per frame
  double accumulator = 0.0;         // simulated time due but not yet stepped
  double behind_s = 0.0;            // simulated time given up: the machine could not keep up

  int due(double wall_elapsed_s) {
    double wanted = wall_elapsed_s * speed;
    if (wanted > max_frame_s) {  // a long stall (window dragged, debugger): do not catch up
      behind_s += wanted - max_frame_s;
      wanted = max_frame_s;
    }
    accumulator += wanted;
    const int n = static_cast<int>(std::floor(accumulator / dt));
    accumulator -= n * dt;
    return n;
  }
  // Called when stepping stopped early (budget): forget the rest instead of piling it up.
  void drop(int not_stepped) {
    behind_s += not_stepped * dt + accumulator;
    accumulator = 0.0;
  }
  // Called when stepping stopped early to show something at once: the rest is stepped next frame.
  void keep(int not_stepped) { accumulator += not_stepped * dt; }
  void reset() { accumulator = behind_s = 0.0; }
};

// The trainee's keys held now (see app_keys.hpp for what each does).
tools::TraineeKeys heldKeys() {
  const Uint8* k = SDL_GetKeyboardState(nullptr);
  tools::TraineeKeys keys;
  keys.insert = k[SDL_SCANCODE_W];
  keys.withdraw = k[SDL_SCANCODE_S];
  keys.pivot_left = k[SDL_SCANCODE_LEFT];
  keys.pivot_right = k[SDL_SCANCODE_RIGHT];
  keys.pivot_up = k[SDL_SCANCODE_UP];
  keys.pivot_down = k[SDL_SCANCODE_DOWN];
  keys.roll_left = k[SDL_SCANCODE_A];
  keys.roll_right = k[SDL_SCANCODE_D];
  keys.loop_in = k[SDL_SCANCODE_Q];
  keys.loop_out = k[SDL_SCANCODE_E];
  keys.pedal_c = k[SDL_SCANCODE_C];
  keys.pedal_shift = k[SDL_SCANCODE_LSHIFT];
  return keys;
}

// A key the panel did not take. True: the case ends (quit, or Enter: to the debrief).
bool handleKey(SDL_Keycode key, tools::Panel& panel, tools::AppHaptics& force_feedback) {
  switch (key) {
    case SDLK_ESCAPE: return true;
    case SDLK_RETURN:
    case SDLK_KP_ENTER: panel.end_requested = true; return true;
    case SDLK_SPACE: panel.paused = !panel.paused; break;
    case SDLK_r: panel.reset_requested = true; break;
    case SDLK_l: panel.lens_index = (panel.lens_index + 1) % 3; break;
    case SDLK_m: panel.manual_requested = true; break;
    case SDLK_i: panel.details = !panel.details; break;
    case SDLK_x: force_feedback.eStop(); break;
    case SDLK_f: force_feedback.resetSafety(); break;
    default: break;
  }
  return false;
}

// The fixed steps due for the wall time since the last frame, within the frame's budget, each
// watched by the monitor; a step that raises the alarm ends the frame's stepping so that the
// alarm is drawn at once. True when a step raised the alarm.
bool stepDue(engine::Simulation& sim, tools::SessionMonitor& monitor, Pacer& pacer, StepTimes& step_times,
             Clock::time_point now, double elapsed) {
  const int due = pacer.due(elapsed);
  const Clock::time_point budget_end =
      now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(pacer.step_budget_s));
  for (int i = 0; i < due; ++i) {
    const Clock::time_point t0 = Clock::now();
    if (t0 >= budget_end) {
      pacer.drop(due - i);
      break;
    }
    sim.step();
    step_times.add(1e6 * seconds(Clock::now() - t0));
    if (monitor.afterStep(sim)) {
      pacer.keep(due - i - 1);
      return true;
    }
  }
  return false;
}

// Manual control: the game controller (when one is used) or else the keyboard scope, pivoting
// at the cervix, takes over from the device's current pose (M toggles); back to the script
// otherwise. Returns the keyboard scope (owned by the simulation) or null.
haptics::PivotScopeDevice* toggleManual(engine::Simulation& sim, const engine::Scene& scene, tools::Panel& panel,
                                        tools::AppGamepad& gamepad) {
  panel.manual_requested = false;
  panel.manual = !panel.manual;
  gamepad.release();  // whatever comes next replaces the simulation's device
  if (panel.manual && gamepad.enabled() && gamepad.attach(sim)) return nullptr;
  if (!panel.manual) {
    sim.setDevice(std::make_unique<haptics::ScriptedDevice>(haptics::Trajectory(scene.tool_path)));
    return nullptr;
  }
  return tools::attachPivotScope(sim);
}

// Scales the rendered scope view into the window right of the panel (panel_w in screen
// coordinates). Returns where the view lies, in screen coordinates.
tools::ViewRect blitView(render::SdlWindow& window, render::Renderer& renderer, float panel_w) {
  int dw = 0, dh = 0, ww = 0, wh = 0;
  window.drawableSize(dw, dh);
  SDL_GetWindowSize(window.nativeWindow(), &ww, &wh);
  const float scale = ww > 0 ? static_cast<float>(dw) / static_cast<float>(ww) : 1.0f;
  const int panel_px = static_cast<int>(panel_w * scale);
  const int area_w = std::max(dw - panel_px, 1), area_h = std::max(dh, 1);
  const double fit = std::min(static_cast<double>(area_w) / renderer.width(),
                              static_cast<double>(area_h) / renderer.height());
  const int vw = static_cast<int>(renderer.width() * fit);
  const int vh = static_cast<int>(renderer.height() * fit);
  const int vx = panel_px + (area_w - vw) / 2, vy = (area_h - vh) / 2;
  window.clear(0.08f, 0.08f, 0.09f);
  renderer.blitTo(0, vx, vy, vw, vh);
  return {ImVec2(vx / scale, vy / scale), ImVec2((vx + vw) / scale, (vy + vh) / scale)};
}

// The first frame that draws the alarm: how long after the engine's event (simulated) and
// after the raising step (wall) it came, and its picture when asked for.
void reportAlarmFrame(const engine::Simulation& sim, const tools::SessionMonitor& monitor, double wall_s,
                      const std::string& screenshot, render::SdlWindow& window) {
  const double event_s = sim.perforationEvents().empty() ? monitor.alarm().raisedAtS()
                                                         : sim.perforationEvents().front().time_s;
  std::printf("hysim-app: perforation alarm: engine event at %.3f s, raised at the step of %.3f s, drawn %.1f ms "
              "(wall) after that step\n",
              event_s, monitor.alarm().raisedAtS(), 1e3 * wall_s);
  if (screenshot.empty()) return;
  const render::Image shot = window.readBackBuffer();
  if (Status s = render::writePng(screenshot, shot); !s.ok()) {
    std::printf("hysim-app: %s\n", s.error().c_str());
    return;
  }
  std::printf("hysim-app: alarm screenshot %s\n", screenshot.c_str());
}

// The window and its ImGui layer, made before any scene: the start screen draws in them too.
struct AppWindow {
  std::unique_ptr<render::SdlWindow> window;
  std::unique_ptr<render::ImGuiLayer> layer;
};

Result<AppWindow> openWindow(const AppArgs& args) {
  render::SdlWindowOptions options;
  options.title = "hysim";
  options.width = args.width;
  options.height = args.height;
  options.vsync = !args.no_vsync;
  auto window = render::SdlWindow::create(options);
  if (!window.ok()) return Error{window.error()};
  auto layer = render::ImGuiLayer::create(**window);
  if (!layer.ok()) return Error{layer.error()};
  return AppWindow{std::move(window.value()), std::move(layer.value())};
}

// Ends the session (stored, logged), prints its last line and returns what the debrief shows
// (`ended`: the trainee ended the case rather than quitting).
tools::CaseResult endAndPrint(tools::Session& session, long frames, bool ended) {
  const engine::Simulation& sim = *session.sim;
  const int alarms = session.monitor->alarm().raised();
  tools::endSession(session);
  std::printf("hysim-app: %ld frames, sim time %.3f s, %llu steps, warnings %d, perforations %d, alarms %d, "
              "state_hash %s\n",
              frames, sim.state().time, static_cast<unsigned long long>(sim.state().steps), sim.state().warnings,
              sim.perforations(), alarms, engine::hashHex(sim.stateHash()).c_str());
  return tools::caseResult(session, ended);
}

// One case, from its scene to the trainee quitting or ending it (sessions begin anew on each
// reset); `result` is what the debrief shows.
int runCase(const AppArgs& args, const std::string& scene_path, bool hands_on, const std::string& trainee,
            AppWindow& w, tools::CaseResult& result) {
  auto scene = engine::loadScene(scene_path);
  if (!scene.ok()) return fail(scene.error());
  tools::AppGamepad gamepad;  // a missing pad or a bad mapping file stops here, before a session
  if (Status s = gamepad.configure(args.gamepad); !s.ok()) return fail(s.error());
  auto renderer = render::Renderer::create(scene->render.width, scene->render.height);
  if (!renderer.ok()) return fail("cannot create the renderer: " + renderer.error());
  tools::AppSessionStore store;
  store.configure(args.data_dir, trainee);
  tools::Session session;
  session.store = &store;
  session.hands_on = hands_on;
  if (Status s = tools::startSession(session, *scene, args.record); !s.ok()) return fail(s.error());
  std::unique_ptr<render::SdlWindow>& window = w.window;
  std::unique_ptr<render::ImGuiLayer>& layer = w.layer;
  SDL_SetWindowTitle(window->nativeWindow(), ("hysim - " + scene->name).c_str());
  std::printf("hysim-app: scene %s (%s); %s\n", scene->name.c_str(), scene_path.c_str(),
              window->description().c_str());
  tools::AlarmSound sound;
  sound.open();

  tools::Panel panel;
  panel.paused = args.paused;
  panel.lens_index = tools::lensIndexFor(scene->camera.lens_deg);
  Pacer pacer;
  pacer.dt = scene->sim.dt;
  StepTimes step_times;
  render::RenderSnapshot snapshot;
  session.sim->fillSnapshot(snapshot);  // the keyboard scope's first depth limit
  Eigen::Matrix<double, Eigen::Dynamic, 3> wire;
  double max_force_n = 0.0;
  double frame_ms = 0.0;   // smoothed wall time per frame
  double realtime = 0.0;   // smoothed simulated seconds per wall second
  const double path_end_s = haptics::Trajectory(scene->tool_path).duration();

  tools::AppHaptics force_feedback;
  panel.manual_requested = gamepad.enabled() || hands_on;  // the pad or the keyboard takes the tool at once

  const Clock::time_point start = Clock::now();
  Clock::time_point last = start;
  long frame = 0;
  bool quit = false;
  bool alarm_raised = false, alarm_shot_done = false;  // the session's first alarm, for --alarm-screenshot
  bool screenshot_failed = false;
  Clock::time_point alarm_step_wall;
  while (true) {
    // Events. Every way out (Esc, window close, --frames, --quit-after-s) still draws this
    // frame, so --screenshot always gets a complete last frame.
    SDL_Event event;
    while (SDL_PollEvent(&event)) {
      const bool taken = layer->processEvent(event);
      if (event.type == SDL_QUIT) quit = true;
      if (event.type == SDL_WINDOWEVENT && event.window.event == SDL_WINDOWEVENT_CLOSE &&
          event.window.windowID == SDL_GetWindowID(window->nativeWindow())) {
        quit = true;
      }
      if (event.type == SDL_KEYDOWN && !taken && event.key.repeat == 0) {
        if (handleKey(event.key.keysym.sym, panel, force_feedback)) quit = true;
      }
    }

    const Clock::time_point now = Clock::now();
    const double elapsed = seconds(now - last);
    last = now;
    if (args.frames >= 0 && frame + 1 >= args.frames) quit = true;
    if (args.quit_after_s >= 0.0 && seconds(now - start) >= args.quit_after_s) quit = true;
    if (panel.end_requested) quit = true;

    if (panel.reset_requested) {
      panel.reset_requested = false;
      tools::endSession(session);  // a reset starts a new session, recorded and logged anew
      session.hands_on = hands_on;
      if (Status s = tools::startSession(session, *scene, ""); !s.ok()) return fail("reset: " + s.error());
      gamepad.release();    // (the pad's device went with the old simulation)
      panel.manual_requested = gamepad.enabled() || hands_on;
      panel.manual = false;
      pacer.reset();
      step_times.clear();
      max_force_n = 0.0;
    }
    engine::Simulation& sim = *session.sim;

    if (panel.manual_requested) session.scope = toggleManual(sim, *scene, panel, gamepad);
    session.hands_on = session.hands_on || panel.manual || gamepad.active();
    gamepad.update(sim, scene->safety.perforation_margin_mm, panel.lens_index,
                   session.monitor->alarm().active(sim.state().time));
    if (session.scope != nullptr) {
      session.scope->setCommand(tools::pivotCommand(heldKeys()));
      tools::limitScope(*session.scope, snapshot.tissue, tools::scopeSize(sim));
    }

    // Fixed steps due for the wall time since the last frame.
    const double sim_before = sim.state().time;
    if (!panel.paused) {
      pacer.speed = panel.speed;
      if (stepDue(sim, *session.monitor, pacer, step_times, now, elapsed) && !alarm_raised) {
        alarm_raised = true;
        alarm_step_wall = Clock::now();
      }
    }
    force_feedback.publish(sim);
    const double tool_force_n = sim.toolForceN().norm();
    max_force_n = std::max(max_force_n, tool_force_n);
    if (elapsed > 0.0) {
      const double a = std::min(1.0, elapsed / 0.5);  // ~0.5 s smoothing
      frame_ms += a * (1e3 * elapsed - frame_ms);
      realtime += a * ((sim.state().time - sim_before) / elapsed - realtime);
    }

    // The scope view.
    sim.fillSnapshot(snapshot);
    snapshot.camera.lens_deg = static_cast<float>(tools::kLens[panel.lens_index]);
    (*renderer)->draw(snapshot);

    const float panel_w = 300.0f;  // screen coordinates
    const tools::ViewRect view = blitView(*window, **renderer, panel_w);
    int ww = 0, wh = 0;
    SDL_GetWindowSize(window->nativeWindow(), &ww, &wh);

    // The panel and the view's overlay.
    layer->newFrame();
    const tools::GuidanceView guidance = tools::guidanceView(session, sound, wire);
    tools::FrameNumbers numbers{step_times.median(), StepTimes::kWindow, realtime, frame_ms, pacer.behind_s, tool_force_n, max_force_n};
    tools::drawPanel(*scene, sim, panel, numbers, guidance, force_feedback, gamepad, session.recording, store, path_end_s,
                     panel_w, static_cast<float>(wh));
    tools::drawViewOverlay(guidance, view, seconds(now - start));
    layer->render();

    ++frame;
    if (alarm_raised && !alarm_shot_done) {
      alarm_shot_done = true;
      reportAlarmFrame(sim, *session.monitor, seconds(Clock::now() - alarm_step_wall), args.alarm_screenshot,
                       *window);
    }
    if (quit && !args.screenshot.empty()) {  // (a failure is said; the session still ends below)
      const render::Image shot = window->readBackBuffer();
      if (Status s = render::writePng(args.screenshot, shot); !s.ok()) {
        screenshot_failed = true;
        std::cerr << "hysim-app: " << s.error() << "\n";
      } else {
        std::printf("hysim-app: screenshot %s (%dx%d)\n", args.screenshot.c_str(), shot.width, shot.height);
      }
    }
    window->swapBuffers();
    if (quit) break;
  }
  result = endAndPrint(session, frame, panel.end_requested);
  return screenshot_failed ? 1 : 0;
}

// Where the trainee is between screens: the start screen's choices, the case, its result.
struct AppFlow {
  std::vector<tools::CaseInfo> cases;
  tools::StartChoice choice;  // the trainee, the case and the mode
  std::string scene_path;
  std::string record;         // --record, for the first case only (later ones get new files)
  tools::CaseResult result;
  std::string message;        // for the debrief: why the replay could not play
};

enum class Next { Start, Case, Debrief, Quit };

tools::StartScreenExit screenExit(const AppArgs& args) { return {args.quit_after_s, args.frames, args.screenshot}; }

// The start screen, and the progress screen from it, until a case is chosen or the trainee quits.
Next startScreen(const AppArgs& args, AppWindow& w, AppFlow& flow) {
  if (flow.cases.empty()) {
    flow.cases = tools::listCases(fs::path(tools::defaultScenePath()).parent_path().string());
  }
  while (true) {
    const tools::StartChoice c = tools::runStartScreen(*w.window, *w.layer, flow.cases, flow.choice, screenExit(args));
    if (!c.trainee.empty()) flow.choice.trainee = c.trainee;
    flow.choice.index = c.index;
    flow.choice.hands_on = c.hands_on;
    if (c.quit) return Next::Quit;
    if (!c.progress) break;
    if (!tools::runProgress(*w.window, *w.layer, args.data_dir, flow.choice.trainee, screenExit(args))) {
      return Next::Quit;
    }
  }
  flow.scene_path = flow.cases[flow.choice.index].path;
  return Next::Case;
}

Next playCase(const AppArgs& args, AppWindow& w, AppFlow& flow, int& rc) {
  AppArgs case_args = args;
  case_args.record = flow.record;
  flow.record.clear();  // a second case must not overwrite the first one's recording
  flow.result = {};
  flow.message.clear();
  rc = runCase(case_args, flow.scene_path, flow.choice.hands_on, flow.choice.trainee, w, flow.result);
  return rc == 0 && flow.result.ended ? Next::Debrief : Next::Quit;
}

// The debrief, and the replay from it, until the trainee restarts, goes back or quits.
Next debrief(const AppArgs& args, AppWindow& w, AppFlow& flow) {
  while (true) {
    switch (tools::runDebrief(*w.window, *w.layer, flow.result, flow.message, screenExit(args))) {
      case tools::DebriefAction::Restart: return Next::Case;
      case tools::DebriefAction::Cases: return Next::Start;
      case tools::DebriefAction::Quit: return Next::Quit;
      case tools::DebriefAction::Replay: break;
    }
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
  const char* user = std::getenv("USER");
  AppFlow flow;
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
  CLI11_PARSE(app, argc, argv);
  return runApp(args);
}
