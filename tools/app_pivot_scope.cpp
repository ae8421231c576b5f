#include "app_pivot_scope.hpp"

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

void limitDepth(haptics::PivotScopeDevice& scope, const render::SurfaceMesh& tissue, double loop_reach_mm) {
  const haptics::ToolPose pose = scope.pose();
  const double free_mm = forwardFreeMm(tissue, pose.tip, pose.rotation.col(2));
  const double ahead_mm = loop_reach_mm + pose.extension_mm;
  scope.setDepthLimit(depthLimitMm(scope.depth(), free_mm - ahead_mm, kFrontClearanceMm));
}

}  // namespace hysim::tools
