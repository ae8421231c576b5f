#include "app_progress.hpp"

#include <imgui.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#include "app_progress_data.hpp"
#include "app_screen.hpp"
#include "session_store.hpp"

namespace hysim::tools {
namespace {

const ImVec4 kGreen(0.35f, 0.85f, 0.4f, 1.0f);
const ImVec4 kRed(1.0f, 0.35f, 0.3f, 1.0f);
const ImVec4 kAmber(1.0f, 0.75f, 0.3f, 1.0f);

// The trainee's sessions, newest first, or why they cannot be read.
struct Loaded {
  std::vector<SessionRecord> sessions;
  std::vector<CaseTrend> trends;
  std::string problem;
};

Loaded loadSessions(const std::string& data_dir, const std::string& trainee) {
  Loaded l;
  SessionStore store(data_dir.empty() ? defaultDataFolder() : data_dir);
  if (Status st = store.open(); !st.ok()) {
    l.problem = st.error();
    return l;
  }
  auto listed = store.list(trainee);
  if (!listed.ok()) {
    l.problem = listed.error();
    return l;
  }
  l.trends = caseTrends(*listed);
  l.sessions = newestFirst(std::move(listed.value()));
  return l;
}

void drawTrends(const std::vector<CaseTrend>& trends, float width) {
  for (const CaseTrend& t : trends) {
    ImGui::Text("%s: %zu finished session%s, %d passed", t.case_name.c_str(), t.scores.size(),
                t.scores.size() == 1 ? "" : "s", t.passed);
    if (t.incomplete > 0) {
      ImGui::SameLine();
      ImGui::TextColored(kAmber, "(%d incomplete)", t.incomplete);
    }
    if (t.scores.empty()) continue;
    ImGui::Text("  score best %.0f, last %.0f, mean %.0f", t.best, t.last, t.mean);
    if (t.scores.size() >= 2) {
      ImGui::PushID(t.case_name.c_str());
      ImGui::PlotLines("score 0..100, oldest to newest", t.scores.data(), static_cast<int>(t.scores.size()), 0,
                       nullptr, 0.0f, 100.0f, ImVec2(width, 60.0f));
      ImGui::PopID();
    }
  }
}

void drawSessionRow(const SessionRecord& s) {
  ImGui::TableNextRow();
  ImGui::TableSetColumnIndex(0);
  ImGui::TextUnformatted(sessionDate(s.started_utc).c_str());
  ImGui::TableSetColumnIndex(1);
  ImGui::TextUnformatted(s.case_name.c_str());
  ImGui::TableSetColumnIndex(2);
  ImGui::TextUnformatted(s.mode.c_str());
  ImGui::TableSetColumnIndex(3);
  if (!s.complete) {
    ImGui::TextColored(kAmber, "incomplete");
    return;  // a killed session's numbers are what it had when it began: none to compare
  }
  ImGui::TextUnformatted("complete");
  ImGui::TableSetColumnIndex(4);
  ImGui::Text("%.1f", s.myoma_resected_pct);
  ImGui::TableSetColumnIndex(5);
  ImGui::Text("%.1f", s.healthy_removed_mm3);
  ImGui::TableSetColumnIndex(6);
  ImGui::Text("%d", s.perforations);
  ImGui::TableSetColumnIndex(7);
  ImGui::Text("%.0f", s.score);
  ImGui::TableSetColumnIndex(8);
  ImGui::TextColored(s.passed ? kGreen : kRed, "%s", s.passed ? "PASS" : "FAIL");
}

void drawSessions(const std::vector<SessionRecord>& sessions, float height) {
  const ImGuiTableFlags flags = ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersInnerH | ImGuiTableFlags_ScrollY |
                                ImGuiTableFlags_SizingStretchProp;
  if (!ImGui::BeginTable("sessions", 9, flags, ImVec2(0.0f, height))) return;
  ImGui::TableSetupScrollFreeze(0, 1);
  for (const char* header :
       {"date (UTC)", "case", "mode", "status", "resected %", "healthy mm3", "perforations", "score", "pass"}) {
    ImGui::TableSetupColumn(header);
  }
  ImGui::TableHeadersRow();
  for (const SessionRecord& s : sessions) drawSessionRow(s);
  ImGui::EndTable();
}

class ProgressScreen final : public Screen {
 public:
  ProgressScreen(Loaded loaded, std::string trainee) : l_(std::move(loaded)), trainee_(std::move(trainee)) {}
  void onKey(SDL_Keycode key) override {
    if (key == SDLK_b || key == SDLK_BACKSPACE) back_ = true;
    if (key == SDLK_ESCAPE) quit_ = true;
  }
  void draw(float w, float h) override;
  bool done() const override { return back_ || quit_; }
  bool back() const { return back_; }

 private:
  Loaded l_;
  std::string trainee_;
  bool back_ = false, quit_ = false;
};

void ProgressScreen::draw(float w, float h) {
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImVec2(w, h));
  ImGui::Begin("Progress", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  ImGui::Text("Sessions of %s", trainee_.c_str());
  ImGui::Separator();
  if (!l_.problem.empty()) {
    ImGui::TextColored(kRed, "The stored sessions cannot be read:");
    ImGui::TextWrapped("%s", l_.problem.c_str());
    ImGui::TextDisabled("(the session files are kept; fix or move the database and they are listed again)");
  } else if (l_.sessions.empty()) {
    ImGui::Text("No sessions stored yet. Finish a case and it is listed here.");
  } else {
    drawTrends(l_.trends, std::max(200.0f, w * 0.5f));
    ImGui::Separator();
    drawSessions(l_.sessions, std::max(120.0f, ImGui::GetContentRegionAvail().y - 40.0f));
  }
  if (ImGui::Button("Back to the cases (B)")) back_ = true;
  ImGui::SameLine();
  if (ImGui::Button("Quit (Esc)")) quit_ = true;
  ImGui::End();
}

}  // namespace

bool runProgress(render::SdlWindow& window, render::ImGuiLayer& layer, const std::string& data_dir,
                 const std::string& trainee, const StartScreenExit& exit) {
  SDL_SetWindowTitle(window.nativeWindow(), ("hysim - progress - " + trainee).c_str());
  ProgressScreen screen(loadSessions(data_dir, trainee), trainee);
  if (runScreen(window, layer, screen, exit)) return false;
  return screen.back();
}

}  // namespace hysim::tools
