#include "hysim/haptics/device.hpp"

#include <Eigen/Geometry>
#include <algorithm>
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

DeviceInfo ManualDevice::defaultInfo() {
  DeviceInfo info;
  info.name = "manual (keyboard)";
  return info;
}

ManualDevice::ManualDevice(const ToolPose& start, double start_time_s, DeviceInfo info)
    : pose_(start), time_s_(start_time_s), info_(std::move(info)) {}

DeviceState ManualDevice::read(double t) {
  const double dt = t > time_s_ ? t - time_s_ : 0.0;
  time_s_ = std::max(time_s_, t);
  const Eigen::Matrix3d& r = pose_.rotation;
  DeviceState s;
  s.velocity_mm_s = r * command_.velocity_scope_mm_s;
  const Eigen::Vector3d omega = command_.yaw_rad_s * r.col(1) + command_.pitch_rad_s * r.col(0);
  s.angular_velocity_rad_s = omega;
  s.extension_velocity_mm_s = command_.extension_mm_s;
  pose_.tip += dt * s.velocity_mm_s;
  if (omega.norm() > 0.0) {
    pose_.rotation = Eigen::AngleAxisd(dt * omega.norm(), omega.normalized()).toRotationMatrix() * r;
  }
  pose_.extension_mm = std::clamp(pose_.extension_mm + dt * command_.extension_mm_s, 0.0, 20.0);
  pose_.pedal = command_.pedal;
  // Keep the tip inside the device's workspace.
  pose_.tip = pose_.tip.cwiseMax(info_.workspace_min_mm).cwiseMin(info_.workspace_max_mm);
  s.time_s = time_s_;
  s.pose = pose_;
  s.buttons = pose_.pedal ? 1u : 0u;
  return s;
}

}  // namespace hysim::haptics
