#include "app_keys.hpp"

namespace hysim::tools {

namespace {
double axis(bool positive, bool negative) { return (positive ? 1.0 : 0.0) - (negative ? 1.0 : 0.0); }
}  // namespace

bool pedalDown(const TraineeKeys& keys) { return keys.pedal_c || keys.pedal_shift; }

haptics::PivotCommand pivotCommand(const TraineeKeys& keys, const KeyRates& rates) {
  haptics::PivotCommand c;
  c.insert_mm_s = rates.insert_mm_s * axis(keys.insert, keys.withdraw);
  // Positive yaw about the scope's up turns the view left; positive pitch turns it down.
  c.yaw_rad_s = rates.pivot_rad_s * axis(keys.pivot_left, keys.pivot_right);
  c.pitch_rad_s = rates.pivot_rad_s * axis(keys.pivot_down, keys.pivot_up);
  c.roll_rad_s = rates.roll_rad_s * axis(keys.roll_left, keys.roll_right);
  c.extension_mm_s = rates.loop_mm_s * axis(keys.loop_out, keys.loop_in);
  c.pedal = pedalDown(keys);
  return c;
}

}  // namespace hysim::tools
