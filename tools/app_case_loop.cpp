#include "app_case_loop.hpp"

#include <SDL.h>
#include <imgui.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <thread>

#include "app_beep.hpp"
#include "app_frame_stats.hpp"
#include "app_guidance.hpp"
#include "app_guidance_panel.hpp"
#include "app_haptics.hpp"
#include "app_keys.hpp"
#include "app_panel.hpp"
#include "app_pivot_scope.hpp"
#include "app_session.hpp"
#include "app_session_store.hpp"
#include "hysim/engine/run.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/sim_thread.hpp"
#include "hysim/render/image.hpp"
#include "hysim/render/renderer.hpp"

namespace hysim::tools {
namespace {

using Clock = std::chrono::steady_clock;
double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

int fail(const std::string& message) {
  std::cerr << "hysim-app: " << message << "\n";
  return 1;
}

// Keys held down, from the window's key events (typed or scripted alike).
using HeldKeys = std::array<bool, SDL_NUM_SCANCODES>;

// The trainee's keys held now (see app_keys.hpp for what each does).
TraineeKeys heldKeys(const HeldKeys& k) {
  TraineeKeys keys;
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

// The first step that raised the perforation alarm, written by the simulation thread's
// after-step call and read by the frame loop, both under the thread's lock.
struct AlarmStep {
  bool raised = false;
  bool shown = false;  // its first frame was reported
  Clock::time_point wall;
  double raised_at_s = 0.0, event_s = 0.0;  // simulated times, for the report
};

// Everything one case carries from frame to frame.
struct CaseLoop {
  CaseLoop(const CaseOptions& o, AppWindow& window, engine::Scene s) : options(o), w(window), scene(std::move(s)) {}
  const CaseOptions& options;
  AppWindow& w;
  engine::Scene scene;
  std::unique_ptr<render::Renderer> renderer;
  AppGamepad gamepad;
  AppSessionStore store;
  Session session;
  AlarmSound sound;
  AppHaptics force_feedback;
  Panel panel;
  engine::SimThread sim_thread;  // after the session: stops stepping before the session goes
  AlarmStep alarm;
  render::RenderSnapshot snapshot;
  Eigen::Matrix<double, Eigen::Dynamic, 3> wire;
  FrameStats frame_stats;
  HeldKeys held{};
  double tool_force_n = 0.0, max_force_n = 0.0;
  double frame_ms = 0.0;  // smoothed wall time per frame
  double path_end_s = 0.0;
  bool quit = false;
  bool said_behind = false;  // "cannot keep up" was said
  bool screenshot_failed = false;
  Clock::time_point start, last;
  long frame = 0;
};

// A key the panel did not take. True: the case ends (quit, or Enter: to the debrief).
bool handleKey(SDL_Keycode key, CaseLoop& c) {
  switch (key) {
    case SDLK_ESCAPE: return true;
    case SDLK_RETURN:
    case SDLK_KP_ENTER: c.panel.end_requested = true; return true;
    case SDLK_SPACE: c.panel.paused = !c.panel.paused; break;
    case SDLK_r: c.panel.reset_requested = true; break;
    case SDLK_l: c.panel.lens_index = (c.panel.lens_index + 1) % 3; break;
    case SDLK_m: c.panel.manual_requested = true; break;
    case SDLK_i: c.panel.details = !c.panel.details; break;
    case SDLK_TAB: c.panel.hidden = !c.panel.hidden; break;
    case SDLK_x: c.force_feedback.eStop(); break;
    case SDLK_f: c.force_feedback.resetSafety(); break;
    default: break;
  }
  return false;
}

void pollEvents(CaseLoop& c) {
  SDL_Event event;
  while (SDL_PollEvent(&event)) {
    const bool taken = c.w.layer->processEvent(event);
    if (event.type == SDL_QUIT) c.quit = true;
    if (event.type == SDL_WINDOWEVENT && event.window.event == SDL_WINDOWEVENT_CLOSE &&
        event.window.windowID == SDL_GetWindowID(c.w.window->nativeWindow())) {
      c.quit = true;
    }
    if ((event.type == SDL_KEYDOWN || event.type == SDL_KEYUP) && event.key.keysym.scancode < SDL_NUM_SCANCODES) {
      c.held[event.key.keysym.scancode] = event.type == SDL_KEYDOWN;
    }
    if (event.type == SDL_KEYDOWN && !taken && event.key.repeat == 0 && handleKey(event.key.keysym.sym, c)) {
      c.quit = true;
    }
  }
}

// The simulation thread steps `c.session.sim` from now on, watched by the session's monitor.
void attachSession(CaseLoop& c) {
  c.sim_thread.attach(c.session.sim.get(), [&c](engine::Simulation& sim) {
    if (c.session.monitor->afterStep(sim) && !c.alarm.raised) {
      c.alarm.raised = true;
      c.alarm.wall = Clock::now();
    }
  });
}

// A reset ends the session and starts the next, recorded and logged anew.
Status resetSession(CaseLoop& c) {
  c.panel.reset_requested = false;
  c.sim_thread.attach(nullptr);
  endSession(c.session);
  c.session.hands_on = c.options.hands_on;
  if (Status s = startSession(c.session, c.scene, ""); !s.ok()) return Error{"reset: " + s.error()};
  c.gamepad.release();  // (the pad's device went with the old simulation)
  c.panel.manual_requested = c.gamepad.enabled() || c.options.hands_on;
  c.panel.manual = false;
  c.max_force_n = 0.0;
  c.alarm = AlarmStep{};
  attachSession(c);
  return {};
}

// Manual control: the game controller (when one is used) or else the keyboard scope, pivoting
// at the cervix, takes over from the device's current pose (M toggles); back to the script
// otherwise. Returns the keyboard scope (owned by the simulation) or null.
haptics::PivotScopeDevice* toggleManual(engine::Simulation& sim, CaseLoop& c) {
  c.panel.manual_requested = false;
  c.panel.manual = !c.panel.manual;
  c.gamepad.release();  // whatever comes next replaces the simulation's device
  if (c.panel.manual && c.gamepad.enabled() && c.gamepad.attach(sim)) return nullptr;
  if (!c.panel.manual) {
    sim.setDevice(std::make_unique<haptics::ScriptedDevice>(haptics::Trajectory(c.scene.tool_path)));
    return nullptr;
  }
  return attachPivotScope(sim);
}

// Between two steps: the trainee's input reaches the simulation, and the frame's snapshot is
// taken.
void exchangeWithSimulation(CaseLoop& c) {
  engine::Simulation& sim = *c.session.sim;
  if (c.panel.manual_requested) c.session.scope = toggleManual(sim, c);
  c.session.hands_on = c.session.hands_on || c.panel.manual || c.gamepad.active();
  c.gamepad.update(sim, c.scene.safety.perforation_margin_mm, c.panel.lens_index,
                   c.session.monitor->alarm().active(sim.state().time));
  if (c.session.scope != nullptr) {
    c.session.scope->setCommand(pivotCommand(heldKeys(c.held)));
    limitScope(*c.session.scope, c.snapshot.tissue, scopeSize(sim));
  }
  if (c.options.input != nullptr) c.options.input->pumpSim(sim.state().time);
  c.sim_thread.setPaused(c.panel.paused);
  c.sim_thread.setSpeed(c.panel.speed);
  c.force_feedback.publish(sim);
  c.tool_force_n = sim.toolForceN().norm();
  c.max_force_n = std::max(c.max_force_n, c.tool_force_n);
  sim.fillSnapshot(c.snapshot);
  c.snapshot.camera.lens_deg = static_cast<float>(kLens[c.panel.lens_index]);
}

// Where the scope view goes: the window right of the panel (or all of it with the panel
// hidden), as large as fits at the camera's 4:3, in pixels and in screen coordinates.
struct ViewPlace {
  int x = 0, y = 0, w = 1, h = 1;  // pixels
  ViewRect rect;                   // screen coordinates
};

ViewPlace placeView(render::SdlWindow& window, float panel_w) {
  int dw = 0, dh = 0, ww = 0, wh = 0;
  window.drawableSize(dw, dh);
  SDL_GetWindowSize(window.nativeWindow(), &ww, &wh);
  const float scale = ww > 0 ? static_cast<float>(dw) / static_cast<float>(ww) : 1.0f;
  const int panel_px = static_cast<int>(panel_w * scale);
  const int area_w = std::max(dw - panel_px, 1), area_h = std::max(dh, 1);
  ViewPlace v;
  v.w = std::max(std::min(area_w, area_h * 4 / 3), 1);
  v.h = std::max(v.w * 3 / 4, 1);
  v.x = panel_px + (area_w - v.w) / 2;
  v.y = (area_h - v.h) / 2;
  v.rect = {ImVec2(v.x / scale, v.y / scale), ImVec2((v.x + v.w) / scale, (v.y + v.h) / scale)};
  return v;
}

// The scope view, rendered at the size it is shown (a new renderer when that changes).
Status drawView(CaseLoop& c, const ViewPlace& place) {
  if (!c.renderer || c.renderer->width() != place.w || c.renderer->height() != place.h) {
    c.renderer.reset();
    auto renderer = render::Renderer::create(place.w, place.h);
    if (!renderer.ok()) return Error{"cannot create the renderer: " + renderer.error()};
    c.renderer = std::move(renderer.value());
  }
  c.renderer->draw(c.snapshot);
  c.w.window->clear(0.08f, 0.08f, 0.09f);
  c.renderer->blitTo(0, place.x, place.y, place.w, place.h);
  return {};
}

// The first frame that draws the alarm: how long after the engine's event (simulated) and
// after the raising step (wall) it came, and its picture when asked for. Called after the
// frame is drawn, with the times taken under the lock.
void reportAlarmFrame(CaseLoop& c) {
  std::printf("hysim-app: perforation alarm: engine event at %.3f s, raised at the step of %.3f s, drawn %.1f ms "
              "(wall) after that step\n",
              c.alarm.event_s, c.alarm.raised_at_s, 1e3 * seconds(Clock::now() - c.alarm.wall));
  if (c.options.alarm_screenshot.empty()) return;
  const render::Image shot = c.w.window->readBackBuffer();
  if (Status s = render::writePng(c.options.alarm_screenshot, shot); !s.ok()) {
    std::printf("hysim-app: %s\n", s.error().c_str());
    return;
  }
  std::printf("hysim-app: alarm screenshot %s\n", c.options.alarm_screenshot.c_str());
}

// Under the lock, on the first frame after the alarm's step: the times its report needs.
bool takeAlarmToReport(CaseLoop& c) {
  if (!c.alarm.raised || c.alarm.shown) return false;
  c.alarm.shown = true;
  const engine::Simulation& sim = *c.session.sim;
  c.alarm.raised_at_s = c.session.monitor->alarm().raisedAtS();
  c.alarm.event_s = sim.perforationEvents().empty() ? c.alarm.raised_at_s : sim.perforationEvents().front().time_s;
  return true;
}

// Said once per case, on the view and on stdout, instead of a counter that only grows.
void sayWhenBehind(CaseLoop& c, const engine::PaceStats& pace, const ViewRect& view) {
  if (!pace.cannot_keep_up) return;
  if (!c.said_behind) {
    c.said_behind = true;
    std::printf("hysim-app: this computer cannot keep up with real time; the simulation runs slower (%.2fx so far)\n",
                pace.wall_s > 0.0 ? pace.sim_s / pace.wall_s : 0.0);
  }
  const char* text = "This computer cannot keep up: the simulation runs slower than real time";
  const float width = ImGui::CalcTextSize(text).x;
  ImGui::GetForegroundDrawList()->AddText(ImVec2(std::max(view.min.x, view.max.x - width - 12.0f), view.min.y + 8.0f),
                                          IM_COL32(255, 190, 80, 255), text);
}

// The panel and the view's overlay, drawn between two steps.
void drawPanelAndOverlay(CaseLoop& c, const ViewRect& view, float panel_w, Clock::time_point now) {
  int ww = 0, wh = 0;
  SDL_GetWindowSize(c.w.window->nativeWindow(), &ww, &wh);
  const engine::Simulation& sim = *c.session.sim;
  const engine::PaceStats& pace = c.sim_thread.stats();
  const GuidanceView guidance = guidanceView(c.session, c.sound, c.wire);
  const FrameNumbers numbers{pace.step_median_us, engine::StepTimes::kWindow, pace.realtime, c.frame_ms,
                             pace.behind_s, c.tool_force_n, c.max_force_n};
  if (panel_w > 0.0f) {
    drawPanel(c.scene, sim, c.panel, numbers, guidance, c.force_feedback, c.gamepad, c.session.recording, c.store,
              c.path_end_s, panel_w, static_cast<float>(wh));
  }
  drawViewOverlay(guidance, view, seconds(now - c.start));
  sayWhenBehind(c, pace, view);
}

// The last frame's picture. False: it could not be written (said on stderr).
bool writeScreenshot(CaseLoop& c) {
  const render::Image shot = c.w.window->readBackBuffer();
  if (Status s = render::writePng(c.options.screenshot, shot); !s.ok()) {
    std::cerr << "hysim-app: " << s.error() << "\n";
    return false;
  }
  std::printf("hysim-app: screenshot %s (%dx%d)\n", c.options.screenshot.c_str(), shot.width, shot.height);
  return true;
}

// The frame's wall time, and whether the command line's limits end the case with this frame.
void timeFrame(CaseLoop& c, Clock::time_point now) {
  const double elapsed = seconds(now - c.last);
  c.last = now;
  if (c.frame > 0) c.frame_stats.addFrame(elapsed);
  const double a = std::min(1.0, elapsed / 0.5);  // ~0.5 s smoothing
  c.frame_ms += a * (1e3 * elapsed - c.frame_ms);
  if (c.options.frames >= 0 && c.frame + 1 >= c.options.frames) c.quit = true;
  if (c.options.quit_after_s >= 0.0 && seconds(now - c.start) >= c.options.quit_after_s) c.quit = true;
  if (c.panel.end_requested) c.quit = true;  // (the panel's button, last frame)
}

// One frame: events, the input to the simulation, the scope view, the panel. Every way out
// (Esc, the window closed, --frames, --quit-after-s) still draws the frame, so --screenshot
// gets a complete last frame.
Status runFrame(CaseLoop& c) {
  pollEvents(c);
  const Clock::time_point now = Clock::now();
  timeFrame(c, now);
  if (c.panel.reset_requested) {
    if (Status s = resetSession(c); !s.ok()) return s;
  }
  c.sim_thread.access([&c] { exchangeWithSimulation(c); });
  const float panel_w = c.panel.hidden ? 0.0f : 300.0f;  // screen coordinates
  const ViewPlace place = placeView(*c.w.window, panel_w);
  if (Status s = drawView(c, place); !s.ok()) return s;
  c.w.layer->newFrame();
  const bool alarm_now = c.sim_thread.access([&] {
    drawPanelAndOverlay(c, place.rect, panel_w, now);
    return takeAlarmToReport(c);
  });
  c.w.layer->render();
  ++c.frame;
  if (alarm_now) reportAlarmFrame(c);
  if (c.quit && !c.options.screenshot.empty() && !writeScreenshot(c)) c.screenshot_failed = true;
  c.w.window->swapBuffers();
  if (c.options.max_fps > 0.0) {
    std::this_thread::sleep_until(now + std::chrono::duration_cast<Clock::duration>(
                                            std::chrono::duration<double>(1.0 / c.options.max_fps)));
  }
  return {};
}

// Ends the session (stored, logged), prints its last line and the frame-rate figures, and
// returns what the debrief shows.
CaseResult endAndPrint(CaseLoop& c) {
  const engine::PaceStats pace = c.sim_thread.access([&c] { return c.sim_thread.stats(); });
  c.sim_thread.attach(nullptr);
  const engine::Simulation& sim = *c.session.sim;
  const int alarms = c.session.monitor->alarm().raised();
  endSession(c.session);
  std::printf("hysim-app: %ld frames, sim time %.3f s, %llu steps, warnings %d, perforations %d, alarms %d, "
              "state_hash %s\n",
              c.frame, sim.state().time, static_cast<unsigned long long>(sim.state().steps), sim.state().warnings,
              sim.perforations(), alarms, engine::hashHex(sim.stateHash()).c_str());
  int dw = 0, dh = 0;
  c.w.window->drawableSize(dw, dh);
  std::printf("hysim-app: frames %s\n", c.frame_stats.summary(dw, dh, pace.sim_s, pace.wall_s, pace.behind_s).c_str());
  return caseResult(c.session, c.panel.end_requested);
}

// Everything before the first frame: the pad, the store, the first session, the panel.
Status prepareCase(CaseLoop& c, const std::string& scene_path) {
  if (Status s = c.gamepad.configure(c.options.gamepad); !s.ok()) return s;  // before a session
  c.store.configure(c.options.data_dir, c.options.trainee);
  c.session.store = &c.store;
  c.session.hands_on = c.options.hands_on;
  if (Status s = startSession(c.session, c.scene, c.options.record); !s.ok()) return s;
  SDL_SetWindowTitle(c.w.window->nativeWindow(), ("hysim - " + c.scene.name).c_str());
  std::printf("hysim-app: scene %s (%s); %s\n", c.scene.name.c_str(), scene_path.c_str(),
              c.w.window->description().c_str());
  c.sound.open();
  c.panel.paused = c.options.paused;
  c.panel.lens_index = lensIndexFor(c.scene.camera.lens_deg);
  c.panel.manual_requested = c.gamepad.enabled() || c.options.hands_on;  // the pad or the keys take the tool at once
  c.session.sim->fillSnapshot(c.snapshot);  // the keyboard scope's first depth limit
  c.path_end_s = haptics::Trajectory(c.scene.tool_path).duration();
  c.sim_thread.access([&c] { c.sim_thread.setPaused(c.panel.paused); });
  c.start = c.last = Clock::now();
  attachSession(c);
  return {};
}

}  // namespace

int runCase(const CaseOptions& options, const std::string& scene_path, AppWindow& w, CaseResult& result) {
  auto scene = engine::loadScene(scene_path);
  if (!scene.ok()) return fail(scene.error());
  CaseLoop c(options, w, std::move(scene.value()));
  if (Status s = prepareCase(c, scene_path); !s.ok()) return fail(s.error());
  while (!c.quit) {
    if (Status s = runFrame(c); !s.ok()) {
      c.sim_thread.attach(nullptr);
      return fail(s.error());
    }
  }
  result = endAndPrint(c);
  return c.screenshot_failed ? 1 : 0;
}

}  // namespace hysim::tools
