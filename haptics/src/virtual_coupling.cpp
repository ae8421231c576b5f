#include "hysim/haptics/virtual_coupling.hpp"

#include <Eigen/Cholesky>

namespace hysim::haptics {

VirtualCoupling::VirtualCoupling(const CouplingGains& gains, double step_s) : gains_(gains), step_s_(step_s) {}

void VirtualCoupling::reset(const Eigen::Vector3d& device_tip_mm, const Eigen::Vector3d& device_velocity_mm_s) {
  proxy_tip_ = device_tip_mm;
  proxy_velocity_ = device_velocity_mm_s;
}

void VirtualCoupling::step(const Eigen::Vector3d& device_tip_mm, const Eigen::Vector3d& device_velocity_mm_s,
                           const Eigen::Vector3d& tissue_force_n, const Eigen::Matrix3d& tissue_stiffness_n_per_mm) {
  // Balance at the end of the step, with the proxy's velocity (x' - x) / h:
  //   k (x_d - x') + b (v_d - (x' - x) / h) + f + K_t (x' - x) = 0
  // => (k + b / h - K_t) x' = k x_d + b v_d + (b / h) x + f - K_t x.
  // K_t is negative semi-definite, so the matrix is symmetric positive definite.
  const double k = gains_.stiffness_n_per_mm, b = gains_.damping_n_s_per_mm, h = step_s_;
  const Eigen::Matrix3d tissue = 0.5 * (tissue_stiffness_n_per_mm + tissue_stiffness_n_per_mm.transpose());
  const Eigen::Matrix3d a = (k + b / h) * Eigen::Matrix3d::Identity() - tissue;
  const Eigen::Vector3d rhs = k * device_tip_mm + b * device_velocity_mm_s + (b / h) * proxy_tip_ + tissue_force_n -
                              tissue * proxy_tip_;
  const Eigen::Vector3d next = a.ldlt().solve(rhs);
  proxy_velocity_ = (next - proxy_tip_) / h;
  proxy_tip_ = next;
}

Eigen::Vector3d VirtualCoupling::handForce(const Eigen::Vector3d& device_tip_mm,
                                           const Eigen::Vector3d& device_velocity_mm_s) const {
  return gains_.stiffness_n_per_mm * (proxy_tip_ - device_tip_mm) +
         gains_.damping_n_s_per_mm * (proxy_velocity_ - device_velocity_mm_s);
}

LocalForceModel VirtualCoupling::forceModel(std::int64_t step, const Eigen::Vector3d& device_tip_mm,
                                            const Eigen::Vector3d& device_velocity_mm_s) const {
  LocalForceModel m;
  m.step = step;
  m.f0_n = handForce(device_tip_mm, device_velocity_mm_s);
  m.stiffness_n_per_mm = -gains_.stiffness_n_per_mm * Eigen::Matrix3d::Identity();
  m.damping_n_s_per_mm = -gains_.damping_n_s_per_mm * Eigen::Matrix3d::Identity();
  m.x_ref_mm = device_tip_mm;
  m.v_ref_mm_s = device_velocity_mm_s;
  return m;
}

}  // namespace hysim::haptics
