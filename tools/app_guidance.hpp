#pragma once
// The trainee's live numbers, taken from the simulation after a frame's steps: how much of the
// myoma is gone, how much healthy tissue went with it, time, electrode-active time, and how
// close the loop is to the serosa, as a bar that turns amber and then red.
#include <Eigen/Core>

#include "hysim/engine/simulation.hpp"

namespace hysim::tools {

struct GuidanceNumbers {
  double myoma_resected_pct = 0.0;   // of the initial myoma volume
  double myoma_resected_mm3 = 0.0;
  double healthy_removed_mm3 = 0.0;  // chips' volume that was not myoma
  double elapsed_s = 0.0;            // simulated time of the session
  double electrode_active_s = 0.0;   // pedal down
  int passes = 0;                    // committed cuts
  int chips = 0;                     // pieces removed
  int perforations = 0;              // events the engine opened
};

// The numbers of the committed passes (a cut still on the worker counts once committed).
GuidanceNumbers guidanceNumbers(const engine::Simulation& sim);

// Distance of the loop's wire from the serosa, mm (< 0: beyond it), at the tool's pose.
// `wire` is scratch reused between calls.
double serosaDistanceMm(const engine::Simulation& sim, Eigen::Matrix<double, Eigen::Dynamic, 3>& wire);

enum class SerosaLevel { Safe, Caution, Danger };

struct SerosaBar {
  double fill = 1.0;  // 0 (at the serosa) .. 1 (kBarRangeMargins margins or farther)
  SerosaLevel level = SerosaLevel::Safe;
};

// The bar spans this many perforation margins; amber within kCautionMargins margins, red
// within one margin: where the engine opens a perforation event while cutting.
inline constexpr double kBarRangeMargins = 5.0;
inline constexpr double kCautionMargins = 2.0;
SerosaBar serosaBar(double distance_mm, double margin_mm);

}  // namespace hysim::tools
