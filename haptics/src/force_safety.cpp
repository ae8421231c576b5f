#include "hysim/haptics/force_safety.hpp"

#include <algorithm>

namespace hysim::haptics {

const char* safetyStateName(SafetyState state) {
  switch (state) {
    case SafetyState::WaitingForSmall: return "waiting for a small force";
    case SafetyState::Ramping: return "ramping in";
    case SafetyState::Engaged: return "engaged";
    case SafetyState::Fault: return "fault";
    case SafetyState::EStopped: return "emergency stop";
  }
  return "unknown";
}

const char* faultReasonName(FaultReason reason) {
  switch (reason) {
    case FaultReason::None: return "none";
    case FaultReason::NonFiniteCommand: return "non-finite force command (NaN or Inf)";
  }
  return "unknown";
}

Eigen::Vector3d ForceSafety::filter(const Eigen::Vector3d& command_n, std::int64_t now_ns) {
  if (state_ == SafetyState::EStopped || state_ == SafetyState::Fault) return Eigen::Vector3d::Zero();
  if (!command_n.allFinite()) {
    state_ = SafetyState::Fault;
    fault_ = FaultReason::NonFiniteCommand;
    ++faults_;
    return Eigen::Vector3d::Zero();
  }
  if (state_ == SafetyState::WaitingForSmall) return waitForSmall(command_n, now_ns);
  if (state_ == SafetyState::Ramping) return clamp(rampScale(now_ns) * command_n);
  return clamp(command_n);
}

void ForceSafety::reset() {
  state_ = SafetyState::WaitingForSmall;
  fault_ = FaultReason::None;
  small_ticks_ = 0;
}

Eigen::Vector3d ForceSafety::waitForSmall(const Eigen::Vector3d& command_n, std::int64_t now_ns) {
  small_ticks_ = command_n.norm() < options_.engage_threshold_n ? small_ticks_ + 1 : 0;
  if (small_ticks_ >= options_.engage_ticks) {
    small_ticks_ = 0;
    state_ = options_.ramp_s > 0.0 ? SafetyState::Ramping : SafetyState::Engaged;
    ramp_start_ns_ = now_ns;
  }
  return Eigen::Vector3d::Zero();  // the ramp starts from zero at this tick
}

double ForceSafety::rampScale(std::int64_t now_ns) {
  const double scale = 1e-9 * static_cast<double>(now_ns - ramp_start_ns_) / options_.ramp_s;
  if (scale >= 1.0) {
    state_ = SafetyState::Engaged;
    return 1.0;
  }
  return std::max(scale, 0.0);
}

Eigen::Vector3d ForceSafety::clamp(const Eigen::Vector3d& force_n) {
  const double norm = force_n.norm();
  if (norm <= options_.max_force_n) return force_n;
  ++ticks_clamped_;
  return options_.max_force_n > 0.0 ? Eigen::Vector3d(force_n * (options_.max_force_n / norm))
                                     : Eigen::Vector3d::Zero();
}

}  // namespace hysim::haptics
