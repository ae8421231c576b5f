// The paper's four rotationally invariant cases of a tet the cut passes through (0-3 of its
// nodes on the cut and separated), each on a single tet: what the subdivision and the
// separation make of it, without the optimisation.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "box_mesh.hpp"
#include "hysim/cutting/cut3d.hpp"

namespace hysim::cutting {
namespace {

using Vec3 = Eigen::Vector3d;

struct Expected {
  TetCutCase tetCase;
  int tets, nodes, duplicated, pieces;
};

// Cuts the unit corner tet with a plane (hybrid, no optimisation) and checks the case count,
// the output's size, validity and the separation of the two sides.
Cut3DResult cutCase(const Vec3& point, const Vec3& normal, const Expected& want) {
  Cut3DOptions options;
  options.optimize.enabled = false;
  const TetMesh tet = testing::singleTet();
  auto plane = CutSurface::plane(point, normal);
  EXPECT_TRUE(plane.ok());
  auto r = cut3d(tet, *plane, options);
  EXPECT_TRUE(r.ok()) << r.error();
  if (!r.ok()) return {};
  std::array<int, 4> cases{};
  cases[static_cast<int>(want.tetCase)] = 1;
  EXPECT_EQ(r->report.tets_by_case, cases);
  EXPECT_EQ(r->mesh.numTets(), want.tets);
  EXPECT_EQ(r->mesh.numNodes(), want.nodes);
  EXPECT_EQ(r->report.duplicated_nodes, want.duplicated);
  const auto valid = validate(r->mesh);
  EXPECT_TRUE(valid.ok()) << valid.error();
  EXPECT_EQ(countStraddling(r->mesh, point, normal, 1e-12), 0);
  EXPECT_EQ(countFacesSharedAcross(r->mesh, point, normal, 1e-12), 0);
  EXPECT_EQ(tetComponents(r->mesh).count, want.pieces);
  return std::move(r).value();
}

// No node on the cut: the plane crosses three edges (1-3 split) or four (2-2 split).
TEST(Cut3DCases, NoNodeSeparatedOneThree) {
  const auto r = cutCase({0.5, 0, 0}, {1, 0, 0}, {TetCutCase::NoNodeSeparated, 4, 10, 3, 2});
  EXPECT_EQ(r.report.split_edges, 3);
  EXPECT_NEAR(totalVolume(r.mesh), 1.0 / 6.0, 1e-15);
}

TEST(Cut3DCases, NoNodeSeparatedTwoTwo) {
  const auto r = cutCase({0.25, 0.25, 0}, {1, 1, 0}, {TetCutCase::NoNodeSeparated, 6, 12, 4, 2});
  EXPECT_EQ(r.report.split_edges, 4);
  EXPECT_NEAR(totalVolume(r.mesh), 1.0 / 6.0, 1e-15);
}

// One node on the cut: the two edges of the face opposite it are split.
TEST(Cut3DCases, OneNodeSeparated) {
  const auto r = cutCase({1, 0, 0}, {1, 2, 0}, {TetCutCase::OneNodeSeparated, 3, 9, 3, 2});
  EXPECT_EQ(r.report.split_edges, 2);
  EXPECT_NEAR(totalVolume(r.mesh), 1.0 / 6.0, 1e-15);
}

// Two nodes on the cut: the opposite edge is split.
TEST(Cut3DCases, TwoNodesSeparated) {
  const auto r = cutCase({0, 0, 0}, {0, 1, -1}, {TetCutCase::TwoNodesSeparated, 2, 8, 3, 2});
  EXPECT_EQ(r.report.split_edges, 1);
  EXPECT_NEAR(totalVolume(r.mesh), 1.0 / 6.0, 1e-15);
}

// Three nodes on the cut, here snapped onto it (each corner slides along its edge to node 0):
// the tet keeps its face on the cut, nothing is split, and a single tet has no neighbour
// across that face to separate from.
TEST(Cut3DCases, ThreeNodesSeparated) {
  const auto r = cutCase(Vec3(0.95, 0, 0), Vec3(1, 1, 1), {TetCutCase::ThreeNodesSeparated, 1, 4, 0, 1});
  EXPECT_EQ(r.report.snapped_nodes, 3);
  EXPECT_EQ(r.report.split_edges, 0);
  EXPECT_NEAR(totalVolume(r.mesh), std::pow(0.95, 3) / 6.0, 1e-15);
}

}  // namespace
}  // namespace hysim::cutting
