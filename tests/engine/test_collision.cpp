// Loop electrode vs. tissue (FCL): the swept wire of one step against the tissue's surface.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "alloc_counter.hpp"
#include "box_mesh.hpp"
#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/mesh_io.hpp"
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

// The tool points down (-z) so the loop lies in a horizontal plane; its wire's points are at
// the height of the tip minus reach.
haptics::ToolPose poseAt(double height) {
  haptics::ToolPose pose;
  pose.rotation = haptics::frameFromAxisUp({0, 0, -1}, {0, 1, 0});
  pose.tip = {0, 0, height};
  return pose;
}

WirePoints wireAt(const LoopGeometry& loop, double wire_z, double x = 0.0) {
  haptics::ToolPose pose = poseAt(wire_z + loop.reach_mm);
  pose.tip.x() = x;
  WirePoints wire;
  loopPoints(loop, pose, wire);
  return wire;
}

double triangleArea(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  return 0.5 * (b - a).cross(c - a).norm();
}

TEST(Collision, SweptWireIsTheStripBetweenTwoWirePositions) {
  LoopGeometry loop;
  const WirePoints before = wireAt(loop, 2.0), after = wireAt(loop, 1.5);  // 0.5 mm down
  SweptWire sweep;
  sweep.reset(static_cast<int>(before.rows()));
  ASSERT_EQ(sweep.numPoints(), loop.segments + 1);
  ASSERT_EQ(sweep.numTriangles(), 2 * loop.segments);
  sweep.update(before, after);
  // Segment i's quad: triangles 2i (prev i, prev i+1, current i+1) and 2i+1 (prev i,
  // current i+1, current i). The motion is perpendicular to the loop's plane, so each quad is
  // a rectangle: its area is the segment's length times 0.5 mm.
  double wire_length = 0.0, area = 0.0;
  for (int i = 0; i < loop.segments; ++i) {
    Eigen::Vector3d a, b, c;
    sweep.triangle(2 * i, a, b, c);
    EXPECT_TRUE(a.isApprox(before.row(i).transpose()));
    EXPECT_TRUE(b.isApprox(before.row(i + 1).transpose()));
    EXPECT_TRUE(c.isApprox(after.row(i + 1).transpose()));
    area += triangleArea(a, b, c);
    sweep.triangle(2 * i + 1, a, b, c);
    EXPECT_TRUE(a.isApprox(before.row(i).transpose()));
    EXPECT_TRUE(b.isApprox(after.row(i + 1).transpose()));
    EXPECT_TRUE(c.isApprox(after.row(i).transpose()));
    area += triangleArea(a, b, c);
    wire_length += (before.row(i + 1) - before.row(i)).norm();
  }
  EXPECT_NEAR(area, 0.5 * wire_length, 1e-9);
  // A semicircle of radius 3.5 as 16 chords.
  EXPECT_NEAR(wire_length, 3.14159265358979 * loop.loop_radius_mm, 0.02);
}

TEST(Collision, BoundaryHierarchyOfASlab) {
  const cutting::TetMesh mesh = slab();
  TissueCollision collision;
  ASSERT_TRUE(collision.build(cutting::boundaryFaces(mesh), mesh.X).ok());
  // 2 triangles per boundary square: 2 * (10*10*2 + 10*4*2 + 10*4*2).
  EXPECT_EQ(collision.numFaces(), 2 * (200 + 80 + 80));
  EXPECT_EQ(collision.numVertices(), 11 * 11 * 5 - 9 * 9 * 3);  // interior nodes left out
  TissueCollision all;
  ASSERT_TRUE(all.build(allTetFaces(mesh), mesh.X).ok());
  EXPECT_GT(all.numFaces(), 2 * mesh.numTets());
  EXPECT_EQ(all.numVertices(), mesh.numNodes());
}

