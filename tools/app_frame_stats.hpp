#pragma once
// How smoothly a case ran: the frames drawn and how long each took, against the simulated time
// the simulation thread stepped. Printed when a case ends (the trainer's frame-rate figures).
#include <string>
#include <vector>

namespace hysim::tools {

class FrameStats {
 public:
  void addFrame(double wall_s) { frame_s_.push_back(wall_s); }
  // The summary line: frames, their rate, the median and 95th-percentile frame time, and the
  // real-time factor (simulated seconds per wall second while not paused).
  std::string summary(int width, int height, double sim_s, double run_wall_s, double behind_s) const;
  double fps() const;           // frames per wall second over all frames
  double percentileMs(double p) const;  // p in [0, 1]
  long frames() const { return static_cast<long>(frame_s_.size()); }

 private:
  std::vector<double> frame_s_;
};

}  // namespace hysim::tools
