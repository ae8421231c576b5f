#include "app_debrief.hpp"

#include <imgui.h>

#include <algorithm>
#include <filesystem>
#include <optional>

#include "app_screen.hpp"

namespace hysim::tools {
namespace {

const ImVec4 kGreen(0.35f, 0.85f, 0.4f, 1.0f);
const ImVec4 kRed(1.0f, 0.35f, 0.3f, 1.0f);
const ImVec4 kAmber(1.0f, 0.75f, 0.3f, 1.0f);

void drawVerdict(const CaseResult& r) {
  ImGui::Text("%s, %s", r.case_name.c_str(), r.hands_on ? "hands-on" : "scripted demo");
  ImGui::SetWindowFontScale(2.0f);
  ImGui::TextColored(r.assessment.passed ? kGreen : kRed, "%s", r.assessment.passed ? "PASS" : "FAIL");
  ImGui::SameLine();
  ImGui::Text("  score %.0f of 100", r.assessment.score);
  ImGui::SetWindowFontScale(1.0f);
}

void drawItems(const CaseResult& r) {
  const ImGuiTableFlags flags = ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersInnerH | ImGuiTableFlags_SizingFixedFit;
  if (!ImGui::BeginTable("items", 5, flags)) return;
  for (const char* header : {"metric", "yours", "threshold", "", "part of the score"}) ImGui::TableSetupColumn(header);
  ImGui::TableHeadersRow();
  for (const DebriefRow& row : debriefRows(r.assessment)) {
    ImGui::TableNextRow();
    ImGui::TableSetColumnIndex(0);
    ImGui::TextUnformatted(row.label.c_str());
    ImGui::TableSetColumnIndex(1);
    ImGui::TextUnformatted(row.value.c_str());
    ImGui::TableSetColumnIndex(2);
    ImGui::TextUnformatted(row.threshold.c_str());
    ImGui::TableSetColumnIndex(3);
    ImGui::TextColored(row.met ? kGreen : kRed, "%s", row.met ? "met" : "NOT met");
    ImGui::TableSetColumnIndex(4);
    ImGui::Text("%3.0f %% of weight %.0f %%", row.score_pct, row.weight_pct);
  }
  ImGui::EndTable();
  const GuidanceNumbers& n = r.numbers;
  ImGui::Text("electrode active %.1f s, %d passes, %d chips", n.electrode_active_s, n.passes, n.chips);
}

// The assessment's threshold for the myoma resected, % (0 when the scene has none).
double resectionThreshold(const engine::Assessment& a) {
  for (const engine::AssessmentItem& i : a.items)
    if (i.name == "resection") return i.threshold;
  return 0.0;
}

// Two bar plots, one bar per committed pass (hover a bar for its value), each under its caption.
void drawTimeline(const PassTimeline& t, double threshold_pct, float width) {
  if (t.resected_pct.empty()) {
    ImGui::Text("per pass");
    ImGui::TextDisabled("no pass was committed (the electrode never cut through tissue)");
    return;
  }
  ImGui::Text("myoma resected so far, per pass: %.1f %% after pass %zu (to pass: %.0f %%)", t.resected_pct.back(),
              t.resected_pct.size(), threshold_pct);
  ImGui::PlotHistogram("##resected", t.resected_pct.data(), static_cast<int>(t.resected_pct.size()), 0, nullptr, 0.0f,
                       resectionPlotTop(t, threshold_pct), ImVec2(width, 110.0f));
  ImGui::Text("healthy tissue removed by each pass, mm3 (largest %.1f)", t.max_healthy_mm3);
  ImGui::PlotHistogram("##healthy", t.healthy_mm3.data(), static_cast<int>(t.healthy_mm3.size()), 0, nullptr, 0.0f,
                       std::max(1.0f, t.max_healthy_mm3 * 1.1f), ImVec2(width, 80.0f));
  ImGui::TextDisabled("passes ended at %.1f s ... %.1f s of simulated time", t.time_s.front(), t.time_s.back());
}

class DebriefScreen final : public Screen {
 public:
  DebriefScreen(const CaseResult& r, const std::string& message) : r_(r), message_(message) {}
  void onKey(SDL_Keycode key) override {
    switch (key) {
      case SDLK_p: choose(DebriefAction::Replay); break;
      case SDLK_r: choose(DebriefAction::Restart); break;
      case SDLK_c: choose(DebriefAction::Cases); break;
      case SDLK_ESCAPE: choose(DebriefAction::Quit); break;
      default: break;
    }
  }
  void draw(float w, float h) override;
  bool done() const override { return action_.has_value(); }
  DebriefAction action() const { return action_.value_or(DebriefAction::Quit); }

 private:
  void choose(DebriefAction a) {
    if (a != DebriefAction::Replay || !r_.recording.empty()) action_ = a;
  }
  void drawButtons();
  const CaseResult& r_;
  std::string message_;
  std::optional<DebriefAction> action_;
};

void DebriefScreen::drawButtons() {
  if (!r_.recording.empty()) {
    ImGui::TextDisabled("recording %s", std::filesystem::path(r_.recording).filename().c_str());
  } else {
    ImGui::TextColored(kAmber, "not recorded: %s", r_.recording_problem.c_str());
  }
  if (!message_.empty()) ImGui::TextColored(kAmber, "%s", message_.c_str());
  ImGui::BeginDisabled(r_.recording.empty());
  if (ImGui::Button("Replay (P)")) choose(DebriefAction::Replay);
  ImGui::EndDisabled();
  ImGui::SameLine();
  if (ImGui::Button("Restart the case (R)")) choose(DebriefAction::Restart);
  ImGui::SameLine();
  if (ImGui::Button("Back to the cases (C)")) choose(DebriefAction::Cases);
  ImGui::SameLine();
  if (ImGui::Button("Quit (Esc)")) choose(DebriefAction::Quit);
}

void DebriefScreen::draw(float w, float h) {
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImVec2(w, h));
  ImGui::Begin("Debrief", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  drawVerdict(r_);
  ImGui::Separator();
  drawItems(r_);
  ImGui::Separator();
  drawTimeline(r_.timeline, resectionThreshold(r_.assessment), std::max(200.0f, w - 40.0f));
  ImGui::Separator();
  drawButtons();
  ImGui::End();
}

}  // namespace

DebriefAction runDebrief(render::SdlWindow& window, render::ImGuiLayer& layer, const CaseResult& result,
                         const std::string& message, const StartScreenExit& exit) {
  SDL_SetWindowTitle(window.nativeWindow(), ("hysim - debrief - " + result.case_name).c_str());
  DebriefScreen screen(result, message);
  if (runScreen(window, layer, screen, exit)) return DebriefAction::Quit;
  return screen.action();
}

}  // namespace hysim::tools
