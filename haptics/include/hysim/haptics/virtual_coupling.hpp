#pragma once
// The virtual coupling between the device and the simulated tool: the simulation moves a
// proxy of the tool tip, not the device's tip itself; a spring-damper (gains within the
// device's limits, see couplingGains) pulls the proxy towards the device, the tissue pushes it
// back, and the user feels the spring-damper. However stiff the tissue, the device never has
// to render more than the coupling's stiffness, so the loop stays passive.
#include <Eigen/Core>
#include <cstdint>

#include "hysim/haptics/local_force_model.hpp"

namespace hysim::haptics {

class VirtualCoupling {
 public:
  VirtualCoupling(const CouplingGains& gains, double step_s);

  // Puts the proxy on the device's tip, at rest relative to it.
  void reset(const Eigen::Vector3d& device_tip_mm, const Eigen::Vector3d& device_velocity_mm_s);

  // One simulation step: the proxy moves to where the coupling balances the tissue's
  // reaction, tissue_force_n (on the tool, at the proxy's current position) plus
  // tissue_stiffness (dF/dx there, N/mm, negative semi-definite) times the proxy's move. The
  // proxy is massless and the balance is solved implicitly (coupling spring, damper and tissue
  // stiffness together), so the step is stable for any tissue stiffness.
  void step(const Eigen::Vector3d& device_tip_mm, const Eigen::Vector3d& device_velocity_mm_s,
            const Eigen::Vector3d& tissue_force_n, const Eigen::Matrix3d& tissue_stiffness_n_per_mm);

  const Eigen::Vector3d& proxyTip() const { return proxy_tip_; }
  const Eigen::Vector3d& proxyVelocity() const { return proxy_velocity_; }
  const CouplingGains& gains() const { return gains_; }

  // The force the coupling puts on the user's hand with the device at (x, v): towards the
  // proxy, damping the difference of their velocities.
  Eigen::Vector3d handForce(const Eigen::Vector3d& device_tip_mm, const Eigen::Vector3d& device_velocity_mm_s) const;

  // The same force as a local model for the haptic thread: exact for any device state until
  // the proxy moves at the next step (F0 at the device's state of this step, K = -k I,
  // D = -b I about it).
  LocalForceModel forceModel(std::int64_t step, const Eigen::Vector3d& device_tip_mm,
                             const Eigen::Vector3d& device_velocity_mm_s) const;

 private:
  CouplingGains gains_;
  double step_s_;
  Eigen::Vector3d proxy_tip_{0, 0, 0};
  Eigen::Vector3d proxy_velocity_{0, 0, 0};
};

}  // namespace hysim::haptics
