#include "hysim/haptics/filters.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace hysim::haptics {

DeviceState MotionScale::apply(DeviceState s) const {
  s.pose.tip = center_mm + scale * (s.pose.tip - center_mm);
  s.velocity_mm_s *= scale;
  return s;
}

DeviceState PoseTransform::apply(DeviceState s) const {
  s.pose.tip = rotation * s.pose.tip + translation_mm;
  s.pose.rotation = rotation * s.pose.rotation;
  s.velocity_mm_s = rotation * s.velocity_mm_s;
  s.angular_velocity_rad_s = rotation * s.angular_velocity_rad_s;
  return s;
}

MotionLimit::MotionLimit(double max_speed_mm_s, double max_turn_rad_s, double max_extension_mm_s)
    : max_speed_(max_speed_mm_s), max_turn_(max_turn_rad_s), max_extension_(max_extension_mm_s) {}

DeviceState MotionLimit::apply(const DeviceState& in) {
  if (!has_last_) {
    has_last_ = true;
    last_ = in;
    return in;
  }
  DeviceState out = in;
  const double dt = std::max(0.0, in.time_s - last_.time_s);
  bool limited = false;
  const Eigen::Vector3d move = in.pose.tip - last_.pose.tip;
  if (move.norm() > max_speed_ * dt) {
    out.pose.tip = last_.pose.tip + move * (max_speed_ * dt / move.norm());
    out.velocity_mm_s = dt > 0.0 ? Eigen::Vector3d((out.pose.tip - last_.pose.tip) / dt) : Eigen::Vector3d::Zero();
    limited = true;
  }
  const Eigen::Quaterniond from(last_.pose.rotation), to(in.pose.rotation);
  const double turn = from.angularDistance(to);
  if (turn > max_turn_ * dt) {
    out.pose.rotation = from.slerp(max_turn_ * dt / turn, to).toRotationMatrix();
    out.angular_velocity_rad_s = in.angular_velocity_rad_s.normalized() * std::min(in.angular_velocity_rad_s.norm(), max_turn_);
    if (!out.angular_velocity_rad_s.allFinite()) out.angular_velocity_rad_s.setZero();
    limited = true;
  }
  const double stretch = in.pose.extension_mm - last_.pose.extension_mm;
  if (std::abs(stretch) > max_extension_ * dt) {
    out.pose.extension_mm = last_.pose.extension_mm + std::copysign(max_extension_ * dt, stretch);
    out.extension_velocity_mm_s = std::copysign(std::min(std::abs(in.extension_velocity_mm_s), max_extension_), stretch);
    limited = true;
  }
  if (limited) ++limited_;
  last_ = out;
  return out;
}

FilteredDevice::FilteredDevice(std::unique_ptr<Device> inner, MotionScale scale, PoseTransform transform,
                               MotionLimit limit)
    : inner_(std::move(inner)), scale_(scale), transform_(transform), limit_(limit) {}

DeviceState FilteredDevice::read(double time_s) {
  return limit_.apply(transform_.apply(scale_.apply(inner_->read(time_s))));
}

void FilteredDevice::commandForce(const Eigen::Vector3d& force_n) {
  last_force_ = safeForce(force_n, inner_->info().max_force_n);
  inner_->commandForce(transform_.forceToDevice(last_force_));
}

}  // namespace hysim::haptics
