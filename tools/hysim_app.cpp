// hysim-app: the trainee window. Loads a scene, runs the fixed-step simulation paced to
// real time, shows the hysteroscope view (SDL2 + OpenGL 3.3) and an ImGui panel with the
// numbers a trainee and an instructor watch.
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
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "hysim/engine/run.hpp"
#include "app_gamepad.hpp"
#include "app_recording.hpp"
#include "app_haptics.hpp"
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
  int width = 1024;
  int height = 768;
  bool no_vsync = false;
  bool paused = false;
  tools::GamepadArgs gamepad;
  std::string record;  // the session's recording; empty: a new file in the recordings folder
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
  void reset() { accumulator = behind_s = 0.0; }
};

struct Panel {
  bool paused = false;
  bool reset_requested = false;
  int lens_index = 2;  // 0, 12, 30 degrees
  float speed = 1.0f;
  bool manual = false;  // keyboard drives the scope instead of the scripted path
  bool manual_requested = false;
  bool pedal = false;
};

// Keyboard -> rate command for the manual device: W/S forward/back along the axis,
// arrows left/right/up/down (strafe), A/D yaw, PageUp/PageDown pitch, Q/E retract/extend
// the loop.
haptics::ManualCommand keyboardCommand(bool pedal) {
  const Uint8* k = SDL_GetKeyboardState(nullptr);
  constexpr double kSpeed = 10.0;   // mm/s
  constexpr double kTurn = 0.6;     // rad/s
  constexpr double kExtend = 5.0;   // mm/s
  haptics::ManualCommand c;
  c.velocity_scope_mm_s.z() = kSpeed * ((k[SDL_SCANCODE_W] ? 1 : 0) - (k[SDL_SCANCODE_S] ? 1 : 0));
  c.velocity_scope_mm_s.x() = kSpeed * ((k[SDL_SCANCODE_RIGHT] ? 1 : 0) - (k[SDL_SCANCODE_LEFT] ? 1 : 0));
  c.velocity_scope_mm_s.y() = kSpeed * ((k[SDL_SCANCODE_UP] ? 1 : 0) - (k[SDL_SCANCODE_DOWN] ? 1 : 0));
  c.yaw_rad_s = kTurn * ((k[SDL_SCANCODE_A] ? 1 : 0) - (k[SDL_SCANCODE_D] ? 1 : 0));
  c.pitch_rad_s = kTurn * ((k[SDL_SCANCODE_PAGEDOWN] ? 1 : 0) - (k[SDL_SCANCODE_PAGEUP] ? 1 : 0));
  c.extension_mm_s = kExtend * ((k[SDL_SCANCODE_E] ? 1 : 0) - (k[SDL_SCANCODE_Q] ? 1 : 0));
  c.pedal = pedal;
  return c;
}

constexpr std::array<int, 3> kLens = {0, 12, 30};

int lensIndexFor(double deg) {
  int best = 0;
  for (int i = 1; i < 3; ++i) {
    if (std::fabs(kLens[i] - deg) < std::fabs(kLens[best] - deg)) best = i;
  }
  return best;
}

// A key the panel did not take. True: quit.
bool handleKey(SDL_Keycode key, Panel& panel, tools::AppHaptics& force_feedback) {
  switch (key) {
    case SDLK_ESCAPE: return true;
    case SDLK_SPACE: panel.paused = !panel.paused; break;
    case SDLK_r: panel.reset_requested = true; break;
    case SDLK_l: panel.lens_index = (panel.lens_index + 1) % 3; break;
    case SDLK_m: panel.manual_requested = true; break;
    case SDLK_x: force_feedback.eStop(); break;
    case SDLK_f: force_feedback.resetSafety(); break;
    default: break;
  }
  return false;
}

// The fixed steps due for the wall time since the last frame, within the frame's budget.
void stepDue(engine::Simulation& sim, Pacer& pacer, StepTimes& step_times, Clock::time_point now, double elapsed) {
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
  }
}

