#include "hysim/haptics/local_force_model.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>

namespace hysim::haptics {

bool isPassive(const CouplingGains& gains, double period_s) {
  return gains.damping_n_s_per_mm > 0.5 * gains.stiffness_n_per_mm * period_s;
}

CouplingGains couplingGains(const DeviceInfo& info, double period_s) {
  CouplingGains gains;
  gains.stiffness_n_per_mm = info.max_stiffness_n_per_mm;
  gains.damping_n_s_per_mm = std::max(gains.stiffness_n_per_mm * period_s, kMinCouplingDamping_n_s_per_mm);
  return gains;
}

namespace {

bool allFinite(const LocalForceModel& m) {
  return m.f0_n.allFinite() && m.stiffness_n_per_mm.allFinite() && m.damping_n_s_per_mm.allFinite() &&
         m.x_ref_mm.allFinite() && m.v_ref_mm_s.allFinite();
}

// Smallest damping rate of D over all directions (D negative-definite when it damps).
double weakestDamping(const Eigen::Matrix3d& damping) {
  const Eigen::Matrix3d dissipation = -0.5 * (damping + damping.transpose());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(dissipation, Eigen::EigenvaluesOnly);
  return solver.eigenvalues()(0);  // sorted increasing
}

// Largest stiffness over all directions (largest singular value).
double spectralNorm(const Eigen::Matrix3d& m) {
  return Eigen::JacobiSVD<Eigen::Matrix3d>(m).singularValues()(0);  // sorted decreasing
}

}  // namespace

LocalForceModel limitToDevice(const LocalForceModel& model, const DeviceInfo& info, double period_s) {
  if (!allFinite(model)) return model;
  LocalForceModel limited = model;
  const double max_k = info.max_stiffness_n_per_mm;
  double k = spectralNorm(limited.stiffness_n_per_mm);
  if (k > max_k) {
    limited.stiffness_n_per_mm *= max_k / k;
    k = max_k;
  }
  const double needed = k * period_s;
  const double weakest = weakestDamping(limited.damping_n_s_per_mm);
  if (weakest < needed) limited.damping_n_s_per_mm -= (needed - weakest) * Eigen::Matrix3d::Identity();
  return limited;
}

}  // namespace hysim::haptics
