#pragma once
// The resectoscope's loop electrode: its wire as a polyline in the world, and the surface it
// sweeps while it moves. A straight pull gives the paper's extruded loop; a curved path a
// curved strip. The accumulated sweep from entry to exit is the cut surface.
#include <Eigen/Core>
#include <vector>

#include "hysim/haptics/trajectory.hpp"

namespace hysim::engine {

struct LoopGeometry {
  double loop_radius_mm = 3.5;   // radius of the wire's arc
  double wire_radius_mm = 0.15;  // thickness of the wire (sweep is thickened by this)
  double arc_deg = 180.0;        // how much of a circle the wire spans, centred on "down"
  double reach_mm = 12.0;        // loop centre ahead of the scope tip at extension 0
  double drop_mm = 3.0;          // loop centre below the shaft axis (towards -up)
  double angle_deg = 90.0;       // angle between the loop's plane and the shaft (90: perpendicular)
  int segments = 16;             // polyline segments of the arc
};

// Wire points (segments + 1) in world coordinates for a tool pose. `out` is resized once and
// then reused (no allocation when its size is right).
void loopPoints(const LoopGeometry& loop, const haptics::ToolPose& pose, Eigen::Matrix<double, Eigen::Dynamic, 3>& out);

// The surface swept between two wire positions (same number of points): a strip of
// 2*segments triangles, appended to X (#V x 3) and F (#F x 3).
class Sweep {
 public:
  void clear();  // keeps the storage
  // Room for `rows` wire positions of `row_size` points: advance() then allocates nothing
  // until a sweep grows longer than that.
  void reserve(int rows, int row_size) { points_.reserve(static_cast<size_t>(rows) * row_size); }
  bool empty() const { return num_quads_ == 0; }
  // Appends the strip between the last wire position and `wire` (the first call only records
  // the position).
  void advance(const Eigen::Matrix<double, Eigen::Dynamic, 3>& wire);
  // Triangles of the accumulated sweep: vertices #V x 3, triangles #F x 3.
  Eigen::Matrix<double, Eigen::Dynamic, 3> vertices() const;
  Eigen::Matrix<int, Eigen::Dynamic, 3> triangles() const;
  double area() const;                // mm^2
  // The sweep with one more wire row before its start and after its end, `extra_mm` along
  // the direction of motion there: a cut with it surely reaches through the surface where
  // the loop entered and where it left. Empty when fewer than two rows were recorded.
  void extendedSurface(double extra_mm, Eigen::Matrix<double, Eigen::Dynamic, 3>& vertices,
                       Eigen::Matrix<int, Eigen::Dynamic, 3>& triangles) const;
  double pathLength() const { return path_length_; }  // of the wire's middle point, mm
  int numRows() const { return num_rows_; }
  int rowSize() const { return row_size_; }
  const Eigen::Vector3d& point(int row, int i) const { return points_[static_cast<size_t>(row) * row_size_ + i]; }
  // Unit mean direction of the wire's points from row `from` to row `to` (zero: no motion).
  Eigen::Vector3d motion(int from, int to) const;
  // Area of the strips between consecutive rows (the triangles() surface), summed as the rows
  // came in, mm^2.
  double stripArea() const { return strip_area_; }
  // Area of extendedSurface(extra_mm)'s triangles, mm^2.
  double extendedArea(double extra_mm) const;

 private:
  std::vector<Eigen::Vector3d> points_;  // consecutive wire positions, row after row
  int row_size_ = 0;
  int num_rows_ = 0;
  int num_quads_ = 0;
  double path_length_ = 0.0;
  double strip_area_ = 0.0;
};

}  // namespace hysim::engine
