#include "app_guidance.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "hysim/engine/tool.hpp"

namespace hysim::tools {

GuidanceNumbers guidanceNumbers(const engine::Simulation& sim) {
  GuidanceNumbers g;
  double removed = 0.0;
  for (const engine::PassRecord& p : sim.passes()) {
    g.myoma_resected_mm3 += p.removed_myoma_mm3;
    removed += p.removed_mm3;
    g.chips += p.chips;
  }
  g.passes = static_cast<int>(sim.passes().size());
  const double initial = sim.initialMyomaVolume();
  g.myoma_resected_pct = initial > 0.0 ? 100.0 * g.myoma_resected_mm3 / initial : 0.0;
  g.healthy_removed_mm3 = std::max(0.0, removed - g.myoma_resected_mm3);
  g.elapsed_s = sim.state().time;
  g.electrode_active_s = sim.electrodeActiveSeconds();
  g.perforations = sim.perforations();
  return g;
}

double serosaDistanceMm(const engine::Simulation& sim, Eigen::Matrix<double, Eigen::Dynamic, 3>& wire) {
  if (sim.outerWall().empty()) return std::numeric_limits<double>::infinity();
  engine::loopPoints(sim.loop(), sim.toolPose(), wire);
  double nearest = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < wire.rows(); ++i) {
    nearest = std::min(nearest, sim.outerWall().signedDistance(wire.row(i).transpose()));
  }
  return nearest - sim.loop().wire_radius_mm;
}

SerosaBar serosaBar(double distance_mm, double margin_mm) {
  SerosaBar bar;
  const double range = kBarRangeMargins * margin_mm;
  bar.fill = range > 0.0 ? std::clamp(distance_mm / range, 0.0, 1.0) : 1.0;
  if (std::isnan(distance_mm)) bar.fill = 1.0;
  if (distance_mm < margin_mm) {
    bar.level = SerosaLevel::Danger;
  } else if (distance_mm < kCautionMargins * margin_mm) {
    bar.level = SerosaLevel::Caution;
  }
  return bar;
}

}  // namespace hysim::tools
