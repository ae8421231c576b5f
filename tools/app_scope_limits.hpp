#pragma once
// Where the keyboard scope may go: the trocar point the scripted course pivots about, and how
// deep the scope may be inserted before its tip meets the tissue in front of it.
#include <Eigen/Core>
#include <vector>

#include "hysim/haptics/trajectory.hpp"
#include "hysim/render/snapshot.hpp"

namespace hysim::tools {

// Free distance from `origin` along the unit direction `dir` to the tissue surface (its
// triangles are counter-clockwise seen from outside the tissue, i.e. from the cavity):
// the distance to the first triangle the ray meets from the cavity side; 0 when the first
// triangle is met from inside (the origin is in the tissue); +inf when the ray meets none.
double forwardFreeMm(const render::SurfaceMesh& surface, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir);

// The depth limit for a scope at `depth_mm` whose tip has `free_mm` in front of it: the tip
// stops `clearance_mm` short of the tissue (never below the current depth).
double depthLimitMm(double depth_mm, double free_mm, double clearance_mm);

// The point nearest to every keyframe's shaft line (least squares): where a scripted course
// pivots (the cervix). Falls back to 16 mm behind the first tip when the lines are parallel.
Eigen::Vector3d pivotOfPath(const std::vector<haptics::Keyframe>& path);

}  // namespace hysim::tools
