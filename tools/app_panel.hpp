#pragma once
// The trainee app's panel: the case, the trainee's guidance, the scope's driver, the
// recording, the controls (pause, reset, speed, lens, manual scope, details) and, behind
// "details", the developer's numbers. ImGui drawing and the state its controls change.
#include <array>

#include "app_gamepad.hpp"
#include "app_guidance_panel.hpp"
#include "app_haptics.hpp"
#include "app_recording.hpp"
#include "app_session_store.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/simulation.hpp"

namespace hysim::tools {

struct Panel {
  bool paused = false;
  bool reset_requested = false;
  bool end_requested = false;  // the trainee ended the case: the debrief comes next
  int lens_index = 2;  // 0, 12, 30 degrees
  float speed = 1.0f;
  bool manual = false;  // keyboard drives the scope instead of the scripted path
  bool manual_requested = false;
  bool details = false;  // developer numbers (step time, substeps, forces) shown
  bool hidden = false;   // the panel is collapsed: the scope view takes the whole window
};

inline constexpr std::array<int, 3> kLens = {0, 12, 30};  // degrees
// The lens closest to `deg`.
int lensIndexFor(double deg);

// The numbers of the frame the details show.
struct FrameNumbers {
  double step_median_us = 0.0;
  int step_window = 0;  // steps the median is taken over
  double realtime = 0.0;
  double frame_ms = 0.0;
  double behind_s = 0.0;
  double tool_force_n = 0.0;
  double max_force_n = 0.0;
};

// The whole panel at the window's left edge, panel_w x panel_h screen coordinates.
void drawPanel(const engine::Scene& scene, const engine::Simulation& sim, Panel& panel, const FrameNumbers& n,
               const GuidanceView& guidance, AppHaptics& force_feedback, const AppGamepad& gamepad,
               const AppRecording& recording, const AppSessionStore& store, double path_end_s, float panel_w,
               float panel_h);

}  // namespace hysim::tools
