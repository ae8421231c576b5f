#include "app_pivot_scope.hpp"

#include <algorithm>
#include <array>
#include <memory>

#include "app_scope_limits.hpp"

namespace hysim::tools {

haptics::PivotScopeDevice* attachPivotScope(engine::Simulation& sim) {
  const Eigen::Vector3d trocar = pivotOfPath(sim.scene().tool_path);
  // The cone's axis points from the cervix to the organ's middle: the cavity's long axis.
  const Eigen::Vector3d centre = sim.mesh().X.colwise().mean().transpose();
  Eigen::Vector3d reference = centre - trocar;
  if (reference.norm() < 1e-9) reference = sim.deviceState().pose.rotation.col(2);
  auto device = std::make_unique<haptics::PivotScopeDevice>(trocar, sim.deviceState().pose, sim.state().time,
                                                            reference.normalized());
  haptics::PivotScopeDevice* view = device.get();
  sim.setDevice(std::move(device));
  return view;
}

ScopeSize scopeSize(const engine::Simulation& sim) {
  return {sim.loop().reach_mm, sim.scene().contact.shaft_radius_mm};
}

void limitScope(haptics::PivotScopeDevice& scope, const render::SurfaceMesh& tissue, const ScopeSize& size) {
  const haptics::ToolPose pose = scope.pose();
  const double free_mm = forwardFreeMm(tissue, pose.tip, pose.rotation.col(2));
  const double ahead_mm = size.loop_reach_mm + pose.extension_mm;
  scope.setDepthLimit(depthLimitMm(scope.depth(), free_mm - ahead_mm, kFrontClearanceMm));
  const Eigen::Vector3d x = pose.rotation.col(0), up = pose.rotation.col(1);
  const std::array<Eigen::Vector3d, 4> sides = {x, Eigen::Vector3d(-x), up, Eigen::Vector3d(-up)};
  std::array<double, 4> room{};
  for (std::size_t i = 0; i < sides.size(); ++i) {
    room[i] = std::max(0.0, forwardFreeMm(tissue, pose.tip, sides[i]) - size.shaft_radius_mm);
  }
  scope.setSideRoom(pose.tip, sides, room);
}

}  // namespace hysim::tools
