#include "hysim/engine/tet_locator.hpp"

#include <gtest/gtest.h>

#include <Eigen/LU>

#include <random>

#include "box_mesh.hpp"

namespace hysim::engine {
namespace {

// Whether p lies in tet t at positions x (closed, as TetLocator's test up to rounding).
bool holds(const cutting::TetMesh& mesh, const sim::NodeVectors& x, int t, const Eigen::Vector3d& p) {
  const Eigen::Vector3d a = x.row(mesh.T(t, 0)).transpose();
  Eigen::Matrix3d m;
  for (int k = 0; k < 3; ++k) m.col(k) = x.row(mesh.T(t, k + 1)).transpose() - a;
  const Eigen::Vector3d w = m.inverse() * (p - a);
  return w.minCoeff() >= 0.0 && w.sum() <= 1.0;
}

// A box mesh whose nodes moved after the build, plus copies of some tets appended at the end
// (overlapping tets, as a folded deformed mesh has): the lowest-numbered holding tet is the
// answer, with or without a `known` tet, whichever tet that is.
TEST(TetLocator, KnownTetGivesTheSameAnswer) {
  cutting::TetMesh mesh = hysim::testing::boxTetMesh(5, 4, 3, 1.0);
  const int base = mesh.numTets();
  const int copies = 20;
  mesh.T.conservativeResize(base + copies, 4);
  mesh.material.conservativeResize(base + copies);
  for (int c = 0; c < copies; ++c) {
    mesh.T.row(base + c) = mesh.T.row(7 * c % base);
    mesh.material[base + c] = 1;
  }
  sim::NodeVectors x = mesh.X;
  TetLocator locator;
  locator.build(mesh, x);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> shift(-0.1, 0.1), coord(-0.5, 5.5);
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    for (int c = 0; c < 3; ++c) x(i, c) += shift(rng);
  const double moved = locator.maxDisplacement(x);
  int checked = 0, overlapping = 0;
  for (int q = 0; q < 3000; ++q) {
    const Eigen::Vector3d p(coord(rng), coord(rng) * 0.8, coord(rng) * 0.6);
    const int plain = locator.locate(mesh, x, p, moved);
    int lowest = -1;
    std::vector<int> holding;
    for (int t = 0; t < mesh.numTets(); ++t)
      if (holds(mesh, x, t, p)) holding.push_back(t);
    if (!holding.empty()) lowest = holding.front();
    EXPECT_EQ(plain, lowest) << "query " << q;
    overlapping += holding.size() > 1 ? 1 : 0;
    for (int known : holding) {
      EXPECT_EQ(locator.locate(mesh, x, p, moved, known), plain) << "query " << q << " known " << known;
      ++checked;
    }
    // A `known` tet that does not hold p changes nothing either.
    const int wrong = (plain + 1 + q % 50) % mesh.numTets();
    if (!holds(mesh, x, wrong, p)) {
      EXPECT_EQ(locator.locate(mesh, x, p, moved, wrong), plain);
    }
  }
  EXPECT_GT(checked, 1000);
  EXPECT_GT(overlapping, 10);
}

}  // namespace
}  // namespace hysim::engine
