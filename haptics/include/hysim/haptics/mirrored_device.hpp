#pragma once
// A device with no hardware behind it, for a haptic loop that runs before a hardware device is
// attached (the trainee app with the keyboard or the script): the thread that owns the real
// input (the simulation's) publishes the state that input had, and the haptic loop reads it as
// if a hand held it there. The whole force pipeline (local model, watchdog, safety gate) then
// runs as it will with hardware; the force it commands is kept for display.
#include <Eigen/Core>
#include <atomic>

#include "hysim/haptics/device.hpp"
#include "hysim/haptics/latest_value.hpp"

namespace hysim::haptics {

class MirroredDevice final : public Device {
 public:
  explicit MirroredDevice(DeviceInfo info = defaultInfo());
  static DeviceInfo defaultInfo();

  // The one writer thread: the input's newest state.
  void publish(const DeviceState& state) { states_.publish(state); }

  // The one reader thread (the haptic loop): the newest published state, whatever time_s
  // asks for; a state at rest at the origin until the first publish.
  const DeviceInfo& info() const override { return info_; }
  DeviceState read(double time_s) override;
  void commandForce(const Eigen::Vector3d& force_n) override;
  const Eigen::Vector3d& lastForce() const override { return last_force_; }  // haptic thread only

  // Any thread: the magnitude of the force last commanded, newtons.
  double renderedForceN() const { return rendered_n_.load(std::memory_order_relaxed); }

 private:
  DeviceInfo info_;
  LatestValue<DeviceState> states_;
  DeviceState state_;
  Eigen::Vector3d last_force_{0, 0, 0};
  std::atomic<double> rendered_n_{0.0};
};

}  // namespace hysim::haptics