// The panel's controls: pause, reset, speed, lens, manual scope, and the keys.
void drawControls(Panel& panel) {
  if (ImGui::Button(panel.paused ? "Resume (Space)" : "Pause (Space)", ImVec2(-1, 0))) {
    panel.paused = !panel.paused;
  }
  if (ImGui::Button("Reset (R)", ImVec2(-1, 0))) panel.reset_requested = true;
  ImGui::SliderFloat("speed", &panel.speed, 0.05f, 1.0f, "%.2fx");
  ImGui::Text("lens (L)");
  for (int i = 0; i < 3; ++i) {
    char label[16];
    std::snprintf(label, sizeof(label), "%d deg", kLens[i]);
    if (i > 0) ImGui::SameLine();
    ImGui::RadioButton(label, &panel.lens_index, i);
  }
  ImGui::Separator();
  if (ImGui::Checkbox("manual scope (M)", &panel.manual)) {
    panel.manual = !panel.manual;  // applied (and toggled) at the top of the next frame
    panel.manual_requested = true;
  }
  if (panel.manual) {
    ImGui::TextDisabled("W/S forward/back, arrows move");
    ImGui::TextDisabled("A/D yaw, PgUp/PgDn pitch");
    ImGui::TextDisabled("Q/E loop in/out");
  } else {
    ImGui::TextDisabled("scope follows the scene's scripted path");
  }
  ImGui::TextDisabled("X: force e-stop, F: reset force");
  ImGui::TextDisabled("Esc: quit");
}

// Manual control: the game controller (when one is used) or else a keyboard device takes over
// from the device's current pose (M toggles); back to the script otherwise. Returns the
// keyboard device (owned by the simulation) or null.
haptics::ManualDevice* toggleManual(engine::Simulation& sim, const engine::Scene& scene, Panel& panel,
                                    tools::AppGamepad& gamepad) {
  panel.manual_requested = false;
  panel.manual = !panel.manual;
  gamepad.release();  // whatever comes next replaces the simulation's device
  if (panel.manual && gamepad.enabled() && gamepad.attach(sim)) return nullptr;
  if (!panel.manual) {
    sim.setDevice(std::make_unique<haptics::ScriptedDevice>(haptics::Trajectory(scene.tool_path)));
    return nullptr;
  }
  auto* device = new haptics::ManualDevice(sim.deviceState().pose, sim.state().time);
  sim.setDevice(std::unique_ptr<haptics::Device>(device));
  return device;
}

// Scales the rendered scope view into the window right of the panel (panel_w in screen
// coordinates). Returns the window's height in screen coordinates, for the panel.
int blitView(render::SdlWindow& window, render::Renderer& renderer, float panel_w) {
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
  window.clear(0.08f, 0.08f, 0.09f);
  renderer.blitTo(0, panel_px + (area_w - vw) / 2, (area_h - vh) / 2, vw, vh);
  return wh;
}

// The numbers of the frame the panel shows.
struct FrameNumbers {
  double step_median_us = 0.0;
  double realtime = 0.0;
  double frame_ms = 0.0;
  double behind_s = 0.0;
  double tool_force_n = 0.0;
  double max_force_n = 0.0;
};

