// Loop electrode vs. tissue (FCL): entry and exit on a slab, inside counts as touching.
#include <gtest/gtest.h>

#include "box_mesh.hpp"
#include "hysim/engine/collision.hpp"
#include "hysim/engine/tool.hpp"

namespace hysim::engine {
namespace {

// A 20 x 20 x 8 mm slab of tissue from z = -4 to 4, centred on x, y.
cutting::TetMesh slab() {
  cutting::TetMesh m = testing::boxTetMesh(10, 10, 4, 2.0);
  for (int i = 0; i < m.numNodes(); ++i) m.X.row(i) -= Eigen::RowVector3d(10, 10, 4);
  return m;
}

// The tool points down (-z) so the loop hangs sideways; its wire's points are at the height
// of the tip minus reach.
haptics::ToolPose poseAt(double height) {
  haptics::ToolPose pose;
  pose.rotation = haptics::frameFromAxisUp({0, 0, -1}, {0, 1, 0});
  pose.tip = {0, 0, height};
  return pose;
}

TEST(Collision, EntryInsideAndExitThroughASlab) {
  const cutting::TetMesh mesh = slab();
  sim::NodeVectors x = mesh.X;
  TissueCollision collision;
  ASSERT_TRUE(collision.build(mesh, x).ok());
  EXPECT_GT(collision.numFaces(), 2 * mesh.numTets());  // interior faces are in the hierarchy
  LoopGeometry loop;
  Eigen::Matrix<double, Eigen::Dynamic, 3> wire;
  // Lower the loop through the slab: the wire sits at z = tip - reach (perpendicular loop).
  bool was_touching = false;
  double entry = 0, exit = 0;
  for (int k = 0; k <= 400; ++k) {
    const double wire_z = 10.0 - 0.05 * k;  // from 10 down to -10
    loopPoints(loop, poseAt(wire_z + loop.reach_mm), wire);
    const bool touching = collision.touches(wire, loop.wire_radius_mm);
    if (touching && !was_touching) entry = wire_z;
    if (!touching && was_touching) exit = wire_z;
    was_touching = touching;
  }
  EXPECT_NEAR(entry, 4.0 + loop.wire_radius_mm, 0.051);   // first touch of the top face
  EXPECT_NEAR(exit, -4.0 - loop.wire_radius_mm, 0.051);   // leaves through the bottom
  // Deep inside the slab the wire touches interior faces only.
  loopPoints(loop, poseAt(0.3 + loop.reach_mm), wire);
  EXPECT_TRUE(collision.touches(wire, loop.wire_radius_mm));
  // Far to the side: nothing.
  haptics::ToolPose away = poseAt(loop.reach_mm);
  away.tip.x() = 40;
  loopPoints(loop, away, wire);
  EXPECT_FALSE(collision.touches(wire, loop.wire_radius_mm));
}

TEST(Collision, RefitFollowsTheDeformation) {
  const cutting::TetMesh mesh = slab();
  sim::NodeVectors x = mesh.X;
  TissueCollision collision;
  ASSERT_TRUE(collision.build(mesh, x).ok());
  LoopGeometry loop;
  Eigen::Matrix<double, Eigen::Dynamic, 3> wire;
  loopPoints(loop, poseAt(6.0 + loop.reach_mm), wire);  // 2 mm above the slab
  EXPECT_FALSE(collision.touches(wire, loop.wire_radius_mm));
  x.col(2).array() += 3.0;  // the tissue rises by 3 mm
  collision.refit(x);
  EXPECT_TRUE(collision.touches(wire, loop.wire_radius_mm));
}

}  // namespace
}  // namespace hysim::engine
