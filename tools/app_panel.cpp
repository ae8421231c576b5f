#include "app_panel.hpp"

#include <imgui.h>

#include <cmath>
#include <cstdio>

namespace hysim::tools {

int lensIndexFor(double deg) {
  int best = 0;
  for (int i = 1; i < 3; ++i) {
    if (std::fabs(kLens[i] - deg) < std::fabs(kLens[best] - deg)) best = i;
  }
  return best;
}

namespace {

// The panel's controls: pause, reset, speed, lens, manual scope, details, and the keys.
void drawControls(Panel& panel) {
  if (ImGui::Button(panel.paused ? "Resume (Space)" : "Pause (Space)", ImVec2(-1, 0))) {
    panel.paused = !panel.paused;
  }
  if (ImGui::Button("Reset (R)", ImVec2(-1, 0))) panel.reset_requested = true;
  if (ImGui::Button("End the case: debrief (Enter)", ImVec2(-1, 0))) panel.end_requested = true;
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
    ImGui::TextDisabled("W/S insert/withdraw");
    ImGui::TextDisabled("arrows: pivot at the cervix");
    ImGui::TextDisabled("A/D roll (lens view), Q/E loop in/out");
    ImGui::TextDisabled("hold C or Left-Shift: CUT");
  } else {
    ImGui::TextDisabled("scope follows the scene's scripted path");
  }
  ImGui::Checkbox("details (I)", &panel.details);
  ImGui::TextDisabled("X: force e-stop, F: reset force");
  ImGui::TextDisabled("Enter: end the case (debrief), Esc: quit");
}

// The developer's numbers, shown with "details": step time, substeps, pacing, forces,
// numerical warnings, the force-feedback thread.
void drawDetails(const engine::Scene& scene, const engine::Simulation& sim, const FrameNumbers& n,
                 AppHaptics& force_feedback) {
  const sim::State& st = sim.state();
  ImGui::Text("sim time     %8.3f s", st.time);
  ImGui::Text("steps        %8llu  (dt %.3g ms)", static_cast<unsigned long long>(st.steps), 1e3 * scene.sim.dt);
  ImGui::Text("step time    %8.1f us  (median of %d)", n.step_median_us, n.step_window);
  ImGui::Text("substeps     %8d", sim.model().substeps);
  ImGui::Text("real time    %8.2f x", n.realtime);
  ImGui::Text("frame        %8.1f ms", n.frame_ms);
  if (n.behind_s > 0.05) {
    // The simulation is never skipped ahead: a too slow machine runs in slow motion.
    ImGui::TextColored(ImVec4(1.0f, 0.75f, 0.3f, 1.0f), "behind real time by %.2f s", n.behind_s);
  }
  ImGui::Text("tool force   %8.3f N", n.tool_force_n);
  ImGui::Text("max force    %8.3f N", n.max_force_n);
  force_feedback.drawPanel();
  if (st.warnings > 0) {
    ImGui::TextColored(ImVec4(1.0f, 0.35f, 0.3f, 1.0f), "numerical warnings %d", st.warnings);
  } else {
    ImGui::Text("numerical warnings %d", st.warnings);
  }
}

}  // namespace

// The panel: the case, the trainee's guidance, the controller, the controls, and the details.
void drawPanel(const engine::Scene& scene, const engine::Simulation& sim, Panel& panel, const FrameNumbers& n,
               const GuidanceView& guidance, AppHaptics& force_feedback,
               const AppGamepad& gamepad, const AppRecording& recording, const AppSessionStore& store,
               double path_end_s, float panel_w, float panel_h) {
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImVec2(panel_w, panel_h));
  ImGui::Begin("hysim", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  ImGui::TextWrapped("%s", scene.description.empty() ? scene.name.c_str() : scene.description.c_str());
  if (panel.paused) ImGui::TextColored(ImVec4(0.4f, 0.8f, 1.0f, 1.0f), "PAUSED");
  ImGui::Separator();
  drawGuidance(guidance);
  ImGui::Separator();
  const char* path = gamepad.active()              ? "game controller"
                     : panel.manual                ? "keyboard"
                     : sim.state().time < path_end_s ? "scripted demo"
                                                     : "demo done (Enter: debrief)";
  ImGui::Text("scope        %s", path);
  if (gamepad.active()) gamepad.drawPanel();
  recording.drawPanel();
  store.drawPanel();
  ImGui::Separator();
  drawControls(panel);
  if (panel.details) {
    ImGui::Separator();
    drawDetails(scene, sim, n, force_feedback);
  }
  ImGui::End();
}

}  // namespace hysim::tools
