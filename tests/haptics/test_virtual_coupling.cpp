#include <gtest/gtest.h>

#include <cmath>

#include "hysim/haptics/virtual_coupling.hpp"

namespace hysim::haptics {
namespace {

constexpr double kStep = 1e-3;

CouplingGains defaultGains() { return couplingGains(DeviceInfo{}, kStep); }

TEST(VirtualCoupling, WithoutTissueTheProxyTracksAMovingDeviceExactly) {
  VirtualCoupling c(defaultGains(), kStep);
  const Eigen::Vector3d v(12.0, -3.0, 40.0);
  Eigen::Vector3d x(1.0, 2.0, 3.0);
  c.reset(x, v);
  for (int i = 0; i < 100; ++i) {
    x += v * kStep;
    c.step(x, v, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Zero());
    EXPECT_LT((c.proxyTip() - x).norm(), 1e-9);
    EXPECT_LT(c.handForce(x, v).norm(), 1e-9);
  }
  EXPECT_LT((c.proxyVelocity() - v).norm(), 1e-6);
}

TEST(VirtualCoupling, AConstantTissueForceOffsetsTheProxyAndReachesTheHand) {
  // The hand at rest; the tissue pushes the tool with 0.6 N along -z. The proxy settles where
  // the spring balances it, 0.6 N / k behind the device, and the hand feels the 0.6 N.
  const CouplingGains g = defaultGains();
  VirtualCoupling c(g, kStep);
  const Eigen::Vector3d x(0, 0, 10), f(0, 0, -0.6);
  c.reset(x, Eigen::Vector3d::Zero());
  for (int i = 0; i < 200; ++i) c.step(x, Eigen::Vector3d::Zero(), f, Eigen::Matrix3d::Zero());
  EXPECT_NEAR(c.proxyTip().z(), 10.0 - 0.6 / g.stiffness_n_per_mm, 1e-9);
  EXPECT_LT((c.handForce(x, Eigen::Vector3d::Zero()) - f).norm(), 1e-9);
}

// A wall at z = 0 much stiffer than the device can render; the device's tip is pushed 5 mm
// into it and held there. The tissue's force and stiffness come from the proxy's position,
// one step late, as in the simulation: the first step into the wall goes too deep (the wall
// was not known yet), the next pushes the proxy back out, and from there it settles on the
// balance from one side.
TEST(VirtualCoupling, AStiffWallStopsTheProxyWithoutRinging) {
  const CouplingGains g = defaultGains();
  VirtualCoupling c(g, kStep);
  const double wall_k = 1000.0;  // N/mm, 1000 times the device's limit
  const Eigen::Vector3d device(0, 0, -5);
  c.reset(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d::Zero());
  const double settled = g.stiffness_n_per_mm * 5.0 / (wall_k + g.stiffness_n_per_mm);
  double previous_depth = 0.0;
  for (int i = 0; i < 500; ++i) {
    const double depth = std::max(0.0, -c.proxyTip().z());
    Eigen::Vector3d f = Eigen::Vector3d::Zero();
    Eigen::Matrix3d k = Eigen::Matrix3d::Zero();
    if (depth > 0.0) {
      f.z() = wall_k * depth;
      k(2, 2) = -wall_k;
    }
    c.step(device, Eigen::Vector3d::Zero(), f, k);
    const double next_depth = std::max(0.0, -c.proxyTip().z());
    if (i >= 2) {  // no bounce: straight down to the balance, never past it
      EXPECT_LE(next_depth, previous_depth + 1e-15) << "step " << i;
      EXPECT_GE(next_depth, settled - 1e-15) << "step " << i;
      // From then on the hand never feels more than the spring stretched over the whole way
      // (the step into the wall and the one back out add the damper's kick).
      EXPECT_LE(c.handForce(device, Eigen::Vector3d::Zero()).norm(), g.stiffness_n_per_mm * 5.0 + 1e-9);
    }
    previous_depth = next_depth;
  }
  EXPECT_NEAR(previous_depth, settled, 1e-6);
  EXPECT_NEAR(c.handForce(device, Eigen::Vector3d::Zero()).z(), wall_k * settled, 1e-3);
}

TEST(VirtualCoupling, TheLocalModelIsTheCouplingForceAtAnyDeviceState) {
  const CouplingGains g = defaultGains();
  VirtualCoupling c(g, kStep);
  c.reset(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d::Zero());
  c.step(Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(50, 0, 0), Eigen::Vector3d(-0.3, 0.1, 0), Eigen::Matrix3d::Zero());
  const Eigen::Vector3d xd(1, 0, 0), vd(50, 0, 0);
  const LocalForceModel m = c.forceModel(7, xd, vd);
  EXPECT_EQ(m.step, 7);
  for (const Eigen::Vector3d& dx : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.2, -0.1, 0.4), Eigen::Vector3d(-2, 1, 3)}) {
    const Eigen::Vector3d dv = 100.0 * dx;
    EXPECT_LT((m.force(xd + dx, vd + dv) - c.handForce(xd + dx, vd + dv)).norm(), 1e-12);
  }
  // Within the device's limits: limitToDevice leaves it as it is.
  const LocalForceModel limited = limitToDevice(m, DeviceInfo{}, kStep);
  EXPECT_TRUE(limited.stiffness_n_per_mm.isApprox(m.stiffness_n_per_mm));
  EXPECT_TRUE(limited.damping_n_s_per_mm.isApprox(m.damping_n_s_per_mm));
  EXPECT_TRUE(isPassive(g, kStep));
}

}  // namespace
}  // namespace hysim::haptics