// Lower the loop through the slab in 0.05 mm steps: the swept wire touches the top face on
// the way in and the bottom face on the way out, and nothing of the surface while inside.
TEST(Collision, SweptWireTouchesTheSurfaceOnEntryAndExit) {
  const cutting::TetMesh mesh = slab();
  TissueCollision collision;
  ASSERT_TRUE(collision.build(cutting::boundaryFaces(mesh), mesh.X).ok());
  LoopGeometry loop;
  const double r = loop.wire_radius_mm;
  SweptWire sweep;
  sweep.reset(loop.segments + 1);
  WirePoints previous = wireAt(loop, 10.0);
  int contacts = 0;
  double first_in = 0, last_in = 0, first_out = 0, last_out = 0;
  for (int k = 1; k <= 400; ++k) {
    const double z = 10.0 - 0.05 * k;  // from 10 down to -10
    const WirePoints wire = wireAt(loop, z);
    sweep.update(previous, wire);
    const bool touching = collision.touches(sweep, r);
    if (touching) {
      if (z > 0) {
        if (first_in == 0) first_in = z;
        last_in = z;
      } else {
        if (first_out == 0) first_out = z;
        last_out = z;
      }
      ++contacts;
    }
    previous = wire;
  }
  // The strip from z + 0.05 down to z, thickened by r, touches the top face (z = 4) while
  // z - r <= 4 <= z + 0.05 + r, and the bottom face likewise.
  EXPECT_NEAR(first_in, 4.0 + r, 0.051);
  EXPECT_NEAR(last_in, 4.0 - r - 0.05, 0.051);
  EXPECT_NEAR(first_out, -4.0 + r, 0.051);
  EXPECT_NEAR(last_out, -4.0 - r - 0.05, 0.051);
  EXPECT_LT(contacts, 30);  // nothing in between: the inside is no surface
}

TEST(Collision, AWireAtRestTouchesWithinItsRadius) {
  const cutting::TetMesh mesh = slab();
  TissueCollision collision;
  ASSERT_TRUE(collision.build(cutting::boundaryFaces(mesh), mesh.X).ok());
  LoopGeometry loop;
  const double r = loop.wire_radius_mm;
  SweptWire sweep;
  sweep.reset(loop.segments + 1);
  // A wire that does not move sweeps degenerate quads (segments): the distance still counts.
  for (double gap : {2.0, 0.5, r + 0.01}) {
    const WirePoints wire = wireAt(loop, 4.0 + gap);
    sweep.update(wire, wire);
    EXPECT_FALSE(collision.touches(sweep, r)) << gap;
  }
  for (double gap : {r - 0.01, 0.0, -0.1}) {
    const WirePoints wire = wireAt(loop, 4.0 + gap);
    sweep.update(wire, wire);
    EXPECT_TRUE(collision.touches(sweep, r)) << gap;
  }
  // Far to the side: nothing.
  const WirePoints away = wireAt(loop, 0.0, 40.0);
  sweep.update(away, away);
  EXPECT_FALSE(collision.touches(sweep, r));
}

// A wire that jumps through the whole slab in one step (both positions outside) is caught by
// its sweep.
TEST(Collision, AFastMotionThroughTheSlabIsNotMissed) {
  const cutting::TetMesh mesh = slab();
  TissueCollision collision;
  ASSERT_TRUE(collision.build(cutting::boundaryFaces(mesh), mesh.X).ok());
  LoopGeometry loop;
  SweptWire sweep;
  sweep.reset(loop.segments + 1);
  const WirePoints above = wireAt(loop, 6.0), below = wireAt(loop, -6.0);
  sweep.update(above, above);
  EXPECT_FALSE(collision.touches(sweep, loop.wire_radius_mm));
  sweep.update(below, below);
  EXPECT_FALSE(collision.touches(sweep, loop.wire_radius_mm));
  sweep.update(above, below);
  EXPECT_TRUE(collision.touches(sweep, loop.wire_radius_mm));
}

TEST(Collision, RefitFollowsTheDeformation) {
  const cutting::TetMesh mesh = slab();
  sim::NodeVectors x = mesh.X;
  TissueCollision collision;
  ASSERT_TRUE(collision.build(cutting::boundaryFaces(mesh), x).ok());
  LoopGeometry loop;
  SweptWire sweep;
  sweep.reset(loop.segments + 1);
  const WirePoints wire = wireAt(loop, 6.0);  // 2 mm above the slab
  sweep.update(wire, wire);
  EXPECT_FALSE(collision.touches(sweep, loop.wire_radius_mm));
  x.col(2).array() += 1.9;  // the tissue rises by 1.9 mm: 0.1 mm below the wire
  collision.refit(x);
  EXPECT_TRUE(collision.touches(sweep, loop.wire_radius_mm));
  x.col(2).array() += 2.0;  // further: the wire is inside, away from the surface
  collision.refit(x);
  EXPECT_FALSE(collision.touches(sweep, loop.wire_radius_mm));
  x.col(2).array() -= 3.9;
  collision.refit(x);
  EXPECT_FALSE(collision.touches(sweep, loop.wire_radius_mm));
}