// The panel: what runs, how fast, the forces, the controller, the controls.
void drawPanel(const engine::Scene& scene, const engine::Simulation& sim, Panel& panel, const FrameNumbers& n,
               tools::AppHaptics& force_feedback, const tools::AppGamepad& gamepad,
               const tools::AppRecording& recording, double path_end_s, float panel_w, float panel_h) {
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImVec2(panel_w, panel_h));
  ImGui::Begin("hysim", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  ImGui::TextWrapped("%s", scene.description.empty() ? scene.name.c_str() : scene.description.c_str());
  ImGui::Separator();
  const sim::State& st = sim.state();
  if (panel.paused) ImGui::TextColored(ImVec4(0.4f, 0.8f, 1.0f, 1.0f), "PAUSED");
  ImGui::Text("sim time     %8.3f s", st.time);
  ImGui::Text("steps        %8llu  (dt %.3g ms)", static_cast<unsigned long long>(st.steps), 1e3 * scene.sim.dt);
  ImGui::Text("step time    %8.1f us  (median of %d)", n.step_median_us, StepTimes::kWindow);
  ImGui::Text("substeps     %8d", sim.model().substeps);
  ImGui::Text("real time    %8.2f x", n.realtime);
  ImGui::Text("frame        %8.1f ms", n.frame_ms);
  if (n.behind_s > 0.05) {
    // The simulation is never skipped ahead: a too slow machine runs in slow motion.
    ImGui::TextColored(ImVec4(1.0f, 0.75f, 0.3f, 1.0f), "behind real time by %.2f s", n.behind_s);
  }
  ImGui::Separator();
  ImGui::Text("tool force   %8.3f N", n.tool_force_n);
  ImGui::Text("max force    %8.3f N", n.max_force_n);
  force_feedback.drawPanel();
  if (st.warnings > 0) {
    ImGui::TextColored(ImVec4(1.0f, 0.35f, 0.3f, 1.0f), "warnings     %8d  (numerical trouble)", st.warnings);
  } else {
    ImGui::Text("warnings     %8d", st.warnings);
  }
  const char* path = gamepad.active() ? "game controller"
                     : panel.manual   ? "manual (keyboard)"
                     : st.time < path_end_s ? "scripted"
                                            : "done (holding last pose)";
  ImGui::Text("tool path    %s", path);
  if (gamepad.active()) {
    ImGui::Separator();
    gamepad.drawPanel();
  }
  recording.drawPanel();
  ImGui::Separator();
  drawControls(panel);
  ImGui::End();
}

