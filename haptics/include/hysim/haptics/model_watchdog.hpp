#pragma once
// Fades out the nominal force F0 of the local force model when the simulation stops
// publishing new models (a stalled step must not leave a stale push on the user's hand); the
// local spring and damper stay, since they only react to the user's own motion.
#include <cstdint>

namespace hysim::haptics {

class ModelWatchdog {
 public:
  explicit ModelWatchdog(double watchdog_s = 0.05, double fade_s = 0.01);

  // Called once per haptic tick; new_model = a model with a new step arrived at this tick.
  // Returns the scale for F0: 1 while models keep coming, falling linearly to 0 over fade_s
  // once none has arrived for watchdog_s, and climbing back at the same rate when they return.
  double update(bool new_model, std::int64_t now_ns);
  double scale() const;

 private:
  // Integer nanoseconds, so the scale reaches exactly 0 and 1.
  std::int64_t watchdog_ns_;
  std::int64_t fade_ns_;
  std::int64_t level_ns_;  // scale * fade_ns_
  bool started_ = false;
  std::int64_t last_tick_ns_ = 0;
  std::int64_t last_model_ns_ = 0;
};

}  // namespace hysim::haptics
