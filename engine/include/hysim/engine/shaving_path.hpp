#pragma once
// `tool_path: auto`: a level-by-level loop resection of a generated organ's myomas, the same
// passes tools/make-shaving-path writes for the pre-meshed organ, for a myoma on any wall.
// The scope pivots at the internal os; each pass (2 s) pushes the loop out beyond the myoma,
// presses the pedal, dips to the pass's depth, draws the loop back towards the sheath and
// lifts it out, so the chip comes free. Levels go from the myoma's cavity side towards its
// base, stopping short of the serosa by the perforation margin and a safety distance.
#include <vector>

#include "hysim/engine/organ.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/haptics/trajectory.hpp"

namespace hysim::engine {

struct ShavingPlan {
  double level_step_mm = 1.5;     // between levels, along the wall's normal
  double pass_spacing_mm = 3.0;   // between passes on a level, side to side
  double edge_mm = 1.5;           // outermost loop centres this far inside the myoma's outline
  double lift_mm = 4.0;           // the loop enters and leaves this far above the pass's depth
  double serosa_safety_mm = 2.5;  // deepest loop point: this plus the perforation margin from the serosa
};

// Keyframes for every myoma the loop can reach from the cavity (FIGO 0 to 4 and 2-5), in the
// order given; empty when there is none.
std::vector<haptics::Keyframe> planShavingPath(const OrganSpec& organ, const ContactSettings& contact,
                                               double perforation_margin_mm, const ShavingPlan& plan = {});

// The scope's pivot (the internal os) and the tip's depth beyond it, for an organ.
Eigen::Vector3d scopePivot(const UterusSpec& u);
double scopeTipMm(const UterusSpec& u);

}  // namespace hysim::engine
