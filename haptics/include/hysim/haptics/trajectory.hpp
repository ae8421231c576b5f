#pragma once
// A scripted tool path: timed keyframes of the scope tip pose, the loop electrode's
// extension and the cut pedal. Until real devices arrive, this is what drives the tool
// (and the camera, which sits at the scope tip).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace hysim::haptics {

struct Keyframe {
  enum class Move { Linear, Arc };
  double time_s = 0.0;
  Eigen::Vector3d tip{0, 0, 0};      // mm, world: scope tip (camera position)
  // How the tip gets here from the previous keyframe: a straight line, or a circular arc
  // about arc_center (radius interpolated linearly when the two ends differ; the arc spans
  // less than 180 degrees, so its plane is defined).
  Move move = Move::Linear;
  Eigen::Vector3d arc_center{0, 0, 0};
  Eigen::Vector3d axis{0, 0, 1};     // unit: shaft axis, pointing into the body
  Eigen::Vector3d up{0, 1, 0};       // reference direction (light post); made orthogonal to axis
  double extension_mm = 0.0;         // loop electrode pushed out beyond its rest position
  bool pedal = false;                // cut pedal (electrode active) from this keyframe on
};

struct ToolPose {
  Eigen::Vector3d tip{0, 0, 0};
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // columns: body x, y (= up), z (= axis)
  double extension_mm = 0.0;
  bool pedal = false;
};

// Positions along lines or arcs, linear extension, spherical-linear orientation between
// keyframes; holds the first/last keyframe outside the scripted time range. Pedal switches
// at keyframes.
class Trajectory {
 public:
  Trajectory() = default;
  explicit Trajectory(std::vector<Keyframe> keyframes);  // keyframes sorted by time

  bool empty() const { return keys_.empty(); }
  const std::vector<Keyframe>& keyframes() const { return keys_; }
  double duration() const { return keys_.empty() ? 0.0 : keys_.back().time_s; }
  ToolPose sample(double time_s) const;  // allocates nothing

 private:
  std::vector<Keyframe> keys_;
  std::vector<Eigen::Quaterniond> orientations_;  // one per keyframe
};

// Rotation whose columns are (up x axis, up, axis) after orthogonalising up against axis.
Eigen::Matrix3d frameFromAxisUp(const Eigen::Vector3d& axis, const Eigen::Vector3d& up);

// Is the arc from `from` to `to` about `center` well defined (both ends off the centre,
// not opposite or equal directions)?
bool validArc(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Eigen::Vector3d& center);

}  // namespace hysim::haptics
