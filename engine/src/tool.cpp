#include "hysim/engine/tool.hpp"

#include <Eigen/Geometry>
#include <cmath>

#include "hysim/cutting/cut_surface.hpp"

namespace hysim::engine {

void loopPoints(const LoopGeometry& loop, const haptics::ToolPose& pose, Eigen::Matrix<double, Eigen::Dynamic, 3>& out) {
  const int n = loop.segments + 1;
  if (out.rows() != n) out.resize(n, 3);
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  // Body frame: x = pose x, y = up, z = shaft axis. The loop's plane contains the body x axis
  // and its in-plane "down" direction, tilted from -y towards +z when the loop is not
  // perpendicular to the shaft.
  const double tilt = (90.0 - loop.angle_deg) * kDeg;
  const Eigen::Vector3d x_body(1, 0, 0);
  const Eigen::Vector3d down_body(0, -std::cos(tilt), std::sin(tilt));
  const Eigen::Vector3d centre_body(0, -loop.drop_mm, loop.reach_mm + pose.extension_mm);
  const double half = 0.5 * loop.arc_deg * kDeg;
  for (int i = 0; i < n; ++i) {
    const double phi = -half + (2.0 * half) * i / loop.segments;
    const Eigen::Vector3d p_body =
        centre_body + loop.loop_radius_mm * (std::sin(phi) * x_body + std::cos(phi) * down_body);
    out.row(i) = (pose.tip + pose.rotation * p_body).transpose();
  }
}

void Sweep::clear() {
  points_.clear();
  row_size_ = 0;
  num_rows_ = 0;
  num_quads_ = 0;
  path_length_ = 0.0;
  strip_area_ = 0.0;
}

// Area of the quad strip between rows a and b (#n points each), as triangles (a_i, a_i+1,
// b_i+1) and (a_i, b_i+1, b_i), the order triangles() gives.
template <class RowA, class RowB>
static double quadStripArea(int n, const RowA& a, const RowB& b) {
  double total = 0.0;
  for (int i = 0; i + 1 < n; ++i) {
    const Eigen::Vector3d p = a(i), q = a(i + 1), r = b(i + 1), s = b(i);
    total += 0.5 * (q - p).cross(r - p).norm() + 0.5 * (r - p).cross(s - p).norm();
  }
  return total;
}

Eigen::Vector3d Sweep::motion(int from, int to) const {
  Eigen::Vector3d d = Eigen::Vector3d::Zero();
  for (int i = 0; i < row_size_; ++i) d += point(to, i) - point(from, i);
  return d.norm() > 0.0 ? Eigen::Vector3d(d.normalized()) : d;
}

void Sweep::advance(const Eigen::Matrix<double, Eigen::Dynamic, 3>& wire) {
  const int n = static_cast<int>(wire.rows());
  if (num_rows_ > 0 && n != row_size_) clear();  // a different loop: start over
  if (num_rows_ > 0) {
    const int mid = n / 2;
    path_length_ += (wire.row(mid).transpose() - points_[(num_rows_ - 1) * row_size_ + mid]).norm();
    num_quads_ += n - 1;
    const int last = num_rows_ - 1;
    strip_area_ += quadStripArea(
        n, [&](int i) -> Eigen::Vector3d { return point(last, i); },
        [&](int i) -> Eigen::Vector3d { return wire.row(i).transpose(); });
  }
  row_size_ = n;
  for (int i = 0; i < n; ++i) points_.push_back(wire.row(i).transpose());
  ++num_rows_;
}

Eigen::Matrix<double, Eigen::Dynamic, 3> Sweep::vertices() const {
  Eigen::Matrix<double, Eigen::Dynamic, 3> v(static_cast<Eigen::Index>(points_.size()), 3);
  for (size_t i = 0; i < points_.size(); ++i) v.row(static_cast<Eigen::Index>(i)) = points_[i].transpose();
  return v;
}

Eigen::Matrix<int, Eigen::Dynamic, 3> Sweep::triangles() const {
  // The cut surface's strip layout (the pass cuts with CutSurface::strip of the same grid).
  if (num_rows_ < 2) return Eigen::Matrix<int, Eigen::Dynamic, 3>(0, 3);
  return cutting::CutSurface::stripTriangles(num_rows_, row_size_);
}

void Sweep::extendedSurface(double extra_mm, Eigen::Matrix<double, Eigen::Dynamic, 3>& vertices,
                            Eigen::Matrix<int, Eigen::Dynamic, 3>& triangles) const {
  if (num_rows_ < 2) {
    vertices.resize(0, 3);
    triangles.resize(0, 3);
    return;
  }
  const int n = row_size_;
  auto row = [&](int r, int i) -> const Eigen::Vector3d& { return point(r, i); };
  const Eigen::Vector3d start_dir = motion(0, 1), end_dir = motion(num_rows_ - 2, num_rows_ - 1);
  const int rows = num_rows_ + 2;
  vertices.resize(static_cast<Eigen::Index>(rows) * n, 3);
  for (int i = 0; i < n; ++i) vertices.row(i) = (row(0, i) - extra_mm * start_dir).transpose();
  for (int r = 0; r < num_rows_; ++r)
    for (int i = 0; i < n; ++i) vertices.row(static_cast<Eigen::Index>(r + 1) * n + i) = row(r, i).transpose();
  for (int i = 0; i < n; ++i) {
    vertices.row(static_cast<Eigen::Index>(rows - 1) * n + i) = (row(num_rows_ - 1, i) + extra_mm * end_dir).transpose();
  }
  triangles.resize(2 * (rows - 1) * (n - 1), 3);
  int t = 0;
  for (int r = 0; r + 1 < rows; ++r) {
    for (int i = 0; i + 1 < n; ++i) {
      const int a = r * n + i, b = a + 1, c = a + n, d = c + 1;
      triangles.row(t++) << a, b, d;
      triangles.row(t++) << a, d, c;
    }
  }
}

double Sweep::extendedArea(double extra_mm) const {
  if (num_rows_ < 2) return 0.0;
  const int n = row_size_, last = num_rows_ - 1;
  const Eigen::Vector3d start = extra_mm * motion(0, 1), end = extra_mm * motion(last - 1, last);
  return strip_area_ +
         quadStripArea(
             n, [&](int i) -> Eigen::Vector3d { return point(0, i) - start; },
             [&](int i) -> Eigen::Vector3d { return point(0, i); }) +
         quadStripArea(
             n, [&](int i) -> Eigen::Vector3d { return point(last, i); },
             [&](int i) -> Eigen::Vector3d { return point(last, i) + end; });
}

double Sweep::area() const {
  const auto v = vertices();
  const auto f = triangles();
  double total = 0.0;
  for (int t = 0; t < f.rows(); ++t) {
    const Eigen::Vector3d a = v.row(f(t, 0)), b = v.row(f(t, 1)), c = v.row(f(t, 2));
    total += 0.5 * (b - a).cross(c - a).norm();
  }
  return total;
}

}  // namespace hysim::engine
