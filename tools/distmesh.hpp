#pragma once
// DistMesh (Persson & Strang, "A simple mesh generator in MATLAB", SIAM Review 2004), 2D,
// uniform size: a truss of bars relaxed towards a rest length, re-triangulated (CGAL's
// Delaunay) whenever points moved enough, points outside projected back onto the boundary
// of a signed-distance domain. Used to make the paper's test meshes (Table 1).
#include <Eigen/Core>
#include <functional>
#include <vector>

#include "hysim/cutting/mesh.hpp"

namespace hysim::tools {

struct DistMeshOptions {
  double h0 = 1.0;                       // desired edge length
  Eigen::Vector2d box_min{-1, -1};       // bounding box of the domain
  Eigen::Vector2d box_max{1, 1};
  std::vector<Eigen::Vector2d> fixed;    // fixed points (corners)
  double dptol = 1e-3, ttol = 0.1, fscale = 1.2, deltat = 0.2;
  int max_iterations = 2000;
};

// Signed distance: negative inside.
using SignedDistance = std::function<double(const Eigen::Vector2d&)>;

cutting::TriMesh distmesh2d(const SignedDistance& fd, const DistMeshOptions& options);

SignedDistance rectangleDistance(double x0, double y0, double x1, double y1);
SignedDistance circleDistance(double cx, double cy, double r);

}  // namespace hysim::tools
