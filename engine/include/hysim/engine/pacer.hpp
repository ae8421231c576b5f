#pragma once
// Pacing a fixed-step simulation to the wall clock: wall time in, the number of steps due out.
// The physics never reads the clock; whoever steps it (the app's simulation thread) asks the
// pacer how many steps are due. A machine that cannot keep up runs in slow motion: simulated
// time due beyond `max_lag_s` is given up and counted, instead of piling up.
#include <algorithm>
#include <cmath>

namespace hysim::engine {

class Pacer {
 public:
  explicit Pacer(double dt_s = 1e-3, double max_lag_s = 0.1) : dt_(dt_s), max_lag_s_(max_lag_s) {}

  // Wall seconds since the last call (times the speed: simulated seconds per wall second) are
  // now due. Returns the steps due; the fraction of a step left stays due.
  int due(double wall_elapsed_s, double speed = 1.0) {
    accumulator_ += std::max(0.0, wall_elapsed_s) * speed;
    if (accumulator_ > max_lag_s_) {
      behind_s_ += accumulator_ - max_lag_s_;
      accumulator_ = max_lag_s_;
      ++lag_events_;
    }
    const int n = static_cast<int>(std::floor(accumulator_ / dt_));
    accumulator_ -= n * dt_;
    return n;
  }
  // Steps that were due but not done: due again at the next call.
  void keep(int not_stepped) { accumulator_ += std::max(0, not_stepped) * dt_; }
  // Simulated seconds until the next step is due (0: one is due now).
  double untilNextStep() const { return std::max(0.0, dt_ - accumulator_); }
  // Forget what is due (pause, reset); the lag counters stay.
  void clearDue() { accumulator_ = 0.0; }

  double dt() const { return dt_; }
  double behindS() const { return behind_s_; }  // simulated time given up, in total
  long lagEvents() const { return lag_events_; }  // calls that gave time up

 private:
  double dt_;
  double max_lag_s_;
  double accumulator_ = 0.0;  // simulated time due but not yet stepped
  double behind_s_ = 0.0;
  long lag_events_ = 0;
};

}  // namespace hysim::engine
