#include "app_start_screen.hpp"

#include <SDL.h>
#include <imgui.h>

#include <chrono>
#include <cstdio>
#include <cstring>

#include "hysim/render/image.hpp"

namespace hysim::tools {
namespace {

struct StartState {
  int selected = -1;
  bool hands_on = false;
  char trainee[64] = {};
  bool start = false, quit = false, progress = false;
};

bool startable(const std::vector<CaseInfo>& cases, int i) {
  return i >= 0 && i < static_cast<int>(cases.size()) && cases[i].error.empty();
}

// The next startable case from `from` in direction `step`, or `from` when there is none.
int nextStartable(const std::vector<CaseInfo>& cases, int from, int step) {
  for (int i = from + step; i >= 0 && i < static_cast<int>(cases.size()); i += step)
    if (startable(cases, i)) return i;
  return from;
}

void handleKey(SDL_Keycode key, const std::vector<CaseInfo>& cases, StartState& s) {
  switch (key) {
    case SDLK_ESCAPE: s.quit = true; break;
    case SDLK_UP: s.selected = nextStartable(cases, s.selected, -1); break;
    case SDLK_DOWN: s.selected = nextStartable(cases, s.selected, 1); break;
    case SDLK_h: s.hands_on = !s.hands_on; break;
    case SDLK_p: s.progress = true; break;
    case SDLK_RETURN:
    case SDLK_KP_ENTER: s.start = startable(cases, s.selected); break;
    default: break;
  }
}

void drawCaseTable(const std::vector<CaseInfo>& cases, StartState& s) {
  const ImGuiTableFlags flags = ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersInnerH | ImGuiTableFlags_SizingStretchProp;
  if (!ImGui::BeginTable("cases", 4, flags)) return;
  ImGui::TableSetupColumn("case", ImGuiTableColumnFlags_WidthFixed, 170.0f);
  ImGui::TableSetupColumn("FIGO", ImGuiTableColumnFlags_WidthFixed, 50.0f);
  ImGui::TableSetupColumn("difficulty", ImGuiTableColumnFlags_WidthFixed, 100.0f);
  ImGui::TableSetupColumn("description");
  ImGui::TableHeadersRow();
  for (int i = 0; i < static_cast<int>(cases.size()); ++i) {
    const CaseInfo& c = cases[i];
    ImGui::TableNextRow();
    ImGui::TableSetColumnIndex(0);
    ImGui::PushID(i);
    if (ImGui::Selectable(c.name.c_str(), s.selected == i, ImGuiSelectableFlags_SpanAllColumns) && startable(cases, i)) {
      s.selected = i;
    }
    ImGui::PopID();
    ImGui::TableSetColumnIndex(1);
    ImGui::TextUnformatted(c.figo_type.empty() ? "-" : c.figo_type.c_str());
    ImGui::TableSetColumnIndex(2);
    ImGui::TextUnformatted(c.difficulty.empty() ? "-" : c.difficulty.c_str());
    ImGui::TableSetColumnIndex(3);
    if (c.error.empty()) {
      ImGui::TextWrapped("%s", c.description.c_str());
    } else {
      ImGui::TextColored(ImVec4(1.0f, 0.5f, 0.4f, 1.0f), "cannot be started: %s", c.error.c_str());
    }
  }
  ImGui::EndTable();
}

void drawStartScreen(const std::vector<CaseInfo>& cases, StartState& s, float w, float h) {
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImVec2(w, h));
  ImGui::Begin("hysim: choose a case", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  ImGui::Text("Hysteroscopic myoma resection trainer");
  ImGui::Separator();
  ImGui::SetNextItemWidth(260.0f);
  ImGui::InputText("trainee", s.trainee, sizeof(s.trainee));
  ImGui::Spacing();
  drawCaseTable(cases, s);
  ImGui::Spacing();
  if (ImGui::RadioButton("scripted demo", !s.hands_on)) s.hands_on = false;
  ImGui::SameLine();
  if (ImGui::RadioButton("hands-on (keyboard scope; C or Left-Shift cuts)", s.hands_on)) s.hands_on = true;
  ImGui::Spacing();
  if (ImGui::Button("Start (Enter)") && startable(cases, s.selected)) s.start = true;
  ImGui::SameLine();
  if (ImGui::Button("My progress (P)")) s.progress = true;
  ImGui::SameLine();
  if (ImGui::Button("Quit (Esc)")) s.quit = true;
  ImGui::TextDisabled("Up/Down: choose a case, H: demo or hands-on. Your sessions are stored under your name.");
  ImGui::TextDisabled("In a case, Enter ends it and shows the debrief.");
  ImGui::End();
}

}  // namespace

StartChoice runStartScreen(render::SdlWindow& window, render::ImGuiLayer& layer, const std::vector<CaseInfo>& cases,
                           const StartChoice& last, const StartScreenExit& exit) {
  SDL_SetWindowTitle(window.nativeWindow(), "hysim");
  StartState s;
  std::strncpy(s.trainee, last.trainee.c_str(), sizeof(s.trainee) - 1);
  s.selected = startable(cases, last.index) ? last.index : nextStartable(cases, -1, 1);
  s.hands_on = last.hands_on;
  const auto start = std::chrono::steady_clock::now();
  for (long frame = 1; !s.start && !s.quit && !s.progress; ++frame) {
    SDL_Event event;
    while (SDL_PollEvent(&event)) {
      const bool taken = layer.processEvent(event);
      if (event.type == SDL_QUIT) s.quit = true;
      if (event.type == SDL_KEYDOWN && !taken && event.key.repeat == 0) handleKey(event.key.keysym.sym, cases, s);
    }
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const bool timed_out =
        (exit.quit_after_s >= 0.0 && elapsed >= exit.quit_after_s) || (exit.frames >= 0 && frame >= exit.frames);
    int w = 0, h = 0;
    SDL_GetWindowSize(window.nativeWindow(), &w, &h);
    window.clear(0.07f, 0.07f, 0.08f);
    layer.newFrame();
    drawStartScreen(cases, s, static_cast<float>(w), static_cast<float>(h));
    layer.render();
    if (timed_out && !exit.screenshot.empty()) {
      if (hysim::Status st = render::writePng(exit.screenshot, window.readBackBuffer()); !st.ok()) {
        std::printf("hysim-app: %s\n", st.error().c_str());
      }
    }
    window.swapBuffers();
    s.quit = s.quit || timed_out;
  }
  StartChoice c;
  c.quit = !s.start && (s.quit || !s.progress);
  c.progress = !s.start && !c.quit;
  c.index = s.selected;
  c.hands_on = s.hands_on;
  c.trainee = s.trainee;
  return c;
}

}  // namespace hysim::tools