int runApp(const AppArgs& args) {
  const std::string scene_path = args.scene.empty() ? tools::defaultScenePath() : args.scene;
  auto scene = engine::loadScene(scene_path);
  if (!scene.ok()) return fail(scene.error());
  auto created = engine::Simulation::create(*scene);
  if (!created.ok()) return fail(created.error());
  std::unique_ptr<engine::Simulation> sim = std::move(created.value());
  tools::AppGamepad gamepad;  // before the window: a missing pad or a bad mapping file stops here
  if (Status s = gamepad.configure(args.gamepad); !s.ok()) return fail(s.error());

  render::SdlWindowOptions window_options;
  window_options.title = "hysim - " + scene->name;
  window_options.width = args.width;
  window_options.height = args.height;
  window_options.vsync = !args.no_vsync;
  auto window = render::SdlWindow::create(window_options);
  if (!window.ok()) return fail(window.error());
  auto renderer = render::Renderer::create(scene->render.width, scene->render.height);
  if (!renderer.ok()) return fail("cannot create the renderer: " + renderer.error());
  auto layer = render::ImGuiLayer::create(**window);
  if (!layer.ok()) return fail(layer.error());
  std::printf("hysim-app: scene %s (%s); %s\n", scene->name.c_str(), scene_path.c_str(),
              (*window)->description().c_str());

  Panel panel;
  panel.paused = args.paused;
  panel.lens_index = lensIndexFor(scene->camera.lens_deg);
  Pacer pacer;
  pacer.dt = scene->sim.dt;
  StepTimes step_times;
  render::RenderSnapshot snapshot;
  double max_force_n = 0.0;
  double frame_ms = 0.0;   // smoothed wall time per frame
  double realtime = 0.0;   // smoothed simulated seconds per wall second
  const double path_end_s = haptics::Trajectory(scene->tool_path).duration();

  haptics::ManualDevice* manual_device = nullptr;  // owned by the simulation while in use
  tools::AppHaptics force_feedback;
  tools::AppRecording recording;
  recording.start(*scene, *sim, args.record);
  panel.manual_requested = gamepad.enabled();  // the pad takes the tool at the first frame

  const Clock::time_point start = Clock::now();
  Clock::time_point last = start;
  long frame = 0;
  bool quit = false;
  while (true) {
    // Events. Every way out (Esc, window close, --frames, --quit-after-s) still draws this
    // frame, so --screenshot always gets a complete last frame.
    SDL_Event event;
    while (SDL_PollEvent(&event)) {
      const bool taken = (*layer)->processEvent(event);
      if (event.type == SDL_QUIT) quit = true;
      if (event.type == SDL_WINDOWEVENT && event.window.event == SDL_WINDOWEVENT_CLOSE &&
          event.window.windowID == SDL_GetWindowID((*window)->nativeWindow())) {
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

    if (panel.reset_requested) {
      panel.reset_requested = false;
      auto fresh = engine::Simulation::create(*scene);
      if (!fresh.ok()) return fail("reset: " + fresh.error());
      recording.finish();  // a reset starts a new session, recorded anew
      sim = std::move(fresh.value());
      recording.start(*scene, *sim);
      manual_device = nullptr;  // the fresh simulation follows the script again
      gamepad.release();        // (the pad's device went with the old simulation)
      panel.manual_requested = gamepad.enabled();
      panel.manual = false;
      pacer.reset();
      step_times.clear();
      max_force_n = 0.0;
    }

    if (panel.manual_requested) manual_device = toggleManual(*sim, *scene, panel, gamepad);
    gamepad.update(*sim, scene->safety.perforation_margin_mm, panel.lens_index);
    if (manual_device != nullptr) manual_device->setCommand(keyboardCommand(panel.pedal));

    // Fixed steps due for the wall time since the last frame.
    const double sim_before = sim->state().time;
    if (!panel.paused) {
      pacer.speed = panel.speed;
      stepDue(*sim, pacer, step_times, now, elapsed);
    }
    force_feedback.publish(*sim);
    const double tool_force_n = sim->toolForceN().norm();
    max_force_n = std::max(max_force_n, tool_force_n);
    if (elapsed > 0.0) {
      const double a = std::min(1.0, elapsed / 0.5);  // ~0.5 s smoothing
      frame_ms += a * (1e3 * elapsed - frame_ms);
      realtime += a * ((sim->state().time - sim_before) / elapsed - realtime);
    }

    // The scope view.
    sim->fillSnapshot(snapshot);
    snapshot.camera.lens_deg = static_cast<float>(kLens[panel.lens_index]);
    (*renderer)->draw(snapshot);

    const float panel_w = 300.0f;  // screen coordinates
    const int wh = blitView(**window, **renderer, panel_w);

    // The panel.
    (*layer)->newFrame();
    FrameNumbers numbers{step_times.median(), realtime, frame_ms, pacer.behind_s, tool_force_n, max_force_n};
    drawPanel(*scene, *sim, panel, numbers, force_feedback, gamepad, recording, path_end_s, panel_w,
              static_cast<float>(wh));
    (*layer)->render();

    ++frame;
    if (quit && !args.screenshot.empty()) {
      const render::Image shot = (*window)->readBackBuffer();
      if (Status s = render::writePng(args.screenshot, shot); !s.ok()) return fail(s.error());
      std::printf("hysim-app: screenshot %s (%dx%d)\n", args.screenshot.c_str(), shot.width, shot.height);
    }
    (*window)->swapBuffers();
    if (quit) break;
  }
  recording.finish();
  std::printf("hysim-app: %ld frames, sim time %.3f s, %llu steps, warnings %d, state_hash %s\n", frame,
              sim->state().time, static_cast<unsigned long long>(sim->state().steps), sim->state().warnings,
              engine::hashHex(sim->stateHash()).c_str());
  return 0;
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
  app.add_option("--record", args.record,
                 "Record the session into this file (default: a new file in the recordings folder, "
                 "$HYSIM_DATA_DIR or ~/.local/share/hysim, /recordings)");
  CLI11_PARSE(app, argc, argv);
  return runApp(args);
}
