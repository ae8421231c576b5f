#pragma once
// What the trainee sees besides the scope view: the guidance section of the panel (resected,
// healthy tissue removed, time, electrode time, the serosa bar, perforations) and the overlay
// on the view (a CUT label while the electrode is active, a pulsing red rim while the
// perforation alarm is on, a note when the scope is stopped at the wall). ImGui drawing only.
#include <imgui.h>

#include "app_guidance.hpp"

namespace hysim::tools {

struct ViewRect {
  ImVec2 min, max;  // screen coordinates
};

struct GuidanceView {
  GuidanceNumbers numbers;
  double serosa_mm = 0.0;
  double margin_mm = 2.0;
  bool cutting = false;        // electrode active (pedal down)
  bool alarm = false;          // perforation alarm on
  bool scope_at_wall = false;  // the keyboard scope was held back from the tissue (ahead or beside)
};

void drawGuidance(const GuidanceView& view);
// `wall_s` makes the rim pulse.
void drawViewOverlay(const GuidanceView& view, const ViewRect& rect, double wall_s);

}  // namespace hysim::tools