// update() with a margin: boxes are refitted only around vertices that left their margin,
// and queries stay exact in between (the narrow phase reads the moved vertices).
TEST(Collision, UpdateWithAMarginStaysExact) {
  const cutting::TetMesh mesh = slab();
  sim::NodeVectors x = mesh.X;
  TissueCollision collision;
  ASSERT_TRUE(collision.build(cutting::boundaryFaces(mesh), x, 0.5).ok());
  LoopGeometry loop;
  SweptWire sweep;
  sweep.reset(loop.segments + 1);
  const WirePoints wire = wireAt(loop, 6.0);  // 2 mm above the slab
  sweep.update(wire, wire);
  auto rise = [&](double dz) {
    x = mesh.X;
    x.col(2).array() += dz;
    collision.update(x);
    return collision.touches(sweep, loop.wire_radius_mm);
  };
  EXPECT_FALSE(rise(0.4));  // within the margin: no box changes
  EXPECT_EQ(collision.numLocalRefits(), 0);
  EXPECT_TRUE(rise(1.9));   // 0.1 mm below the wire
  EXPECT_EQ(collision.numLocalRefits(), collision.numHierarchyVertices());
  EXPECT_GE(collision.numHierarchyVertices(), collision.numVertices());
  EXPECT_FALSE(rise(2.3));  // wire 0.3 mm inside: no surface within 0.15 mm
  EXPECT_FALSE(rise(1.5));
  EXPECT_TRUE(rise(1.88));
  EXPECT_EQ(collision.numLocalRefits(), collision.numHierarchyVertices());  // all within the margin since
}

// Random jitter of every vertex (a random walk, steps up to 0.4 mm): update() answers as a
// hierarchy built from scratch does.
TEST(Collision, UpdateAgreesWithAFreshHierarchy) {
  const cutting::TetMesh mesh = slab();
  const cutting::Tris faces = cutting::boundaryFaces(mesh);
  sim::NodeVectors x = mesh.X;
  TissueCollision followed;
  ASSERT_TRUE(followed.build(faces, x, 0.5).ok());
  LoopGeometry loop;
  SweptWire sweep;
  sweep.reset(loop.segments + 1);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> step(-0.4, 0.4);
  int agreed = 0, touched = 0;
  for (int k = 0; k < 60; ++k) {
    for (Eigen::Index i = 0; i < x.rows(); ++i)
      for (int c = 0; c < 3; ++c) x(i, c) += step(rng);
    followed.update(x);
    TissueCollision fresh;
    ASSERT_TRUE(fresh.build(faces, x).ok());
    for (double z : {3.0, 3.6, 4.0, 4.4, 5.0, 6.0}) {
      const WirePoints a = wireAt(loop, z), b = wireAt(loop, z - 0.1);
      sweep.update(a, b);
      const bool expected = fresh.touches(sweep, loop.wire_radius_mm);
      agreed += followed.touches(sweep, loop.wire_radius_mm) == expected ? 1 : 0;
      touched += expected ? 1 : 0;
    }
  }
  EXPECT_EQ(agreed, 60 * 6);
  EXPECT_GT(touched, 30);
  EXPECT_GT(followed.numLocalRefits(), 0);
  EXPECT_EQ(followed.numRefits(), 1);  // the build's
}

