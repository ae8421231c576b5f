#include "hysim/haptics/mirrored_device.hpp"

#include <utility>

namespace hysim::haptics {

DeviceInfo MirroredDevice::defaultInfo() {
  DeviceInfo info;
  info.name = "mirrored (no hardware)";
  return info;
}

MirroredDevice::MirroredDevice(DeviceInfo info) : info_(std::move(info)) {}

DeviceState MirroredDevice::read(double /*time_s*/) {
  states_.read(state_);  // keeps the previous state when nothing new arrived
  return state_;
}

void MirroredDevice::commandForce(const Eigen::Vector3d& force_n) {
  last_force_ = safeForce(force_n, info_.max_force_n);
  rendered_n_.store(last_force_.norm(), std::memory_order_relaxed);
}

}  // namespace hysim::haptics
