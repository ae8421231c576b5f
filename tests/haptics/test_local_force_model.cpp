#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>

#include "hysim/haptics/local_force_model.hpp"

namespace hysim::haptics {
namespace {

TEST(LocalForceModel, DefaultRendersNothing) {
  const LocalForceModel m;
  EXPECT_EQ(m.step, -1);
  EXPECT_EQ(m.force({3, 4, 5}, {1, 2, 3}), Eigen::Vector3d::Zero());
}

TEST(LocalForceModel, FirstOrderExpansionWithScaledF0) {
  LocalForceModel m;
  m.f0_n = {1, 0, 0};
  m.stiffness_n_per_mm = -0.5 * Eigen::Matrix3d::Identity();  // restoring spring: negative
  m.damping_n_s_per_mm = -0.01 * Eigen::Matrix3d::Identity();
  m.x_ref_mm = {0, 0, 2};
  m.v_ref_mm_s = {0, 10, 0};
  const Eigen::Vector3d x(0, 0, 4), v(0, 30, 0);
  EXPECT_TRUE(m.force(x, v).isApprox(Eigen::Vector3d(1, -0.2, -1)));
  EXPECT_TRUE(m.force(x, v, 0.25).isApprox(Eigen::Vector3d(0.25, -0.2, -1)));
  EXPECT_TRUE(m.force(m.x_ref_mm, m.v_ref_mm_s, 0.0).isZero());
}

TEST(CouplingGains, DeviceStiffnessWithTwiceThePassivityBound) {
  DeviceInfo info;
  info.max_stiffness_n_per_mm = 2.0;
  const CouplingGains g = couplingGains(info, 1e-3);
  EXPECT_DOUBLE_EQ(g.stiffness_n_per_mm, 2.0);
  EXPECT_DOUBLE_EQ(g.damping_n_s_per_mm, 2e-3);
  EXPECT_TRUE(isPassive(g, 1e-3));
  EXPECT_FALSE(isPassive(g, 3e-3));  // same gains, slower loop: K T / 2 = 3e-3 > 2e-3

  info.max_stiffness_n_per_mm = 0.1;  // soft device: the minimum damping applies
  EXPECT_DOUBLE_EQ(couplingGains(info, 1e-3).damping_n_s_per_mm, kMinCouplingDamping_n_s_per_mm);
}

TEST(CouplingGains, PassivityBoundIsStrict) {
  EXPECT_FALSE(isPassive({1.0, 0.5e-3}, 1e-3));
  EXPECT_TRUE(isPassive({1.0, 0.51e-3}, 1e-3));
  EXPECT_FALSE(isPassive({1.0, 0.0}, 1e-3));
}

TEST(LimitToDevice, ScalesStiffnessAndRaisesDamping) {
  DeviceInfo info;
  info.max_stiffness_n_per_mm = 1.0;
  LocalForceModel m;
  m.step = 7;
  m.f0_n = {0.3, 0, 0};
  m.stiffness_n_per_mm = Eigen::Vector3d(-5, -2, -1).asDiagonal();
  const LocalForceModel limited = limitToDevice(m, info, 1e-3);
  EXPECT_EQ(limited.step, 7);
  EXPECT_EQ(limited.f0_n, m.f0_n);
  // The stiffest direction (5 N/mm) comes down to the device's 1 N/mm, the others with it.
  EXPECT_TRUE(limited.stiffness_n_per_mm.isApprox(Eigen::Matrix3d(Eigen::Vector3d(-1, -0.4, -0.2).asDiagonal())));
  // Every direction now damps at least |K| T = 1e-3 N s/mm.
  const Eigen::Matrix3d dissipation = -limited.damping_n_s_per_mm;
  EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(dissipation).eigenvalues().minCoeff(), 1e-3 - 1e-12);
}

TEST(LimitToDevice, LeavesAModelWithinTheLimitsAlone) {
  DeviceInfo info;
  LocalForceModel m;
  m.stiffness_n_per_mm = -0.1 * Eigen::Matrix3d::Identity();
  m.damping_n_s_per_mm = -0.01 * Eigen::Matrix3d::Identity();
  const LocalForceModel limited = limitToDevice(m, info, 1e-3);
  EXPECT_EQ(limited.stiffness_n_per_mm, m.stiffness_n_per_mm);
  EXPECT_EQ(limited.damping_n_s_per_mm, m.damping_n_s_per_mm);
}

TEST(LimitToDevice, KeepsNonFiniteModelsForTheSafetyLayer) {
  DeviceInfo info;
  LocalForceModel m;
  m.stiffness_n_per_mm = -50.0 * Eigen::Matrix3d::Identity();
  m.f0_n.x() = std::numeric_limits<double>::quiet_NaN();
  const LocalForceModel limited = limitToDevice(m, info, 1e-3);
  EXPECT_TRUE(std::isnan(limited.f0_n.x()));
  EXPECT_EQ(limited.stiffness_n_per_mm, m.stiffness_n_per_mm);
}

}  // namespace
}  // namespace hysim::haptics
