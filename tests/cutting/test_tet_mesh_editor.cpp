// TetMeshEditor: every operation leaves the editor valid (validate() after each), refuses what
// would break the mesh without changing anything, and compact() reports what changed.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "box_mesh.hpp"
#include "hysim/cutting/mesh.hpp"
#include "hysim/cutting/tet_mesh_editor.hpp"

namespace hysim::cutting {
namespace {

using Vec3 = Eigen::Vector3d;
using testing::boxTetMesh;

double liveVolume(const TetMesh& mesh, const std::vector<std::uint8_t>& dead) {
  double v = 0;
  for (int t = 0; t < mesh.numTets(); ++t)
    if (!dead[t]) v += tetVolume(mesh, t);
  return v;
}

std::vector<int> liveStarOf(const TetMeshEditor& ed, int n) {
  std::vector<int> out;
  for (const std::int32_t *s = ed.starBegin(n), *e = ed.starEnd(n); s < e; ++s)
    if (!ed.isDead(*s)) out.push_back(*s);
  return out;
}

// A box mesh with its interior nodes moved a little at random (a structured mesh has coplanar
// neighbours, where no flip is valid).
TetMesh jitteredBox(int n, unsigned seed) {
  TetMesh mesh = boxTetMesh(n, n, n, 1.0);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> d(-0.15, 0.15);
  const Vec3 lo = mesh.X.colwise().minCoeff(), hi = mesh.X.colwise().maxCoeff();
  for (int i = 0; i < mesh.numNodes(); ++i) {
    const Vec3 x = mesh.X.row(i);
    if ((x - lo).minCoeff() > 1e-9 && (hi - x).minCoeff() > 1e-9) mesh.X.row(i) += Vec3(d(rng), d(rng), d(rng)).transpose();
  }
  return mesh;
}

// A node with no boundary face: all 6 x 4 x ... tets of a box around it.
int interiorNode(const TetMesh& mesh) {
  const Vec3 lo = mesh.X.colwise().minCoeff(), hi = mesh.X.colwise().maxCoeff();
  for (int n = 0; n < mesh.numNodes(); ++n) {
    const Vec3 x = mesh.X.row(n);
    if ((x - lo).minCoeff() > 1e-9 && (hi - x).minCoeff() > 1e-9) return n;
  }
  return -1;
}

TEST(TetMeshEditor, StartsValid) {
  TetMesh mesh = boxTetMesh(3, 3, 3, 1.0);
  std::vector<std::uint8_t> dead;
  TetMeshEditor ed(mesh, dead);
  const Status s = ed.validate();
  EXPECT_TRUE(s.ok()) << s.error();
  EXPECT_EQ(dead.size(), static_cast<size_t>(mesh.numTets()));
}

TEST(TetMeshEditor, SplitEdgeKeepsVolumeAndRecordsTheNewNode) {
  TetMesh mesh = boxTetMesh(3, 3, 3, 1.0);
  const int M0 = mesh.numTets(), N0 = mesh.numNodes();
  std::vector<std::uint8_t> dead;
  TetMeshEditor ed(mesh, dead);
  const double v0 = liveVolume(mesh, dead);
  const int a = mesh.T(5, 0), b = mesh.T(5, 2);
  std::vector<int> around;
  for (int t : liveStarOf(ed, a))
    for (int k = 0; k < 4; ++k)
      if (mesh.T(t, k) == b) around.push_back(t);
  ASSERT_FALSE(around.empty());
  const Vec3 xa = mesh.X.row(a), xb = mesh.X.row(b);
  const int m = ed.splitEdge(a, b, 0.3);
  ASSERT_EQ(m, N0);
  ASSERT_TRUE(ed.validate().ok()) << ed.validate().error();
  EXPECT_LT((Vec3(mesh.X.row(m)) - (0.7 * xa + 0.3 * xb)).norm(), 1e-12);
  EXPECT_NEAR(liveVolume(mesh, dead), v0, 1e-12 * v0);
  EXPECT_EQ(liveStarOf(ed, m).size(), 2 * around.size());
  EXPECT_EQ(ed.splitEdge(a, m == a ? b : a, 0.0), -1);  // w outside (0, 1)
  ed.compact();
  ASSERT_TRUE(ed.validate().ok());
  const TopologyChange& c = ed.change();
  EXPECT_EQ(c.old_num_elements, M0);
  EXPECT_EQ(c.new_num_elements, M0 + static_cast<int>(around.size()));
  ASSERT_EQ(c.new_nodes.size(), 1u);
  EXPECT_EQ(c.new_nodes[0].num_parents, 2);
  EXPECT_EQ(c.new_nodes[0].parents[0], a);
  EXPECT_EQ(c.new_nodes[0].parents[1], b);
  EXPECT_EQ(c.removed_elements.size(), around.size());
  EXPECT_EQ(c.added_elements.size(), 2 * around.size());
  EXPECT_TRUE(cutting::validate(mesh).ok());
}

TEST(TetMeshEditor, MoveNodeRefusesInversionAndQualityLoss) {
  TetMesh mesh = boxTetMesh(4, 4, 4, 1.0);
  std::vector<std::uint8_t> dead;
  TetMeshEditor ed(mesh, dead);
  const int n = interiorNode(mesh);
  ASSERT_GE(n, 0);
  const Vec3 x = mesh.X.row(n);
  EXPECT_FALSE(ed.moveNode(n, x + Vec3(3, 0, 0), 0.0));  // through its neighbours: inverts
  EXPECT_EQ(Vec3(mesh.X.row(n)), x);
  EXPECT_FALSE(ed.moveNode(n, x + Vec3(0.45, 0.45, 0), 0.5));  // worse than the floor and than before
  EXPECT_EQ(Vec3(mesh.X.row(n)), x);
  EXPECT_TRUE(ed.moveNode(n, x + Vec3(0.02, -0.01, 0.01), 0.0));
  EXPECT_TRUE(ed.validate().ok()) << ed.validate().error();
  EXPECT_FALSE(ed.moveNode(n, Vec3(NAN, 0, 0), 0.0));
  ed.compact();
  EXPECT_EQ(ed.change().moved_nodes, std::vector<std::int32_t>{n});
}

TEST(TetMeshEditor, DuplicateNodeSeparatesTheSides) {
  TetMesh mesh = boxTetMesh(4, 4, 4, 1.0);
  std::vector<std::uint8_t> dead;
  TetMeshEditor ed(mesh, dead);
  const int n = interiorNode(mesh);
  const double xn = mesh.X(n, 0);
  std::vector<std::int32_t> side;
  for (int t : liveStarOf(ed, n)) {
    double cx = 0;
    for (int k = 0; k < 4; ++k) cx += mesh.X(mesh.T(t, k), 0) / 4;
    if (cx < xn) side.push_back(t);
  }
  ASSERT_FALSE(side.empty());
  const int m = ed.duplicateNode(n, side);
  ASSERT_GE(m, 0);
  ASSERT_TRUE(ed.validate().ok()) << ed.validate().error();
  EXPECT_EQ(liveStarOf(ed, m).size(), side.size());
  for (int t : liveStarOf(ed, n)) EXPECT_EQ(std::count(side.begin(), side.end(), t), 0);
  EXPECT_EQ(ed.duplicateNode(n, side), -1);  // those tets no longer hold n
  ed.compact();
  ASSERT_EQ(ed.change().new_nodes.size(), 1u);
  EXPECT_TRUE(ed.change().new_nodes[0].duplicate);
  EXPECT_EQ(ed.change().removed_elements.size(), 0u);  // renumbered nodes: same elements
}

TEST(TetMeshEditor, FlipTwoThreeAndBackKeepsVolume) {
  TetMesh mesh = jitteredBox(3, 5);
  std::vector<std::uint8_t> dead;
  TetMeshEditor ed(mesh, dead);
  const double v0 = liveVolume(mesh, dead);
  int flipped = 0;
  for (int t = 0; t < mesh.numTets() && flipped == 0; ++t)
    for (int f = 0; f < 4 && flipped == 0; ++f) {
      const int M = mesh.numTets();
      if (!ed.flip23(t, f)) {
        ASSERT_EQ(mesh.numTets(), M);
        continue;
      }
      flipped = 1;
      ASSERT_TRUE(ed.validate().ok()) << ed.validate().error();
      EXPECT_NEAR(liveVolume(mesh, dead), v0, 1e-12 * v0);
      // The new edge joins t's node f to the neighbour's far node, with three tets around it:
      // 3-2 about it undoes the flip.
      const int d = mesh.T(t, f);
      int far = -1;
      for (int s : liveStarOf(ed, d))
        for (int k = 0; k < 4; ++k) {
          const int w = mesh.T(s, k);
          int around = 0;
          for (int r : liveStarOf(ed, d))
            for (int j = 0; j < 4; ++j) around += mesh.T(r, j) == w;
          if (w != d && around == 3 && far < 0) {
            const int live = static_cast<int>(std::count(dead.begin(), dead.end(), 0));
            if (ed.flip32(d, w)) {
              far = w;
              EXPECT_EQ(static_cast<int>(std::count(dead.begin(), dead.end(), 0)), live - 1);
            }
          }
        }
      EXPECT_GE(far, 0);
      ASSERT_TRUE(ed.validate().ok()) << ed.validate().error();
      EXPECT_NEAR(liveVolume(mesh, dead), v0, 1e-12 * v0);
    }
  EXPECT_EQ(flipped, 1);
}

TEST(TetMeshEditor, RefusedCollapseChangesNothing) {
  TetMesh mesh = boxTetMesh(3, 3, 3, 1.0);
  std::vector<std::uint8_t> dead;
  TetMeshEditor ed(mesh, dead);
  int done = 0, refused = 0;
  for (int t = 0; t < 40; ++t) {
    if (dead[t]) continue;
    const TetMesh before = mesh;
    const std::vector<std::uint8_t> deadBefore = dead;
    if (ed.collapseEdge(mesh.T(t, 0), mesh.T(t, 1))) {
      ++done;
    } else {
      ++refused;
      EXPECT_EQ(mesh.T, before.T);
      EXPECT_EQ(dead, deadBefore);
    }
    ASSERT_TRUE(ed.validate().ok()) << ed.validate().error();
  }
  EXPECT_GT(done, 0);
  EXPECT_GT(refused, 0);
  ed.compact();
  EXPECT_TRUE(cutting::validate(mesh).ok());
}

// Thousands of random operations, validate() after each one.
TEST(TetMeshEditor, RandomOperationsKeepEverythingValid) {
  TetMesh mesh = jitteredBox(4, 7);
  std::vector<std::uint8_t> dead;
  TetMeshEditor ed(mesh, dead);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int ok[7] = {0, 0, 0, 0, 0, 0, 0};
  for (int i = 0; i < 3000; ++i) {
    int t = static_cast<int>(rng() % mesh.numTets());
    for (int tries = 0; dead[t] && tries < 100; ++tries) t = static_cast<int>(rng() % mesh.numTets());
    if (dead[t]) continue;
    const int ka = static_cast<int>(rng() % 4), kb = (ka + 1 + static_cast<int>(rng() % 3)) % 4;
    const int a = mesh.T(t, ka), b = mesh.T(t, kb);
    const int op = static_cast<int>(rng() % 7);
    bool done = false;
    switch (op) {
      case 0: done = ed.splitEdge(a, b, 0.2 + 0.6 * unit(rng)) >= 0; break;
      case 1: done = ed.moveNode(a, Vec3(mesh.X.row(a)) + 0.1 * Vec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5), 0.02); break;
      case 2: done = ed.flip23(t, static_cast<int>(rng() % 4)); break;
      case 3: done = ed.flip32(a, b); break;
      case 4: done = ed.collapseEdge(a, b); break;
      case 5: done = i % 10 == 0 && (ed.removeTet(t), true); break;
      case 6: if (i % 500 == 0) { ed.compact(); done = true; } break;
    }
    if (done) ++ok[op];
    const Status s = ed.validate();
    ASSERT_TRUE(s.ok()) << "operation " << i << " (kind " << op << "): " << s.error();
  }
  for (int op = 0; op < 7; ++op) EXPECT_GT(ok[op], 0) << "kind " << op << " never succeeded";
  ed.compact();
  EXPECT_TRUE(ed.validate().ok());
  EXPECT_TRUE(cutting::validate(mesh, {.requireAllNodesUsed = true}).ok());
}

}  // namespace
}  // namespace hysim::cutting
