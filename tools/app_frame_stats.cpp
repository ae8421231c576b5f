#include "app_frame_stats.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

namespace hysim::tools {

double FrameStats::fps() const {
  const double total = std::accumulate(frame_s_.begin(), frame_s_.end(), 0.0);
  return total > 0.0 ? static_cast<double>(frame_s_.size()) / total : 0.0;
}

double FrameStats::percentileMs(double p) const {
  if (frame_s_.empty()) return 0.0;
  std::vector<double> sorted = frame_s_;
  std::sort(sorted.begin(), sorted.end());
  const auto i = static_cast<std::size_t>(std::lround(std::clamp(p, 0.0, 1.0) * static_cast<double>(sorted.size() - 1)));
  return 1e3 * sorted[i];
}

std::string FrameStats::summary(int width, int height, double sim_s, double run_wall_s, double behind_s) const {
  char line[256];
  std::snprintf(line, sizeof line,
                "%dx%d: %ld frames, %.1f fps (frame median %.1f ms, p95 %.1f ms); real-time factor %.3f "
                "(%.2f s simulated in %.2f s), %.2f s given up",
                width, height, frames(), fps(), percentileMs(0.5), percentileMs(0.95),
                run_wall_s > 0.0 ? sim_s / run_wall_s : 0.0, sim_s, run_wall_s, behind_s);
  return line;
}

}  // namespace hysim::tools
