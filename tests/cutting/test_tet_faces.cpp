// The face adjacency (matchFaces, tetPieces, boundaryFromSlots) against a plain reference: a
// map from each face's sorted nodes to its slots, and a union-find over shared faces.
#include "hysim/cutting/tet_faces.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <map>
#include <numeric>

#include "box_mesh.hpp"
#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/mesh_io.hpp"

namespace hysim::cutting {
namespace {

using Vec3 = Eigen::Vector3d;

// next as matchFaces defines it, from a map of sorted faces to their slots (ascending).
std::vector<int> referenceNext(const TetMesh& mesh) {
  std::map<std::array<int, 3>, std::vector<int>> slotsOf;
  for (int t = 0; t < mesh.numTets(); ++t)
    for (int k = 0; k < 4; ++k) {
      std::array<int, 3> key{mesh.T(t, kTetFace[k][0]), mesh.T(t, kTetFace[k][1]), mesh.T(t, kTetFace[k][2])};
      std::sort(key.begin(), key.end());
      slotsOf[key].push_back(4 * t + k);
    }
  std::vector<int> next(4 * static_cast<size_t>(mesh.numTets()), -1);
  for (const auto& [key, slots] : slotsOf)
    if (slots.size() > 1)
      for (size_t i = 0; i < slots.size(); ++i) next[slots[i]] = slots[(i + 1) % slots.size()];
  return next;
}

// Component labels numbered by first tet, from a union-find over the reference's faces.
std::vector<int> referenceLabels(const TetMesh& mesh, const std::vector<int>& next, int* count) {
  std::vector<int> parent(static_cast<size_t>(mesh.numTets()));
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&parent](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (size_t s = 0; s < next.size(); ++s)
    if (next[s] >= 0) parent[find(static_cast<int>(s / 4))] = find(next[s] / 4);
  std::vector<int> id(parent.size(), -1), label(parent.size());
  *count = 0;
  for (size_t t = 0; t < parent.size(); ++t) {
    const int r = find(static_cast<int>(t));
    if (id[r] < 0) id[r] = (*count)++;
    label[t] = id[r];
  }
  return label;
}

void expectSameAsReference(const TetMesh& mesh) {
  std::vector<int> next;
  ASSERT_TRUE(matchFaces(mesh, next));
  const std::vector<int> expected = referenceNext(mesh);
  ASSERT_EQ(next, expected);
  std::vector<std::uint8_t> anchored(static_cast<size_t>(mesh.numNodes()), 0);
  for (int i = 0; i < mesh.numNodes(); ++i) anchored[i] = mesh.X(i, 2) < 0.3;
  const Pieces pieces = tetPieces(mesh, next, anchored);
  int count = 0;
  EXPECT_EQ(pieces.label, referenceLabels(mesh, expected, &count));
  ASSERT_EQ(pieces.count, count);
  for (int t = 0; t < mesh.numTets(); ++t)
    for (int k = 0; k < 4; ++k)
      if (anchored[mesh.T(t, k)]) {
        EXPECT_EQ(pieces.free[pieces.label[t]], 0) << t;
      }
  // Whole-mesh routines built on it: boundary faces are the unmatched slots in slot order.
  Eigen::VectorXi face_tet;
  const Tris faces = boundaryFaces(mesh, &face_tet);
  Eigen::Index row = 0;
  for (size_t s = 0; s < expected.size(); ++s) {
    if (expected[s] >= 0) continue;
    ASSERT_LT(row, faces.rows());
    const int t = static_cast<int>(s / 4);
    for (int j = 0; j < 3; ++j) EXPECT_EQ(faces(row, j), mesh.T(t, kTetFace[s % 4][j]));
    EXPECT_EQ(face_tet(row), t);
    ++row;
  }
  EXPECT_EQ(row, faces.rows());
  const Components3D comps = tetComponents(mesh);
  EXPECT_EQ(comps.count, count);
}

TEST(TetFaces, SameAsReferenceOnABox) { expectSameAsReference(testing::boxTetMesh(4, 4, 4, 0.5)); }

TEST(TetFaces, SameAsReferenceAfterThroughAndPartialCuts) {
  const auto box = testing::boxTetMesh(5, 5, 5, 0.4);
  auto through = cut3d(box, *CutSurface::plane(Vec3(1.0, 1.0, 1.13), Vec3(0.2, 0.1, 1)));
  ASSERT_TRUE(through.ok()) << through.error();
  expectSameAsReference(through->mesh);
  int count = 0;
  std::vector<int> next;
  ASSERT_TRUE(matchFaces(through->mesh, next));
  referenceLabels(through->mesh, next, &count);
  EXPECT_GE(count, 2);  // the top came off
  Positions v(4, 3);
  v << -0.5, -0.5, 1.07, 1.1, -0.5, 1.07, -0.5, 2.5, 1.07, 1.1, 2.5, 1.07;
  Tris f(2, 3);
  f << 0, 1, 3, 0, 3, 2;
  auto partial = cut3d(box, *CutSurface::triangles(v, f));
  ASSERT_TRUE(partial.ok()) << partial.error();
  expectSameAsReference(partial->mesh);
}

TEST(TetFaces, SameAsReferenceOnTheUterus) {
  auto mesh = readTetMesh(std::string(HYSIM_SOURCE_DIR) + "/assets/uterus_myoma.msh");
  ASSERT_TRUE(mesh.ok()) << mesh.error();
  expectSameAsReference(*mesh);
}

TEST(TetFaces, AFaceSharedByThreeTetsJoinsThemAll) {
  // Not a valid mesh: the face's three slots form one cycle and its tets one piece.
  TetMesh m;
  m.X.resize(7, 3);
  m.X << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0.2, 0.2, 1, 0.1, 0.3, -1, 5, 5, 5;
  m.T.resize(4, 4);
  m.T << 6, 4, 5, 3, 0, 1, 2, 3, 1, 2, 0, 4, 0, 2, 1, 5;  // (0, 1, 2) in tets 1, 2 and 3
  m.material = Labels::Ones(4);
  expectSameAsReference(m);
  std::vector<int> next;
  ASSERT_TRUE(matchFaces(m, next));
  EXPECT_EQ(tetPieces(m, next, std::vector<std::uint8_t>(7, 0)).count, 2);
  EXPECT_FALSE(validate(m).ok());
}

TEST(TetFaces, RejectsMissingNodesButMatchesAnyIdsOnRequest) {
  auto box = testing::boxTetMesh(2, 2, 2, 0.5);
  const std::vector<int> whole = referenceNext(box);
  box.T(0, 0) = box.numNodes() + 1000;
  std::vector<int> next{7};
  EXPECT_FALSE(matchFaces(box, next));
  EXPECT_EQ(next, std::vector<int>{7});
  matchFacesOfAnyIds(box, next);
  EXPECT_EQ(next, referenceNext(box));
  EXPECT_NE(next, whole);  // tet 0's faces through the moved id no longer match
}

}  // namespace
}  // namespace hysim::cutting
