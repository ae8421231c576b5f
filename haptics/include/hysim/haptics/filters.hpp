#pragma once
// Filters between a device and the simulation (as OpenSurgSim's input components do): scale
// the hand's motion, map the device's workspace into the world (the scope's pivot frame), and
// limit how far the tool may move between two reads, so a jump in the device's data (a
// glitch, a reconnect, a bridge restarting) never teleports the tool into tissue.
#include <Eigen/Core>
#include <memory>

#include "hysim/haptics/device.hpp"

namespace hysim::haptics {

// Motion scaling about a centre, in the device's frame: positions and velocities scale,
// orientations do not (a 0.5 scale halves how far the tip travels, not how it turns).
struct MotionScale {
  double scale = 1.0;
  Eigen::Vector3d center_mm{0, 0, 0};
  DeviceState apply(DeviceState state) const;
};

// Device frame to world: x_world = rotation * x_device + translation.
struct PoseTransform {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation_mm{0, 0, 0};
  DeviceState apply(DeviceState state) const;
  // A world force in the device's frame (what its motors render).
  Eigen::Vector3d forceToDevice(const Eigen::Vector3d& world_force_n) const {
    return rotation.transpose() * world_force_n;
  }
};

// Keeps the tip's speed, the turn rate and the loop's extension rate at most the given
// limits between consecutive reads (by their time_s); the first read after construction or
// reset() passes unchanged. Limited reads are counted.
class MotionLimit {
 public:
  MotionLimit(double max_speed_mm_s = 500.0, double max_turn_rad_s = 6.0, double max_extension_mm_s = 100.0);
  DeviceState apply(const DeviceState& state);
  void reset() { has_last_ = false; }
  long limitedReads() const { return limited_; }

 private:
  double max_speed_, max_turn_, max_extension_;
  bool has_last_ = false;
  DeviceState last_;
  long limited_ = 0;
};

// A device seen through the filters: scale, then transform, then limit. Forces go back
// rotated into the device's frame. connected() and counters() are the inner device's.
class FilteredDevice final : public Device {
 public:
  FilteredDevice(std::unique_ptr<Device> inner, MotionScale scale, PoseTransform transform, MotionLimit limit);
  const DeviceInfo& info() const override { return inner_->info(); }
  DeviceState read(double time_s) override;
  void commandForce(const Eigen::Vector3d& force_n) override;
  const Eigen::Vector3d& lastForce() const override { return last_force_; }
  bool connected() const override { return inner_->connected(); }
  DeviceCounters counters() const override { return inner_->counters(); }
  const MotionLimit& limit() const { return limit_; }
  Device& inner() { return *inner_; }

 private:
  std::unique_ptr<Device> inner_;
  MotionScale scale_;
  PoseTransform transform_;
  MotionLimit limit_;
  Eigen::Vector3d last_force_{0, 0, 0};
};

}  // namespace hysim::haptics
