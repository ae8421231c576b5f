// The face adjacency kept across a cut and the free pieces found near it give exactly what
// the whole-mesh routines give (cutting::matchFaces, cutting::tetPieces), and the
// nearest-point grid what a linear scan gives. (matchFaces itself: tests/cutting/test_tet_faces.cpp.)
#include "hysim/engine/mesh_faces.hpp"

#include <gtest/gtest.h>

#include <random>

#include "box_mesh.hpp"
#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/mesh_io.hpp"

namespace hysim::engine {
namespace {

using Vec3 = Eigen::Vector3d;

// The cut surface of the tests below: the plane through c with normal n or, when `quad`, a
// nearly flat quad around c (corners 3 d below and d above c in x and y) that ends inside
// the mesh (a partial cut).
Result<cutting::CutSurface> planeOrQuad(const Vec3& c, const Vec3& d, const Vec3& n, bool quad) {
  if (!quad) return cutting::CutSurface::plane(c, n.normalized());
  cutting::Positions v(4, 3);
  v << c.x() - 3 * d.x(), c.y() - 3 * d.y(), c.z(), c.x() + d.x(), c.y() - 3 * d.y(), c.z() + 0.01 * d.z(),
      c.x() - 3 * d.x(), c.y() + d.y(), c.z() + 0.02 * d.z(), c.x() + d.x(), c.y() + d.y(), c.z();
  cutting::Tris f(2, 3);
  f << 0, 1, 3, 0, 3, 2;
  return cutting::CutSurface::triangles(v, f);
}

// `mesh` cut by planeOrQuad(c, d, n, quad) with `method`.
Result<cutting::Cut3DResult> cutPlaneOrQuad(const cutting::TetMesh& mesh, const Vec3& c, const Vec3& d, const Vec3& n,
                                            bool quad, cutting::CutMethod method) {
  const Result<cutting::CutSurface> surface = planeOrQuad(c, d, n, quad);
  if (!surface.ok()) return Error{surface.error()};
  cutting::Cut3DOptions options;
  options.method = method;
  return cutting::cut3d(mesh, *surface, options);
}

// updateFaces after a sequence of cuts (through, partial, hybrid and standard, on the uterus
// and a box) gives exactly matchFaces' next of the cut mesh, and refuses mismatched input.
TEST(MeshFaces, UpdateAfterCutsMatchesMatchingAllFaces) {
  auto uterus = cutting::readTetMesh(std::string(HYSIM_SOURCE_DIR) + "/assets/uterus_myoma.msh");
  ASSERT_TRUE(uterus.ok()) << uterus.error();
  for (const cutting::TetMesh& start : {testing::boxTetMesh(5, 5, 5, 0.4), *uterus}) {
    cutting::TetMesh mesh = start;
    std::vector<int> next;
    ASSERT_TRUE(matchFaces(mesh, next));
    const Vec3 lo = mesh.X.colwise().minCoeff().transpose(), hi = mesh.X.colwise().maxCoeff().transpose();
    for (int cut = 0; cut < 4; ++cut) {
      const Vec3 c = lo + (hi - lo).cwiseProduct(Vec3(0.31 + 0.11 * cut, 0.47, 0.29 + 0.13 * cut));
      const Vec3 d = (hi - lo) * 0.3;
      // A quad that ends inside the mesh (partial) for odd cuts, a plane for even ones.
      auto r = cutPlaneOrQuad(mesh, c, d, Vec3(0.2 * cut, 0.1, 1.0), cut % 2 == 1,
                              cut < 2 ? cutting::CutMethod::Hybrid : cutting::CutMethod::Standard);
      ASSERT_TRUE(r.ok()) << r.error();
      std::vector<int> updated, expected;
      ASSERT_TRUE(updateFaces(mesh, next, r->mesh, r->change.node_old_to_new, r->change.element_old_to_new, updated))
          << "cut " << cut;
      ASSERT_TRUE(matchFaces(r->mesh, expected));
      EXPECT_EQ(updated, expected) << "cut " << cut;
      // Wrong sizes: refused, output untouched.
      std::vector<int> untouched{3};
      EXPECT_FALSE(updateFaces(mesh, std::vector<int>(5, -1), r->mesh, r->change.node_old_to_new,
                               r->change.element_old_to_new, untouched));
      EXPECT_EQ(untouched, std::vector<int>{3});
      mesh = r->mesh;
      next = expected;
    }
  }
}

// The free pieces found near a cut are tetPieces' free pieces, in the same order, for cuts
// that free one or more pieces and cuts that free none (a mesh of one anchored piece before).
TEST(MeshFaces, FreePiecesNearTheCutAreThoseOfAllTets) {
  auto uterus = cutting::readTetMesh(std::string(HYSIM_SOURCE_DIR) + "/assets/uterus_myoma.msh");
  ASSERT_TRUE(uterus.ok()) << uterus.error();
  int freed = 0, cuts = 0;
  for (const cutting::TetMesh& start : {testing::boxTetMesh(6, 6, 6, 0.4), *uterus}) {
    const Vec3 lo = start.X.colwise().minCoeff().transpose(), hi = start.X.colwise().maxCoeff().transpose();
    // Anchored: the bottom tenth (z).
    auto anchoredOf = [&](const cutting::TetMesh& m) {
      std::vector<std::uint8_t> a(static_cast<size_t>(m.numNodes()), 0);
      for (int i = 0; i < m.numNodes(); ++i) a[i] = m.X(i, 2) < lo.z() + 0.1 * (hi.z() - lo.z());
      return a;
    };
    std::vector<int> next;
    ASSERT_TRUE(matchFaces(start, next));
    const std::vector<std::uint8_t> anchored_before = anchoredOf(start);
    const std::vector<int> distance = anchorDistance(start, next, anchored_before);
    ASSERT_EQ(tetPieces(start, next, anchored_before).count, 1);
    for (int t = 0; t < start.numTets(); ++t) ASSERT_LT(distance[t], start.numTets());
    for (int cut = 0; cut < 6; ++cut) {
      // Planes tilted through the upper half (the top comes off) and quads into the side
      // (nothing comes off, or a flap does).
      const Vec3 c = lo + (hi - lo).cwiseProduct(Vec3(0.37 + 0.05 * cut, 0.43, 0.55 + 0.06 * cut));
      const Vec3 d = (hi - lo) * 0.3;
      auto r = cutPlaneOrQuad(start, c, d, Vec3(0.1 * cut, 0.15, 1.0), cut % 2 == 1,
                              cut < 4 ? cutting::CutMethod::Hybrid : cutting::CutMethod::Standard);
      ASSERT_TRUE(r.ok()) << r.error();
      const cutting::TetMesh& after = r->mesh;
      std::vector<int> updated;
      FaceChange change;
      ASSERT_TRUE(updateFaces(start, next, after, r->change.node_old_to_new, r->change.element_old_to_new, updated,
                              &change));
      const std::vector<std::uint8_t> anchored = anchoredOf(after);
      const Pieces all = tetPieces(after, updated, anchored);
      const Pieces near = freePiecesAfterCut(after, updated, anchored, change, distance);
      // The same free pieces: free tets alike, and the free pieces in the same order.
      std::vector<int> all_order, near_order;  // free piece of each free tet, renumbered by first use
      std::vector<int> all_seen(static_cast<size_t>(all.count), -1), near_seen(static_cast<size_t>(near.count), -1);
      int all_n = 0, near_n = 0;
      for (int t = 0; t < after.numTets(); ++t) {
        const bool all_free = all.free[all.label[t]] != 0, near_free = near.free[near.label[t]] != 0;
        ASSERT_EQ(all_free, near_free) << "cut " << cut << " tet " << t;
        if (!all_free) continue;
        if (all_seen[all.label[t]] < 0) all_seen[all.label[t]] = all_n++;
        if (near_seen[near.label[t]] < 0) near_seen[near.label[t]] = near_n++;
        EXPECT_EQ(all_seen[all.label[t]], near_seen[near.label[t]]) << "cut " << cut << " tet " << t;
        EXPECT_EQ(near.label[t], near_seen[near.label[t]] + 1);  // numbered in order, from 1
      }
      EXPECT_EQ(near.count, near_n + 1);
      EXPECT_EQ(near.free[0], 0);
      freed += all_n;
      ++cuts;
    }
  }
  EXPECT_EQ(cuts, 12);
  EXPECT_GE(freed, 4);
}

TEST(MeshFaces, NearestPointMatchesALinearScan) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  sim::NodeVectors x(400, 3);
  for (int i = 0; i < x.rows(); ++i) {
    // Every fourth point on a coarse lattice, some of them twice: ties by distance.
    if (i % 4 == 0) {
      x.row(i) << std::round(u(rng)), std::round(u(rng)), 0.0;
    } else {
      x.row(i) << u(rng), u(rng), 0.3 * u(rng);
    }
  }
  std::vector<int> pts;
  for (int i = 0; i < x.rows(); i += 2) pts.push_back(i);
  std::reverse(pts.begin(), pts.end());  // scan order is not index order
  NearestPoint grid;
  grid.build(x, pts);
  for (int q = 0; q < 2000; ++q) {
    // Inside, far outside and on lattice points (exact ties).
    Vec3 p(u(rng), u(rng), u(rng));
    if (q % 3 == 1) p *= 6.0;
    if (q % 3 == 2) p = Vec3(std::round(p[0]) + 0.5, std::round(p[1]), 0.0);
    int expected = -1;
    double best = std::numeric_limits<double>::infinity();
    for (int i : pts) {
      const double d = (x.row(i).transpose() - p).squaredNorm();
      if (d < best) {
        best = d;
        expected = i;
      }
    }
    ASSERT_EQ(grid.nearest(p), expected) << q;
  }
  NearestPoint empty;
  const std::vector<int> none;
  empty.build(x, none);
  EXPECT_EQ(empty.nearest(Vec3::Zero()), -1);
}

}  // namespace
}  // namespace hysim::engine
