// Tissue update after 3D cuts: positive masses that keep the ten moments, remapped state.
#include <gtest/gtest.h>

#include "box_mesh.hpp"
#include "hysim/cutting/cut3d.hpp"
#include "hysim/sim/tissue_update3d.hpp"

namespace hysim::sim {
namespace {

using Vec3 = Eigen::Vector3d;

void checkMasses(const cutting::TetMesh& before, const cutting::TetMesh& after, const cutting::TopologyChange& change,
                 const Eigen::VectorXd& m0) {
  const Eigen::VectorXd density = Eigen::VectorXd::Constant(after.numTets(), 1e-3);
  MassUpdate3DReport report;
  auto m1 = updateMasses3D(before, m0, after, change, density, {}, &report);
  ASSERT_TRUE(m1.ok()) << m1.error();
  for (int t = 0; t < after.numTets(); ++t)
    for (int k = 0; k < 4; ++k) EXPECT_GT((*m1)[after.T(t, k)], 0.0);
  const Vec3 c(1, 1, 1);
  const auto p0 = massMoments3D(before.X, m0, c, 2.0), p1 = massMoments3D(after.X, *m1, c, 2.0);
  EXPECT_LT((p0 - p1).cwiseAbs().maxCoeff(), 1e-9 * p0.cwiseAbs().maxCoeff()) << (p0 - p1).transpose();
  EXPECT_LT(report.moment_residual, 1e-9);
  EXPECT_GT(report.unknowns, 0);
}

TEST(TissueUpdate3D, MassesKeepMomentsForEveryMethod) {
  const auto box = testing::boxTetMesh(4, 4, 4, 0.5);
  const Eigen::VectorXd m0 = lumpedMasses3D(box, Eigen::VectorXd::Constant(box.numTets(), 1e-3));
  for (auto method : {cutting::CutMethod::Hybrid, cutting::CutMethod::Standard, cutting::CutMethod::Snap}) {
    cutting::Cut3DOptions o;
    o.method = method;
    auto r = cutting::cut3d(box, *cutting::CutSurface::plane(Vec3(1.05, 0.93, 1.11), Vec3(0.3, 0.2, 1)), o);
    ASSERT_TRUE(r.ok());
    checkMasses(box, r->mesh, r->change, m0);
  }
}

TEST(TissueUpdate3D, RepeatedCutsKeepMoments) {
  auto mesh = testing::boxTetMesh(4, 4, 4, 0.5);
  Eigen::VectorXd m = lumpedMasses3D(mesh, Eigen::VectorXd::Constant(mesh.numTets(), 1e-3));
  const double total = m.sum();
  for (int i = 0; i < 4; ++i) {
    auto r = cutting::cut3d(mesh, *cutting::CutSurface::plane(Vec3(0, 0, 0.3 + 0.45 * i), Vec3(0.1, 0, 1)));
    ASSERT_TRUE(r.ok());
    MassUpdate3DReport rep;
    auto m1 = updateMasses3D(mesh, m, r->mesh, r->change, Eigen::VectorXd::Constant(r->mesh.numTets(), 1e-3), {},
                             &rep);
    ASSERT_TRUE(m1.ok());
    EXPECT_LT(rep.moment_residual, 1e-9) << "cut " << i << " unknowns " << rep.unknowns << " clamped " << rep.clamped;
    EXPECT_GT(m1->minCoeff(), 0.0);
    m = *m1;
    mesh = r->mesh;
  }
  EXPECT_NEAR(m.sum(), total, 1e-12 * total);
}

TEST(TissueUpdate3D, StateRemapInterpolatesNewNodes) {
  const auto box = testing::boxTetMesh(3, 3, 3, 1.0);
  cutting::Cut3DOptions o;
  o.method = cutting::CutMethod::Standard;
  auto r = cutting::cut3d(box, *cutting::CutSurface::plane(Vec3(1.5, 1.5, 1.4), Vec3(0.2, 0.1, 1)), o);
  ASSERT_TRUE(r.ok());
  State s;
  s.x = box.X;
  s.v = NodeVectors(box.numNodes(), 3);
  for (int i = 0; i < box.numNodes(); ++i) s.v.row(i) << 2.0 * box.X(i, 0), -box.X(i, 1), 0.5;  // affine field
  const State s1 = remapState3D(s, r->change);
  ASSERT_EQ(s1.x.rows(), r->mesh.numNodes());
  for (int i = 0; i < r->mesh.numNodes(); ++i) {
    EXPECT_LT((s1.x.row(i) - r->mesh.X.row(i)).norm(), 1e-12);
    const Eigen::RowVector3d v(2.0 * r->mesh.X(i, 0), -r->mesh.X(i, 1), 0.5);
    EXPECT_LT((s1.v.row(i) - v).norm(), 1e-12);
  }
}

TEST(TissueUpdate3D, ModelUpdateKeepsMassAndAnchors) {
  const auto box = testing::boxTetMesh(4, 4, 4, 2.0);
  Material mat;
  mat.label = 1;
  auto model = buildModel(box, {mat}, {0, 1, 2}, {});
  ASSERT_TRUE(model.ok()) << model.error();
  auto r = cutting::cut3d(box, *cutting::CutSurface::plane(Vec3(4, 4, 3.3), Vec3(0.1, 0.2, 1)));
  ASSERT_TRUE(r.ok());
  MassUpdate3DReport report;
  auto m1 = updateModel3D(*model, box, r->mesh, r->change, {}, &report);
  ASSERT_TRUE(m1.ok()) << m1.error();
  EXPECT_EQ(m1->num_nodes, r->mesh.numNodes());
  EXPECT_NEAR(m1->mass.sum(), model->mass.sum(), 1e-9 * model->mass.sum());
  EXPECT_TRUE(m1->fixed[0] && m1->fixed[1] && m1->fixed[2]);
  const auto comps = cutting::tetComponents(r->mesh, {0, 1, 2});
  EXPECT_EQ(comps.count, 2);
  EXPECT_EQ(std::count(comps.free.begin(), comps.free.end(), true), 1);
}

}  // namespace
}  // namespace hysim::sim
