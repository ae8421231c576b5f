#pragma once
// The haptic device layer: one interface for the scripted device, hardware drivers and
// replayed recordings. The engine reads the tool's pose, velocity and pedal from a Device
// and sends the reaction force back.
#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "hysim/haptics/trajectory.hpp"

namespace hysim::haptics {

// The loop electrode's extension beyond its rest position never exceeds this (mm): scenes,
// recordings and devices keep to it.
inline constexpr double kMaxLoopExtensionMm = 100.0;

struct DeviceInfo {
  std::string name;
  Eigen::Vector3d workspace_min_mm{-100, -100, -100};  // reachable tip positions (world frame)
  Eigen::Vector3d workspace_max_mm{100, 100, 100};
  double max_force_n = 3.0;   // forces above this are clamped
  double max_stiffness_n_per_mm = 1.0;  // stiffest spring the device renders without buzzing
  double rate_hz = 1000.0;    // update rate the device runs at
  int num_buttons = 1;        // button 0 is the cut pedal
};

struct DeviceState {
  double time_s = 0.0;
  ToolPose pose;                                   // tip, orientation, loop extension, pedal
  Eigen::Vector3d velocity_mm_s{0, 0, 0};          // tip velocity
  Eigen::Vector3d angular_velocity_rad_s{0, 0, 0}; // world frame
  double extension_velocity_mm_s = 0.0;
  std::uint32_t buttons = 0;                       // bit i = button i pressed
};

// What a device driver counts while it runs (reported by `hysim run`): packets of a network
// bridge, disconnects of a pad. Devices with nothing to count leave it zero.
struct DeviceCounters {
  long packets_received = 0;  // well-formed state packets taken
  long packets_lost = 0;      // sequence numbers skipped
  long packets_late = 0;      // arrived after a newer one (reordered or duplicated): dropped
  long packets_malformed = 0; // wrong size, magic, version or non-finite values: dropped
  long stale_periods = 0;     // times the input went silent for longer than the device's timeout
  long disconnects = 0;       // the device went away (unplugged, peer silent)
  long reconnects = 0;
};

class Device {
 public:
  virtual ~Device() = default;
  virtual const DeviceInfo& info() const = 0;
  // The device's state at simulation time t (a scripted device evaluates its script there; a
  // hardware device returns its latest sample). Never blocks; allocates nothing.
  virtual DeviceState read(double time_s) = 0;
  // Force to render on the user's hand, newtons, world frame. Clamped to max_force_n;
  // non-finite forces are replaced by zero (a NaN must never reach a motor).
  virtual void commandForce(const Eigen::Vector3d& force_n) = 0;
  // The force last sent after clamping (for reports and tests).
  virtual const Eigen::Vector3d& lastForce() const = 0;
  // Whether the device is there and delivering input now (a pad unplugged or a silent network
  // peer: false, the tool frozen); and its counters. Any thread.
  virtual bool connected() const { return true; }
  virtual DeviceCounters counters() const { return {}; }
};

// Clamps a force to max_n (keeping its direction); non-finite input gives zero.
Eigen::Vector3d safeForce(const Eigen::Vector3d& force_n, double max_n);

// Follows a scripted Trajectory (keyframes with line and arc moves, pedal events). Velocities
// are central differences of the script over one millisecond.
class ScriptedDevice final : public Device {
 public:
  explicit ScriptedDevice(Trajectory trajectory, DeviceInfo info = defaultInfo());
  static DeviceInfo defaultInfo();

  const DeviceInfo& info() const override { return info_; }
  DeviceState read(double time_s) override;
  void commandForce(const Eigen::Vector3d& force_n) override { last_force_ = safeForce(force_n, info_.max_force_n); }
  const Eigen::Vector3d& lastForce() const override { return last_force_; }
  const Trajectory& trajectory() const { return trajectory_; }

 private:
  Trajectory trajectory_;
  DeviceInfo info_;
  Eigen::Vector3d last_force_{0, 0, 0};
};

// A device driven by rate commands (keyboard, gamepad): the tip moves with a velocity given
// in the scope's own frame, the scope turns (yaw about up, pitch about its x axis), the loop
// extends or retracts. read(t) integrates the current command from the last read up to t,
// so the same command stream gives the same path.
struct ManualCommand {
  Eigen::Vector3d velocity_scope_mm_s{0, 0, 0};  // x: right, y: up, z: forward (along the axis)
  double yaw_rad_s = 0.0;                         // about the scope's up direction
  double pitch_rad_s = 0.0;                       // about the scope's x direction
  double extension_mm_s = 0.0;
  bool pedal = false;
};

class ManualDevice final : public Device {
 public:
  ManualDevice(const ToolPose& start, double start_time_s, DeviceInfo info = defaultInfo());
  static DeviceInfo defaultInfo();

  void setCommand(const ManualCommand& command) { command_ = command; }
  const DeviceInfo& info() const override { return info_; }
  DeviceState read(double time_s) override;
  void commandForce(const Eigen::Vector3d& force_n) override { last_force_ = safeForce(force_n, info_.max_force_n); }
  const Eigen::Vector3d& lastForce() const override { return last_force_; }

 private:
  ToolPose pose_;
  double time_s_;
  ManualCommand command_;
  DeviceInfo info_;
  Eigen::Vector3d last_force_{0, 0, 0};
};

}  // namespace hysim::haptics
