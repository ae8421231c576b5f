// Tissue update after 2D cuts: mass moments up to second order preserved to round-off,
// masses positive, Van Gelder springs.
#include <gtest/gtest.h>

#include "../cutting/cut2d_meshes.hpp"
#include "hysim/cutting/cut2d.hpp"
#include "hysim/cutting/mesh_io.hpp"
#include "hysim/sim/tissue_update2d.hpp"

namespace hysim::sim {
namespace {

using Eigen::Vector2d;

TEST(TissueUpdate2D, VanGelderSpringsOnARightTriangle) {
  cutting::TriMesh m;
  m.X.setZero(3, 3);
  m.X.row(1) << 2, 0, 0;
  m.X.row(2) << 0, 2, 0;
  m.F.resize(1, 3);
  m.F.row(0) << 0, 1, 2;
  const Tissue2D t = buildTissue2D(m, 10.0, 1.0);
  ASSERT_EQ(t.springs.rows(), 3);
  for (int s = 0; s < 3; ++s) {
    const double len = t.rest_length(s);
    EXPECT_NEAR(t.stiffness(s), 10.0 * 2.0 / (len * len), 1e-12);  // area 2
  }
  EXPECT_NEAR(t.mass.sum(), 2.0, 1e-12);
}

TEST(TissueUpdate2D, MomentsPreservedAndMassesPositiveAfterEveryMethod) {
  std::vector<cutting::TriMesh> meshes = {testing::gridTriMesh(6, 5, 2.0)};
  for (const char* name : {"table1_mesh1.msh", "table1_mesh2.msh"}) {
    auto m = cutting::readTriMesh(std::string(HYSIM_TEST_DATA_DIR) + "/cutting/" + name);
    ASSERT_TRUE(m.ok()) << m.error();
    meshes.push_back(*m);
  }
  int checked = 0;
  for (const auto& m : meshes) {
    const Tissue2D t0 = buildTissue2D(m, 60e3, 1.05e-3);
    const Vector2d lo(m.X.col(0).minCoeff(), m.X.col(1).minCoeff()), hi(m.X.col(0).maxCoeff(), m.X.col(1).maxCoeff());
    for (int k = 0; k < 6; ++k) {
      const double f = 0.2 + 0.12 * k;
      const Vector2d a(lo.x() - 1, lo.y() + f * (hi.y() - lo.y())), b(hi.x() + 1, hi.y() - 0.8 * f * (hi.y() - lo.y()));
      for (auto cm : {cutting::CutMethod::Hybrid, cutting::CutMethod::Standard, cutting::CutMethod::Snap}) {
        cutting::Cut2DOptions o;
        o.method = cm;
        auto r = cutting::cut2d(m, a, b, o);
        ASSERT_TRUE(r.ok()) << r.error();
        MassUpdateReport rep;
        auto t1 = updateTissue2D(m, t0, r->mesh, r->change, 60e3, 1.05e-3, {}, &rep);
        ASSERT_TRUE(t1.ok()) << t1.error();
        ASSERT_EQ(t1->mass.size(), r->mesh.numNodes());
        // Moments about the same centre and scale, before and after.
        const Vector2d c = 0.5 * (lo + hi);
        const double s = (hi - lo).norm();
        const auto p0 = massMoments2D(m, t0.mass, c, s), p1 = massMoments2D(r->mesh, t1->mass, c, s);
        EXPECT_LT((p1 - p0).cwiseAbs().maxCoeff(), 1e-12 * p0.cwiseAbs().maxCoeff()) << cutting::cutMethodName(cm);
        EXPECT_LT(rep.moment_residual, 1e-12);
        EXPECT_GT(t1->mass.minCoeff(), 0.0);
        EXPECT_EQ(t1->springs.rows(), t1->stiffness.size());
        EXPECT_GT(t1->stiffness.minCoeff(), 0.0);
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 54);
}

TEST(TissueUpdate2D, NegativeUnconstrainedMassesAreHeldAtTheFloor) {
  // A prior far from the moments (masses of a different mesh) forces large corrections;
  // the active set keeps every mass at or above its floor.
  const cutting::TriMesh m = testing::gridTriMesh(4, 4, 1.0);
  Tissue2D t0 = buildTissue2D(m, 1.0, 1.0);
  cutting::Cut2DOptions o;
  o.method = cutting::CutMethod::Standard;
  auto r = cutting::cut2d(m, Vector2d(-1, 2.5), Vector2d(5, 2.5), o);
  ASSERT_TRUE(r.ok());
  // Skew the previous masses strongly towards one corner.
  for (int i = 0; i < m.numNodes(); ++i) t0.mass(i) = 1e-3 + (m.X(i, 0) + m.X(i, 1) > 7 ? 5.0 : 0.0);
  MassUpdateOptions mo;
  mo.floor_fraction = 0.05;
  MassUpdateReport rep;
  auto mass = updateMasses2D(m, t0.mass, r->mesh, r->change, 1.0, mo, &rep);
  ASSERT_TRUE(mass.ok());
  EXPECT_GT(mass->minCoeff(), 0.0);
}

TEST(TissueUpdate2D, MismatchedInputIsAnError) {
  const cutting::TriMesh m = testing::gridTriMesh(2, 2, 1.0);
  cutting::TopologyChange tc;
  EXPECT_FALSE(updateMasses2D(m, Eigen::VectorXd::Ones(3), m, tc, 1.0).ok());
  EXPECT_FALSE(updateMasses2D(m, Eigen::VectorXd::Ones(m.numNodes()), m, tc, 1.0).ok());
}

}  // namespace
}  // namespace hysim::sim
