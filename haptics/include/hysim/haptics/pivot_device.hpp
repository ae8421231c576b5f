#pragma once
// A keyboard-driven hysteroscope that pivots at the cervix: the shaft always passes through
// a fixed trocar point, so the trainee controls insertion depth, the shaft's direction (yaw
// and pitch about the trocar), roll about the shaft (which turns the fore-oblique lens) and the
// loop's extension, as with a real scope. Depth is kept within [min, limit]: the app sets the
// limit from the cavity's free space in front of the tip each frame, so the scope cannot be
// driven through the fundus, and the room beside the tip, so it cannot be swung into the wall;
// the shaft's tilt from the reference axis is kept within a cone.
// read(t) integrates the current command from the last read to t: the same command stream
// gives the same path.
#include <Eigen/Core>
#include <array>
#include <limits>

#include "hysim/haptics/device.hpp"

namespace hysim::haptics {

struct PivotCommand {
  double insert_mm_s = 0.0;   // + deeper along the shaft, - withdraw
  double yaw_rad_s = 0.0;     // about the scope's up direction, through the trocar
  double pitch_rad_s = 0.0;   // about the scope's x direction, through the trocar
  double roll_rad_s = 0.0;    // about the shaft
  double extension_mm_s = 0.0;
  bool pedal = false;         // electrode active (cut)
};

struct PivotLimits {
  double min_depth_mm = 4.0;   // trocar to tip: the tip stays beyond the trocar
  double max_tilt_rad = 0.44;  // shaft from the reference axis (25 degrees)
  double max_extension_mm = 20.0;
};

class PivotScopeDevice final : public Device {
 public:
  // Starts from `start` (its tip is put on the line from the trocar along its axis at the
  // tip's distance); `reference_axis` is the cone's axis (e.g. the cavity's long axis).
  PivotScopeDevice(const Eigen::Vector3d& trocar, const ToolPose& start, double start_time_s,
                   const Eigen::Vector3d& reference_axis, PivotLimits limits = {},
                   DeviceInfo info = defaultInfo());
  static DeviceInfo defaultInfo();

  void setCommand(const PivotCommand& command) { command_ = command; }
  // Deepest the tip may go (trocar to tip, mm); +inf: no limit. A limit below the current
  // depth stops further insertion without pulling the scope back.
  void setDepthLimit(double max_depth_mm) { depth_limit_ = max_depth_mm; }
  // Room the tip has sideways: from `from`, it may move at most room_mm[i] along the unit
  // direction directions[i]; a turn that would take it further (and not back) is not taken.
  // Like the depth limit, set each frame from the free space around the tip.
  void setSideRoom(const Eigen::Vector3d& from, const std::array<Eigen::Vector3d, 4>& directions,
                   const std::array<double, 4>& room_mm);
  double depth() const { return depth_; }
  // The pose as of the last read (its tip lies on the shaft's line through the trocar).
  ToolPose pose() const;
  const Eigen::Vector3d& trocar() const { return trocar_; }
  // The last read had to stop the insertion (at the depth limit) or the tilt (at the cone).
  bool depthLimited() const { return depth_limited_; }
  bool tiltLimited() const { return tilt_limited_; }
  bool sideLimited() const { return side_limited_; }

  const DeviceInfo& info() const override { return info_; }
  DeviceState read(double time_s) override;
  void commandForce(const Eigen::Vector3d& force_n) override { last_force_ = safeForce(force_n, info_.max_force_n); }
  const Eigen::Vector3d& lastForce() const override { return last_force_; }

 private:
  void turn(double dt);     // yaw, pitch and roll, kept within the tilt cone and the side room
  bool sideBlocked(const Eigen::Vector3d& tip_before, const Eigen::Vector3d& tip_after) const;
  void insert(double dt);   // depth, kept within [min_depth, depth limit]

  Eigen::Vector3d trocar_;
  Eigen::Vector3d reference_axis_;
  PivotLimits limits_;
  Eigen::Matrix3d rotation_ = Eigen::Matrix3d::Identity();  // columns: body x, up, shaft axis
  double depth_ = 0.0;
  double extension_mm_ = 0.0;
  double time_s_;
  double depth_limit_ = std::numeric_limits<double>::infinity();
  bool depth_limited_ = false;
  bool tilt_limited_ = false;
  bool side_limited_ = false;
  Eigen::Vector3d side_from_{0, 0, 0};
  std::array<Eigen::Vector3d, 4> side_directions_{};
  std::array<double, 4> side_room_{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                                   std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  PivotCommand command_;
  DeviceInfo info_;
  Eigen::Vector3d last_force_{0, 0, 0};
};

}  // namespace hysim::haptics
