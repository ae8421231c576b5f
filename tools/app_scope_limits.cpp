#include "app_scope_limits.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

namespace hysim::tools {

namespace {

Eigen::Vector3d vertex(const render::SurfaceMesh& s, std::uint32_t i) {
  return {s.positions[3 * i], s.positions[3 * i + 1], s.positions[3 * i + 2]};
}

// Moller-Trumbore: the ray parameter of the hit (or -1) and the side it is met from.
double rayTriangle(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& a,
                   const Eigen::Vector3d& b, const Eigen::Vector3d& c, bool& from_outside) {
  const Eigen::Vector3d e1 = b - a, e2 = c - a;
  const Eigen::Vector3d p = d.cross(e2);
  const double det = e1.dot(p);
  if (std::fabs(det) < 1e-12) return -1.0;
  const double inv = 1.0 / det;
  const Eigen::Vector3d s = o - a;
  const double u = s.dot(p) * inv;
  if (u < 0.0 || u > 1.0) return -1.0;
  const Eigen::Vector3d q = s.cross(e1);
  const double v = d.dot(q) * inv;
  if (v < 0.0 || u + v > 1.0) return -1.0;
  // det = -dir . (e1 x e2) > 0: the ray runs against the outward normal, so it comes from outside.
  from_outside = det > 0.0;
  return e2.dot(q) * inv;
}

}  // namespace

double forwardFreeMm(const render::SurfaceMesh& surface, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) {
  double nearest = std::numeric_limits<double>::infinity();
  bool nearest_from_outside = true;
  const std::size_t num_tris = surface.triangles.size() / 3;
  for (std::size_t f = 0; f < num_tris; ++f) {
    const std::uint32_t* t = &surface.triangles[3 * f];
    bool from_outside = true;
    const double hit = rayTriangle(origin, dir, vertex(surface, t[0]), vertex(surface, t[1]), vertex(surface, t[2]),
                                   from_outside);
    if (hit >= 0.0 && hit < nearest) {
      nearest = hit;
      nearest_from_outside = from_outside;
    }
  }
  return nearest_from_outside ? nearest : 0.0;
}

double depthLimitMm(double depth_mm, double free_mm, double clearance_mm) {
  return depth_mm + std::max(0.0, free_mm - clearance_mm);
}

Eigen::Vector3d pivotOfPath(const std::vector<haptics::Keyframe>& path) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const haptics::Keyframe& k : path) {
    const Eigen::Vector3d axis = k.axis.normalized();
    const Eigen::Matrix3d across = Eigen::Matrix3d::Identity() - axis * axis.transpose();
    a += across;
    b += across * k.tip;
  }
  constexpr double kFallbackDepthMm = 16.0;
  if (path.empty()) return Eigen::Vector3d::Zero();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(a);
  // Parallel shafts leave the point free along them: no pivot to find.
  if (eig.eigenvalues().minCoeff() < 1e-6 * std::max(1.0, eig.eigenvalues().maxCoeff())) {
    return path.front().tip - kFallbackDepthMm * path.front().axis.normalized();
  }
  return a.ldlt().solve(b);
}

}  // namespace hysim::tools
