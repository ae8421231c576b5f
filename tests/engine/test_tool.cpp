// Loop electrode geometry and its sweep.
#include <gtest/gtest.h>

#include <cmath>

#include "hysim/engine/tool.hpp"

namespace hysim::engine {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(Loop, SemicircleHangsBelowTheAxisAheadOfTheTip) {
  LoopGeometry loop;
  haptics::ToolPose pose;  // tip at origin, axis +z, up +y
  Eigen::Matrix<double, Eigen::Dynamic, 3> wire;
  loopPoints(loop, pose, wire);
  ASSERT_EQ(wire.rows(), loop.segments + 1);
  const Eigen::Vector3d centre(0, -loop.drop_mm, loop.reach_mm);
  for (int i = 0; i < wire.rows(); ++i) {
    EXPECT_NEAR((wire.row(i).transpose() - centre).norm(), loop.loop_radius_mm, 1e-12);
    EXPECT_NEAR(wire(i, 2), loop.reach_mm, 1e-12);  // perpendicular to the shaft
    EXPECT_LE(wire(i, 1), -loop.drop_mm + 1e-12);   // below the centre: hangs down
  }
  EXPECT_NEAR(wire(loop.segments / 2, 1), -loop.drop_mm - loop.loop_radius_mm, 1e-12);  // lowest point
  EXPECT_NEAR(wire(0, 0), -loop.loop_radius_mm, 1e-12);
  EXPECT_NEAR(wire(loop.segments, 0), loop.loop_radius_mm, 1e-12);
}

TEST(Loop, FollowsPoseAndExtension) {
  LoopGeometry loop;
  haptics::ToolPose pose;
  pose.tip = {1, 2, 3};
  pose.rotation = haptics::frameFromAxisUp({1, 0, 0}, {0, 0, 1});  // axis +x, up +z
  pose.extension_mm = 2.0;
  Eigen::Matrix<double, Eigen::Dynamic, 3> wire;
  loopPoints(loop, pose, wire);
  const Eigen::Vector3d lowest = wire.row(loop.segments / 2).transpose();
  EXPECT_NEAR(lowest.x(), 1 + loop.reach_mm + 2.0, 1e-12);
  EXPECT_NEAR(lowest.z(), 3 - loop.drop_mm - loop.loop_radius_mm, 1e-12);
}

// A straight pull of length L sweeps the paper's extruded loop: a half-cylinder strip of
// area ~ L * (arc length), within the polyline's chord error.
TEST(Sweep, StraightPullIsAnExtrudedLoop) {
  LoopGeometry loop;
  loop.segments = 64;
  haptics::ToolPose pose;
  Eigen::Matrix<double, Eigen::Dynamic, 3> wire;
  Sweep sweep;
  const double length = 10.0;
  for (int k = 0; k <= 20; ++k) {
    pose.tip = {0, 0, -length * k / 20.0};  // drawn back towards the camera
    loopPoints(loop, pose, wire);
    sweep.advance(wire);
  }
  const double arc = kPi * loop.loop_radius_mm;
  const double chord = 2 * loop.segments * loop.loop_radius_mm * std::sin(kPi / (2 * loop.segments));
  EXPECT_NEAR(sweep.area(), length * chord, 1e-9);
  EXPECT_NEAR(sweep.area(), length * arc, 0.001 * length * arc);
  EXPECT_NEAR(sweep.pathLength(), length, 1e-12);
  EXPECT_EQ(sweep.triangles().rows(), 2 * 20 * loop.segments);
  EXPECT_EQ(sweep.vertices().rows(), 21 * (loop.segments + 1));
  for (int t = 0; t < sweep.triangles().rows(); ++t) EXPECT_LT(sweep.triangles().row(t).maxCoeff(), sweep.vertices().rows());
  sweep.clear();
  EXPECT_TRUE(sweep.empty());
}

}  // namespace
}  // namespace hysim::engine
