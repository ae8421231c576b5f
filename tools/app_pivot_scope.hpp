#pragma once
// The keyboard scope of the trainee app: a PivotScopeDevice that pivots where the scene's
// course pivots (the cervix), tilting within a cone about the cavity's long axis, its depth
// limited each frame to the free space in front of the tip.
#include "hysim/engine/simulation.hpp"
#include "hysim/haptics/pivot_device.hpp"
#include "hysim/render/snapshot.hpp"

namespace hysim::tools {

// The instrument's front stops this far short of the tissue in front of it.
inline constexpr double kFrontClearanceMm = 2.0;

// Puts a pivot device in charge of the simulation's tool, from the device's current pose.
// Returns it (owned by the simulation).
haptics::PivotScopeDevice* attachPivotScope(engine::Simulation& sim);

// What of the instrument meets the tissue: the loop, loop_reach_mm plus its extension ahead
// of the tip, and the shaft's radius around it.
struct ScopeSize {
  double loop_reach_mm = 12.0;
  double shaft_radius_mm = 4.0;
};
ScopeSize scopeSize(const engine::Simulation& sim);

// Before a frame's steps: the scope's limits from the tissue surface as last drawn. Insertion
// stops when the loop would push into the tissue ahead (extending the loop is how it cuts);
// pivoting stops when the shaft's side would reach the wall beside the tip.
void limitScope(haptics::PivotScopeDevice& scope, const render::SurfaceMesh& tissue, const ScopeSize& size);

}  // namespace hysim::tools
