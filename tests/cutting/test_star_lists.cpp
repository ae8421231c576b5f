// The node -> tet lists cut3d builds once and hands to the optimisation (optimize3d_internal.hpp):
// patched lists (the input's, updated for the rows a cut rewrote and appended) equal lists
// built from scratch for the new mesh.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "../../cutting/src/optimize3d_internal.hpp"
#include "box_mesh.hpp"
#include "hysim/cutting/cut3d.hpp"

namespace hysim::cutting {
namespace {

using Vec3 = Eigen::Vector3d;

// Node n's list, from the CSR row or the pool.
std::vector<std::int32_t> listOf(const StarLists& s, int n) {
  if (!s.pool_start.empty() && s.pool_start[n] >= 0)
    return {s.pool.begin() + s.pool_start[n], s.pool.begin() + s.pool_start[n] + s.pool_len[n]};
  return {s.star.begin() + s.off[n], s.star.begin() + s.off[n + 1]};
}

void expectSameLists(const StarLists& patched, const Tets& T, int numNodes) {
  StarLists full;
  buildStarLists(T, numNodes, &full);
  ASSERT_EQ(static_cast<int>(patched.off.size()), numNodes + 1);
  for (int n = 0; n < numNodes; ++n) {
    EXPECT_EQ(listOf(patched, n), listOf(full, n)) << "node " << n;
    std::vector<std::int32_t> direct;  // every tet with n, ascending
    for (int t = 0; t < T.rows(); ++t)
      for (int k = 0; k < 4; ++k)
        if (T(t, k) == n) direct.push_back(t);
    EXPECT_EQ(listOf(full, n), direct) << "node " << n;
  }
}

TEST(StarLists, PatchedAfterACutEqualsBuiltFromScratch) {
  const TetMesh box = hysim::testing::boxTetMesh(5, 4, 4, 0.5);
  Cut3DOptions o;
  o.optimize.enabled = false;  // the mesh as the cut leaves it (no compaction)
  auto r = cut3d(box, *CutSurface::plane(Vec3(1.13, 0.97, 1.04), Vec3(0.3, 0.2, 1.0)), o);
  ASSERT_TRUE(r.ok()) << r.error();
  const Tets& after = r->mesh.T;
  ASSERT_GT(after.rows(), box.T.rows());
  std::vector<std::int32_t> changed;
  for (int t = 0; t < box.T.rows(); ++t)
    if (box.T.row(t) != after.row(t)) {
      changed.push_back(t);
      changed.push_back(t);  // repeats are allowed
    }
  ASSERT_FALSE(changed.empty());
  changed.push_back(0);  // so is a row listed but not changed
  StarLists s;
  buildStarLists(box.T, box.numNodes(), &s);
  patchStarLists(box.T, after, r->mesh.numNodes(), changed, &s);
  expectSameLists(s, after, r->mesh.numNodes());
}

TEST(StarLists, PatchedAfterRandomRewritesEqualsBuiltFromScratch) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const int N0 = 40, M0 = 60, N1 = N0 + static_cast<int>(rng() % 6), M1 = M0 + static_cast<int>(rng() % 10);
    auto randomRow = [&](Tets& T, int t, int numNodes) {
      std::vector<std::int32_t> v;  // four distinct nodes
      while (v.size() < 4) {
        const std::int32_t x = static_cast<std::int32_t>(rng() % numNodes);
        if (std::find(v.begin(), v.end(), x) == v.end()) v.push_back(x);
      }
      for (int k = 0; k < 4; ++k) T(t, k) = v[k];
    };
    Tets before(M0, 4);
    for (int t = 0; t < M0; ++t) randomRow(before, t, N0);
    Tets after(M1, 4);
    after.topRows(M0) = before;
    std::vector<std::int32_t> changed;
    for (int i = 0; i < 8; ++i) {
      const int t = static_cast<int>(rng() % M0);
      randomRow(after, t, N1);
      changed.push_back(t);
    }
    for (int t = M0; t < M1; ++t) randomRow(after, t, N1);
    StarLists s;
    buildStarLists(before, N0, &s);
    patchStarLists(before, after, N1, changed, &s);
    expectSameLists(s, after, N1);
  }
}

}  // namespace
}  // namespace hysim::cutting
