#pragma once
// The last gate before the motors, fed once per haptic tick. Forces switch on only after the
// command has been small for a few ticks and then ramp in, so the user never feels a jolt;
// a non-finite command or an emergency stop latches zero force until reset().
#include <Eigen/Core>
#include <cstdint>

namespace hysim::haptics {

enum class SafetyState {
  WaitingForSmall,  // output zero until the command has been small for engage_ticks ticks
  Ramping,          // output scaled from 0 to 1 over ramp_s
  Engaged,          // output = command (clamped)
  Fault,            // latched zero output: see FaultReason
  EStopped,         // latched zero output after eStop()
};
const char* safetyStateName(SafetyState state);

enum class FaultReason { None, NonFiniteCommand };
const char* faultReasonName(FaultReason reason);

struct ForceSafetyOptions {
  double max_force_n = 3.0;         // magnitude clamp, keeping direction
  double engage_threshold_n = 0.2;  // "small" command
  int engage_ticks = 3;             // consecutive small ticks before ramping in
  double ramp_s = 1.0;              // 0 = engage at once
};

class ForceSafety {
 public:
  explicit ForceSafety(ForceSafetyOptions options = {}) : options_(options) {}

  // The force to send for this tick's command at time now_ns. Allocates nothing.
  Eigen::Vector3d filter(const Eigen::Vector3d& command_n, std::int64_t now_ns);
  void eStop() { state_ = SafetyState::EStopped; }
  // Back to WaitingForSmall; clears the fault reason (the counters stay).
  void reset();

  SafetyState state() const { return state_; }
  FaultReason faultReason() const { return fault_; }
  long ticksClamped() const { return ticks_clamped_; }
  long faults() const { return faults_; }
  const ForceSafetyOptions& options() const { return options_; }

 private:
  Eigen::Vector3d waitForSmall(const Eigen::Vector3d& command_n, std::int64_t now_ns);
  double rampScale(std::int64_t now_ns);
  Eigen::Vector3d clamp(const Eigen::Vector3d& force_n);

  ForceSafetyOptions options_;
  SafetyState state_ = SafetyState::WaitingForSmall;
  FaultReason fault_ = FaultReason::None;
  int small_ticks_ = 0;
  std::int64_t ramp_start_ns_ = 0;
  long ticks_clamped_ = 0;
  long faults_ = 0;
};

}  // namespace hysim::haptics
