#include "hysim/haptics/device.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace hysim::haptics {

Eigen::Vector3d safeForce(const Eigen::Vector3d& force_n, double max_n) {
  if (!force_n.allFinite() || !(max_n > 0.0)) return Eigen::Vector3d::Zero();
  const double norm = force_n.norm();
  return norm > max_n ? Eigen::Vector3d(force_n * (max_n / norm)) : force_n;
}

DeviceInfo ScriptedDevice::defaultInfo() {
  DeviceInfo info;
  info.name = "scripted";
  return info;
}

ScriptedDevice::ScriptedDevice(Trajectory trajectory, DeviceInfo info)
    : trajectory_(std::move(trajectory)), info_(std::move(info)) {}

DeviceState ScriptedDevice::read(double t) {
  constexpr double h = 0.5e-3;  // half of the 1 ms difference interval
  DeviceState s;
  s.time_s = t;
  s.pose = trajectory_.sample(t);
  const ToolPose before = trajectory_.sample(t - h);
  const ToolPose after = trajectory_.sample(t + h);
  s.velocity_mm_s = (after.tip - before.tip) / (2.0 * h);
  s.extension_velocity_mm_s = (after.extension_mm - before.extension_mm) / (2.0 * h);
  const Eigen::AngleAxisd turn(after.rotation * before.rotation.transpose());
  s.angular_velocity_rad_s = turn.axis() * (turn.angle() / (2.0 * h));
  s.buttons = s.pose.pedal ? 1u : 0u;
  return s;
}

}  // namespace hysim::haptics
