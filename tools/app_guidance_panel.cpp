#include "app_guidance_panel.hpp"

#include <cmath>
#include <cstdio>

namespace hysim::tools {

namespace {

const ImVec4 kGreen(0.35f, 0.85f, 0.4f, 1.0f);
const ImVec4 kAmber(1.0f, 0.7f, 0.15f, 1.0f);
const ImVec4 kRed(1.0f, 0.25f, 0.2f, 1.0f);

ImVec4 levelColour(SerosaLevel level) {
  return level == SerosaLevel::Danger ? kRed : level == SerosaLevel::Caution ? kAmber : kGreen;
}

void drawSerosaBar(const GuidanceView& v) {
  const SerosaBar bar = serosaBar(v.serosa_mm, v.margin_mm);
  char label[48];
  if (std::isfinite(v.serosa_mm)) {
    std::snprintf(label, sizeof(label), "%.1f mm", v.serosa_mm);
  } else {
    std::snprintf(label, sizeof(label), "far");
  }
  ImGui::Text("loop to serosa");
  ImGui::PushStyleColor(ImGuiCol_PlotHistogram, levelColour(bar.level));
  ImGui::ProgressBar(static_cast<float>(bar.fill), ImVec2(-1, 0), label);
  ImGui::PopStyleColor();
  if (bar.level == SerosaLevel::Danger) ImGui::TextColored(kRed, "TOO CLOSE TO THE SEROSA");
  else if (bar.level == SerosaLevel::Caution) ImGui::TextColored(kAmber, "near the serosa: shallower cuts");
}

}  // namespace

void drawGuidance(const GuidanceView& v) {
  const GuidanceNumbers& n = v.numbers;
  if (v.cutting) ImGui::TextColored(kRed, "CUT  (electrode active)");
  else ImGui::TextDisabled("electrode off  (C / L-Shift: cut)");
  ImGui::Text("myoma resected   %5.1f %%", n.myoma_resected_pct);
  ImGui::ProgressBar(static_cast<float>(n.myoma_resected_pct / 100.0), ImVec2(-1, 0), "");
  ImGui::Text("healthy removed  %5.0f mm3", n.healthy_removed_mm3);
  ImGui::Text("time             %5.0f:%02d", std::floor(n.elapsed_s / 60.0), static_cast<int>(n.elapsed_s) % 60);
  ImGui::Text("electrode on     %5.1f s", n.electrode_active_s);
  ImGui::Text("chips removed    %5d", n.chips);
  drawSerosaBar(v);
  if (n.perforations > 0) {
    ImGui::TextColored(kRed, "perforations     %5d", n.perforations);
  } else {
    ImGui::Text("perforations     %5d", n.perforations);
  }
  if (v.alarm) ImGui::TextColored(kRed, "PERFORATION: withdraw the loop");
  if (v.scope_at_wall) ImGui::TextColored(kAmber, "scope held back at the wall");
}

void drawViewOverlay(const GuidanceView& v, const ViewRect& rect, double wall_s) {
  ImDrawList* draw = ImGui::GetForegroundDrawList();
  if (v.alarm) {
    const float pulse = 0.8f + 0.2f * static_cast<float>(std::sin(wall_s * 12.0));
    draw->AddRect(rect.min, rect.max, ImGui::GetColorU32(ImVec4(1.0f, 0.1f, 0.05f, pulse)), 0.0f, 0, 14.0f);
    draw->AddText(ImGui::GetFont(), 28.0f, ImVec2(rect.min.x + 24, rect.max.y - 52),
                  ImGui::GetColorU32(kRed), "PERFORATION");
  }
  if (v.cutting) {
    const ImVec2 a(rect.min.x + 20, rect.min.y + 20), b(rect.min.x + 100, rect.min.y + 58);
    draw->AddRectFilled(a, b, ImGui::GetColorU32(ImVec4(0.85f, 0.1f, 0.05f, 0.9f)), 4.0f);
    draw->AddText(ImGui::GetFont(), 28.0f, ImVec2(a.x + 12, a.y + 5), IM_COL32_WHITE, "CUT");
  }
  if (v.scope_at_wall) {
    draw->AddText(ImGui::GetFont(), 20.0f, ImVec2(rect.min.x + 24, rect.min.y + 70), ImGui::GetColorU32(kAmber),
                  "scope at the wall");
  }
}

}  // namespace hysim::tools