// After a cut, a build that keeps the unchanged chunks (renumbered) answers every query as a
// build from scratch does, and rebuilds only some of the chunks.
TEST(Collision, AChunkedRebuildAfterACutAgreesWithAFreshOne) {
  auto uterus = cutting::readTetMesh(std::string(HYSIM_SOURCE_DIR) + "/assets/uterus_myoma.msh");
  ASSERT_TRUE(uterus.ok()) << uterus.error();
  cutting::TetMesh mesh = *uterus;
  TissueCollision followed;
  ASSERT_TRUE(followed.build(cutting::boundaryFaces(mesh), mesh.X, 0.5, &mesh.X).ok());
  const long first = followed.numChunksBuilt();
  EXPECT_GT(first, 8);
  const Eigen::Vector3d lo = mesh.X.colwise().minCoeff().transpose(), hi = mesh.X.colwise().maxCoeff().transpose();
  LoopGeometry loop;
  SweptWire sweep;
  sweep.reset(loop.segments + 1);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int cut = 0; cut < 3; ++cut) {
    // A partial quad cut near the myoma, then a hybrid plane cut.
    const Eigen::Vector3d c = lo + (hi - lo).cwiseProduct(Eigen::Vector3d(0.45 + 0.05 * cut, 0.35, 0.5));
    Result<cutting::CutSurface> surface = cutting::CutSurface::plane(c, Eigen::Vector3d(0.1 * cut, 1.0, 0.2).normalized());
    if (cut != 1) {
      cutting::Positions v(4, 3);
      v << c.x() - 6, c.y() - 0.3, c.z() - 6, c.x() + 6, c.y(), c.z() - 6, c.x() - 6, c.y(), c.z() + 6, c.x() + 6,
          c.y() + 0.3, c.z() + 6;
      cutting::Tris f(2, 3);
      f << 0, 1, 3, 0, 3, 2;
      surface = cutting::CutSurface::triangles(v, f);
    }
    ASSERT_TRUE(surface.ok());
    cutting::Cut3DOptions options;
    options.method = cutting::CutMethod::Hybrid;
    auto r = cutting::cut3d(mesh, *surface, options);
    ASSERT_TRUE(r.ok()) << r.error();
    mesh = r->mesh;
    const std::vector<int> renumber(r->change.node_old_to_new.begin(), r->change.node_old_to_new.end());
    const cutting::Tris faces = cutting::boundaryFaces(mesh);
    const long built = followed.numChunksBuilt(), kept = followed.numChunksKept();
    ASSERT_TRUE(followed.build(faces, mesh.X, 0.5, &mesh.X, &renumber).ok());
    EXPECT_GT(followed.numChunksKept(), kept) << "cut " << cut;
    EXPECT_LT(followed.numChunksBuilt() - built, first / 2) << "cut " << cut;
    TissueCollision fresh;
    ASSERT_TRUE(fresh.build(faces, mesh.X, 0.5, &mesh.X).ok());
    EXPECT_EQ(followed.numFaces(), fresh.numFaces());
    EXPECT_EQ(followed.numVertices(), fresh.numVertices());
    // Random short sweeps of the wire over the mesh's box.
    int touched = 0;
    for (int k = 0; k < 400; ++k) {
      const Eigen::Vector3d p = lo + (hi - lo).cwiseProduct(Eigen::Vector3d(u(rng), u(rng), u(rng)));
      haptics::ToolPose pose;
      pose.rotation = haptics::frameFromAxisUp(Eigen::Vector3d(u(rng) - 0.5, u(rng) - 0.5, 1.0).normalized(), {0, 1, 0});
      pose.tip = p;
      WirePoints a, b;
      loopPoints(loop, pose, a);
      pose.tip += Eigen::Vector3d(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
      loopPoints(loop, pose, b);
      sweep.update(a, b);
      const bool expected = fresh.touches(sweep, loop.wire_radius_mm);
      EXPECT_EQ(followed.touches(sweep, loop.wire_radius_mm), expected) << "cut " << cut << " sweep " << k;
      touched += expected ? 1 : 0;
    }
    EXPECT_GT(touched, 40);
    EXPECT_LT(touched, 360);
  }
}

TEST(Collision, RefitUpdateAndQueryAllocateNothing) {
  const cutting::TetMesh mesh = slab();
  sim::NodeVectors x = mesh.X;
  TissueCollision collision;
  ASSERT_TRUE(collision.build(cutting::boundaryFaces(mesh), x, 0.5).ok());
  LoopGeometry loop;
  SweptWire sweep;
  sweep.reset(loop.segments + 1);
  const WirePoints a = wireAt(loop, 4.1), b = wireAt(loop, 3.9);
  int touching = 0;
  long count = 0;
  {
    testing::AllocationCounter counter;
    for (int i = 0; i < 10; ++i) {
      x(0, 2) += 0.3;  // leaves the margin every other step
      collision.refit(x);
      collision.update(x);
      sweep.update(a, b);
      touching += collision.touches(sweep, loop.wire_radius_mm) ? 1 : 0;
    }
    count = counter.count();
  }
  EXPECT_EQ(touching, 10);
  EXPECT_EQ(count, 0);
}

}  // namespace
}  // namespace hysim::engine
