#include "hysim/haptics/trajectory.hpp"

#include <algorithm>
#include <cmath>

namespace hysim::haptics {

Eigen::Matrix3d frameFromAxisUp(const Eigen::Vector3d& axis, const Eigen::Vector3d& up) {
  const Eigen::Vector3d z = axis.normalized();
  Eigen::Vector3d y = up - up.dot(z) * z;
  if (y.norm() < 1e-9) {
    // up parallel to the axis: pick any perpendicular direction, deterministically.
    y = std::abs(z.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    y -= y.dot(z) * z;
  }
  y.normalize();
  Eigen::Matrix3d r;
  r.col(0) = y.cross(z);
  r.col(1) = y;
  r.col(2) = z;
  return r;
}

bool validArc(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Eigen::Vector3d& center) {
  const Eigen::Vector3d r0 = from - center, r1 = to - center;
  if (r0.norm() < 1e-9 || r1.norm() < 1e-9) return false;
  const double sin_angle = r0.normalized().cross(r1.normalized()).norm();
  const double cos_angle = r0.normalized().dot(r1.normalized());
  return sin_angle > 1e-6 && cos_angle > -1.0 + 1e-9;
}

namespace {

// Point at fraction s of the arc from `from` to `to` about `center`.
Eigen::Vector3d arcPoint(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Eigen::Vector3d& center,
                         double s) {
  const Eigen::Vector3d r0 = from - center, r1 = to - center;
  const Eigen::Vector3d axis = r0.cross(r1);
  if (axis.norm() < 1e-12) return (1.0 - s) * from + s * to;  // degenerate: a line
  const double angle = std::atan2(axis.norm(), r0.dot(r1));
  const double radius = (1.0 - s) * r0.norm() + s * r1.norm();
  const Eigen::Vector3d dir = Eigen::AngleAxisd(s * angle, axis.normalized()) * r0.normalized();
  return center + radius * dir;
}

}  // namespace

Trajectory::Trajectory(std::vector<Keyframe> keyframes) : keys_(std::move(keyframes)) {
  std::stable_sort(keys_.begin(), keys_.end(),
                   [](const Keyframe& a, const Keyframe& b) { return a.time_s < b.time_s; });
  orientations_.reserve(keys_.size());
  for (const Keyframe& k : keys_) {
    Eigen::Quaterniond q(frameFromAxisUp(k.axis, k.up));
    // Keep consecutive quaternions in the same hemisphere so slerp takes the short way.
    if (!orientations_.empty() && orientations_.back().dot(q) < 0.0) q.coeffs() *= -1.0;
    orientations_.push_back(q);
  }
}

ToolPose Trajectory::sample(double t) const {
  ToolPose pose;
  if (keys_.empty()) return pose;
  if (t <= keys_.front().time_s || keys_.size() == 1) {
    pose.tip = keys_.front().tip;
    pose.rotation = orientations_.front().toRotationMatrix();
    pose.extension_mm = keys_.front().extension_mm;
    pose.pedal = keys_.front().pedal;
    return pose;
  }
  if (t >= keys_.back().time_s) {
    pose.tip = keys_.back().tip;
    pose.rotation = orientations_.back().toRotationMatrix();
    pose.extension_mm = keys_.back().extension_mm;
    pose.pedal = keys_.back().pedal;
    return pose;
  }
  // First keyframe with time > t (binary search: no allocation).
  const auto it = std::upper_bound(keys_.begin(), keys_.end(), t,
                                   [](double value, const Keyframe& k) { return value < k.time_s; });
  const size_t i1 = static_cast<size_t>(it - keys_.begin());
  const size_t i0 = i1 - 1;
  const Keyframe& a = keys_[i0];
  const Keyframe& b = keys_[i1];
  const double span = b.time_s - a.time_s;
  const double s = span > 0.0 ? (t - a.time_s) / span : 1.0;
  pose.tip = b.move == Keyframe::Move::Arc ? arcPoint(a.tip, b.tip, b.arc_center, s) : (1.0 - s) * a.tip + s * b.tip;
  pose.rotation = orientations_[i0].slerp(s, orientations_[i1]).toRotationMatrix();
  pose.extension_mm = (1.0 - s) * a.extension_mm + s * b.extension_mm;
  pose.pedal = a.pedal;
  return pose;
}

}  // namespace hysim::haptics
