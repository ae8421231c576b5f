#include "app_alarm.hpp"

namespace hysim::tools {

bool PerforationAlarm::observe(int perforation_count, bool perforating, double time_s) {
  perforating_ = perforating;
  if (perforating) last_open_s_ = time_s;
  if (perforation_count <= seen_) return false;
  seen_ = perforation_count;
  ++raised_;
  raised_at_s_ = time_s;
  last_open_s_ = time_s;
  return true;
}

}  // namespace hysim::tools
