#pragma once
// The local force model the simulation publishes once per step and the haptic thread
// evaluates at its own, faster rate (OpenSurgSim's scheme): a first-order expansion of the
// contact force about the tool state the step used, so the device feels a smooth spring
// between steps instead of a staircase.
#include <Eigen/Core>
#include <cstdint>

#include "hysim/haptics/device.hpp"

namespace hysim::haptics {

// force(x, v) = f0_scale * F0 + K (x - x_ref) + D (v - v_ref), newtons, world frame.
// Sign convention: K and D are used as given, so a restoring spring or a damper has a
// negative-definite matrix (the simulation publishes K = dF/dx, which is negative for a
// spring pushing the tool back). All fields are zero by default: a model that renders nothing.
struct LocalForceModel {
  std::int64_t step = -1;  // simulation step that produced it; -1 = never published
  Eigen::Vector3d f0_n = Eigen::Vector3d::Zero();
  Eigen::Matrix3d stiffness_n_per_mm = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d damping_n_s_per_mm = Eigen::Matrix3d::Zero();
  Eigen::Vector3d x_ref_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_ref_mm_s = Eigen::Vector3d::Zero();

  Eigen::Vector3d force(const Eigen::Vector3d& x_mm, const Eigen::Vector3d& v_mm_s, double f0_scale = 1.0) const {
    return f0_scale * f0_n + stiffness_n_per_mm * (x_mm - x_ref_mm) + damping_n_s_per_mm * (v_mm_s - v_ref_mm_s);
  }
};

// Gains of the virtual coupling between the device and the simulated tool proxy (both
// positive: the coupling pulls the proxy towards the device and damps their relative motion).
struct CouplingGains {
  double stiffness_n_per_mm = 0.0;
  double damping_n_s_per_mm = 0.0;
};

// Damping the coupling never goes below, so a soft coupling still feels settled.
inline constexpr double kMinCouplingDamping_n_s_per_mm = 0.0005;

// Colgate's passivity condition for a spring sampled with period T and held between samples:
// the damping must exceed K T / 2, the energy such a spring can inject per sample. (Colgate
// and Schenkel state it for the device's physical damping; the rendered damper stands in for
// it here, which holds while the device's velocity estimate is good.)
bool isPassive(const CouplingGains& gains, double period_s);

// Stiffness = the device's limit; damping = twice the passivity bound (K T), at least
// kMinCouplingDamping_n_s_per_mm.
CouplingGains couplingGains(const DeviceInfo& info, double period_s);

// The model with its stiffness scaled down so that its spectral norm (the stiffest direction)
// is at most the device's max_stiffness_n_per_mm, and its damping raised, if needed, until
// the weakest direction of the symmetric part of -D damps at least |K|_2 * T (twice the
// passivity bound).
// A model with a non-finite entry is returned unchanged so the safety layer sees the fault.
LocalForceModel limitToDevice(const LocalForceModel& model, const DeviceInfo& info, double period_s);

}  // namespace hysim::haptics
