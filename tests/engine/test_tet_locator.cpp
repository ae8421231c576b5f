// TetLocator: the tet that holds a point, at positions that moved since the build.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "box_mesh.hpp"
#include "hysim/engine/tet_locator.hpp"

namespace hysim::engine {
namespace {

// The answer does not depend on where the grid was built nor on the displacement bound given
// (as long as it is one): a grid built at x0, queried at x1 with the displacement, gives what
// a fresh grid at x1 gives, for points inside, on faces, near and outside the tissue.
void expectSameAnswers(const cutting::TetMesh& mesh, const sim::NodeVectors& x0, const sim::NodeVectors& x1,
                       double min_moved) {
  TetLocator before, fresh;
  before.build(mesh, x0);
  fresh.build(mesh, x1);
  const double moved = before.maxDisplacement(x1);
  ASSERT_GT(moved, min_moved);
  ASSERT_LE(moved, before.margin());
  EXPECT_EQ(fresh.maxDisplacement(x1), 0.0);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> where(-4.0, 16.0);
  int inside = 0;
  auto check = [&](const Eigen::Vector3d& p) {
    const int a = before.locate(mesh, x1, p, moved);
    EXPECT_EQ(a, before.locate(mesh, x1, p));  // bound: the margin
    EXPECT_EQ(a, fresh.locate(mesh, x1, p, 0.0));
    EXPECT_EQ(a, fresh.locate(mesh, x1, p, 1.0));
    inside += a >= 0;
    return a;
  };
  for (int q = 0; q < 4000; ++q) check(Eigen::Vector3d(where(rng), where(rng), where(rng)));
  EXPECT_GT(inside, 500);
  for (int t = 0; t < mesh.numTets(); ++t) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero(), face = centroid;
    for (int k = 0; k < 4; ++k) centroid += 0.25 * x1.row(mesh.T(t, k)).transpose();
    // On a face, up to rounding: in two tets, one, or (the test has no tolerance) none.
    for (int k = 0; k < 3; ++k) face += x1.row(mesh.T(t, k)).transpose() / 3.0;
    const int a = check(centroid);
    EXPECT_GE(a, 0);
    EXPECT_LE(a, t);  // the lowest-numbered tet that holds it
    check(face);
  }
}

TEST(TetLocator, SameAnswerWhereverTheGridWasBuilt) {
  cutting::TetMesh mesh = testing::boxTetMesh(8, 7, 6, 1.5);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> jitter(-0.2, 0.2);
  sim::NodeVectors x0 = mesh.X;
  for (int i = 0; i < x0.rows(); ++i)
    for (int k = 0; k < 3; ++k) x0(i, k) += jitter(rng);
  // A smooth deformation of up to ~0.8 mm.
  sim::NodeVectors x1 = x0;
  for (int i = 0; i < x1.rows(); ++i) {
    x1(i, 0) += 0.8 * std::sin(0.3 * x0(i, 1));
    x1(i, 2) += 0.5 * std::cos(0.2 * x0(i, 0));
  }
  expectSameAnswers(mesh, x0, x1, 0.3);
}

// The same with the nodes moved by up to the margin (the pass maps its last sweep rows through
// a locator built up to that far from where the tissue is, instead of rebuilding it).
TEST(TetLocator, SameAnswerAfterMovesUpToTheMargin) {
  cutting::TetMesh mesh = testing::boxTetMesh(8, 7, 6, 1.5);
  for (const double amplitude : {1.5, 2.5}) {
    SCOPED_TRACE(amplitude);
    sim::NodeVectors x1 = mesh.X;
    for (int i = 0; i < x1.rows(); ++i) {
      x1(i, 0) += amplitude * std::sin(0.25 * mesh.X(i, 1));
      x1(i, 1) += 0.5 * amplitude * std::cos(0.2 * mesh.X(i, 2));
    }
    expectSameAnswers(mesh, mesh.X, x1, 0.9 * amplitude);
  }
}

}  // namespace
}  // namespace hysim::engine
