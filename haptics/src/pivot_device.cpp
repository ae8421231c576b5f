#include "hysim/haptics/pivot_device.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace hysim::haptics {

namespace {

double angleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

Eigen::Matrix3d rotated(const Eigen::Matrix3d& r, const Eigen::Vector3d& omega, double dt) {
  const double angle = dt * omega.norm();
  if (!(angle > 0.0)) return r;
  return Eigen::AngleAxisd(angle, omega.normalized()).toRotationMatrix() * r;
}

}  // namespace

DeviceInfo PivotScopeDevice::defaultInfo() {
  DeviceInfo info;
  info.name = "keyboard (pivot at the cervix)";
  return info;
}

PivotScopeDevice::PivotScopeDevice(const Eigen::Vector3d& trocar, const ToolPose& start, double start_time_s,
                                   const Eigen::Vector3d& reference_axis, PivotLimits limits, DeviceInfo info)
    : trocar_(trocar),
      reference_axis_(reference_axis.normalized()),
      limits_(limits),
      extension_mm_(std::clamp(start.extension_mm, 0.0, limits.max_extension_mm)),
      time_s_(start_time_s),
      info_(std::move(info)) {
  const Eigen::Vector3d to_tip = start.tip - trocar;
  const Eigen::Vector3d axis = to_tip.norm() > 1e-9 ? Eigen::Vector3d(to_tip.normalized()) : Eigen::Vector3d(start.rotation.col(2));
  rotation_ = frameFromAxisUp(axis, start.rotation.col(1));
  depth_ = std::max(to_tip.norm(), limits_.min_depth_mm);
}

ToolPose PivotScopeDevice::pose() const {
  ToolPose p;
  p.rotation = rotation_;
  p.tip = trocar_ + depth_ * rotation_.col(2);
  p.extension_mm = extension_mm_;
  p.pedal = command_.pedal;
  return p;
}

void PivotScopeDevice::setSideRoom(const Eigen::Vector3d& from, const std::array<Eigen::Vector3d, 4>& directions,
                                   const std::array<double, 4>& room_mm) {
  side_from_ = from;
  side_directions_ = directions;
  side_room_ = room_mm;
}

bool PivotScopeDevice::sideBlocked(const Eigen::Vector3d& tip_before, const Eigen::Vector3d& tip_after) const {
  for (std::size_t i = 0; i < side_room_.size(); ++i) {
    const double before = (tip_before - side_from_).dot(side_directions_[i]);
    const double after = (tip_after - side_from_).dot(side_directions_[i]);
    if (after > side_room_[i] && after > before) return true;
  }
  return false;
}

void PivotScopeDevice::turn(double dt) {
  const Eigen::Vector3d roll = command_.roll_rad_s * rotation_.col(2);
  const Eigen::Vector3d omega = command_.yaw_rad_s * rotation_.col(1) + command_.pitch_rad_s * rotation_.col(0) + roll;
  const Eigen::Matrix3d next = rotated(rotation_, omega, dt);
  const double tilt_before = angleBetween(rotation_.col(2), reference_axis_);
  const double tilt_after = angleBetween(next.col(2), reference_axis_);
  // Outside the cone only a turn back towards it is taken: the shaft would leave the cavity.
  tilt_limited_ = tilt_after > limits_.max_tilt_rad && tilt_after > tilt_before;
  side_limited_ = sideBlocked(trocar_ + depth_ * rotation_.col(2), trocar_ + depth_ * next.col(2));
  rotation_ = tilt_limited_ || side_limited_ ? rotated(rotation_, roll, dt) : next;
}

void PivotScopeDevice::insert(double dt) {
  const double wanted = depth_ + dt * command_.insert_mm_s;
  depth_limited_ = command_.insert_mm_s > 0.0 && wanted > depth_limit_;
  // The limit stops insertion; it never pulls the scope back (the tissue moved towards it).
  const double deepest = std::max(depth_, depth_limit_);
  depth_ = std::max(limits_.min_depth_mm, std::min(wanted, deepest));
}

DeviceState PivotScopeDevice::read(double t) {
  const double dt = t > time_s_ ? t - time_s_ : 0.0;
  time_s_ = std::max(time_s_, t);
  const ToolPose before = pose();
  turn(dt);
  insert(dt);
  extension_mm_ = std::clamp(extension_mm_ + dt * command_.extension_mm_s, 0.0, limits_.max_extension_mm);
  DeviceState s;
  s.time_s = time_s_;
  s.pose = pose();
  if (dt > 0.0) {
    s.velocity_mm_s = (s.pose.tip - before.tip) / dt;
    const Eigen::AngleAxisd turned(s.pose.rotation * before.rotation.transpose());
    s.angular_velocity_rad_s = turned.axis() * (turned.angle() / dt);
    s.extension_velocity_mm_s = (s.pose.extension_mm - before.extension_mm) / dt;
  }
  s.buttons = s.pose.pedal ? 1u : 0u;
  return s;
}

}  // namespace hysim::haptics
