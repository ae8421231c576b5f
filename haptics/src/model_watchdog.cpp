#include "hysim/haptics/model_watchdog.hpp"

#include <algorithm>
#include <cmath>

namespace hysim::haptics {

ModelWatchdog::ModelWatchdog(double watchdog_s, double fade_s)
    : watchdog_ns_(std::llround(watchdog_s * 1e9)),
      fade_ns_(std::max<std::int64_t>(std::llround(fade_s * 1e9), 0)),
      level_ns_(std::max<std::int64_t>(fade_ns_, 1)) {}

double ModelWatchdog::scale() const {
  if (fade_ns_ == 0) return level_ns_ > 0 ? 1.0 : 0.0;
  return static_cast<double>(level_ns_) / static_cast<double>(fade_ns_);
}

double ModelWatchdog::update(bool new_model, std::int64_t now_ns) {
  if (!started_) {
    // Silence counts from the first tick, so a simulation that never publishes still trips.
    started_ = true;
    last_tick_ns_ = now_ns;
    last_model_ns_ = now_ns;
  }
  if (new_model) last_model_ns_ = now_ns;
  const std::int64_t dt_ns = std::max<std::int64_t>(now_ns - last_tick_ns_, 0);
  const std::int64_t silence_ns = now_ns - last_model_ns_;
  last_tick_ns_ = now_ns;
  if (fade_ns_ == 0) {
    level_ns_ = silence_ns > watchdog_ns_ ? 0 : 1;
  } else if (silence_ns <= watchdog_ns_) {
    level_ns_ = std::min(level_ns_ + dt_ns, fade_ns_);
  } else {
    // Only the part of this tick's interval past the watchdog time fades.
    level_ns_ = std::max<std::int64_t>(level_ns_ - std::min(dt_ns, silence_ns - watchdog_ns_), 0);
  }
  return scale();
}

}  // namespace hysim::haptics
