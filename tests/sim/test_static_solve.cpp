// The spring network's static solve (R1 of the accuracy study).
#include <gtest/gtest.h>

#include "box_mesh.hpp"
#include "hysim/sim/static_solve.hpp"

namespace hysim::sim {
namespace {

using testing::boxTetMesh;

Material softTissue() {
  Material m;
  m.label = 1;
  m.young_modulus_pa = 60e3;
  m.density_g_mm3 = 1.05e-3;
  return m;
}

std::vector<int> nodesAtZ0(const cutting::TetMesh& mesh) {
  std::vector<int> fixed;
  for (int i = 0; i < mesh.numNodes(); ++i)
    if (mesh.X(i, 2) == 0.0) fixed.push_back(i);
  return fixed;
}

TEST(StaticSolve, NetForceOnFreeNodesVanishes) {
  const cutting::TetMesh mesh = boxTetMesh(3, 3, 6, 2.0);
  ModelOptions o;
  o.gravity = Eigen::Vector3d(9810.0, 0, 0);  // sideways: the column bends
  auto model = buildModel(mesh, {softTissue()}, nodesAtZ0(mesh), o);
  ASSERT_TRUE(model.ok()) << model.error();
  State s = makeState(*model, mesh);
  const StaticSolveResult r = solveStatic(*model, s);
  EXPECT_TRUE(r.converged);
  EXPECT_LE(r.iterations, 10);  // Newton: a handful of iterations
  const NodeVectors f = staticForces(*model, s.x, nullptr);
  double load = 0.0;
  for (int i = 0; i < model->num_nodes; ++i) load += model->mass[i] * 9810.0;
  for (int i = 0; i < model->num_nodes; ++i) {
    if (!model->fixed[i]) {
      EXPECT_LT(f.row(i).norm(), 1e-8 * load) << "node " << i;
    }
  }
  // The springs pull the anchors along gravity with the free body's whole weight.
  Eigen::RowVector3d reaction = Eigen::RowVector3d::Zero();
  for (int i = 0; i < model->num_nodes; ++i)
    if (model->fixed[i]) reaction += f.row(i);
  double weight = 0.0;
  for (int i = 0; i < model->num_nodes; ++i)
    if (!model->fixed[i]) weight += model->mass[i] * 9810.0;
  EXPECT_NEAR(reaction.x(), weight, 1e-6 * weight);
  EXPECT_GT(s.x.col(0).maxCoeff() - mesh.X.col(0).maxCoeff(), 0.0);  // it bent along gravity
}

TEST(StaticSolve, ImplicitEulerRunToRestReachesTheSameEquilibrium) {
  const cutting::TetMesh mesh = boxTetMesh(2, 2, 5, 2.0);
  ModelOptions o;
  o.gravity = Eigen::Vector3d(0, 9810.0, 0);
  o.integrator = Integrator::ImplicitEuler;
  o.implicit_iterations = 16;
  o.dt = 5e-3;
  o.drag_per_s = 50.0;
  auto model = buildModel(mesh, {softTissue()}, nodesAtZ0(mesh), o);
  ASSERT_TRUE(model.ok()) << model.error();
  State stat = makeState(*model, mesh);
  ASSERT_TRUE(solveStatic(*model, stat).converged);
  State dyn = makeState(*model, mesh);
  for (int k = 0; k < 2000; ++k) step(*model, dyn, {});
  const double sag = (stat.x - mesh.X).norm();
  ASSERT_GT(sag, 0.0);
  EXPECT_LT((dyn.x - stat.x).norm(), 1e-6 * sag);
}

TEST(StaticSolve, HeldNodesMovedFirstGiveAnIndentationReaction) {
  // A column pressed 0.4 mm at its top: the reaction grows with the depth, and compressed
  // springs (an indefinite Hessian) do not stop the solve.
  const cutting::TetMesh mesh = boxTetMesh(2, 2, 4, 2.0);
  std::vector<int> fixed = nodesAtZ0(mesh), top;
  const double zmax = mesh.X.col(2).maxCoeff();
  for (int i = 0; i < mesh.numNodes(); ++i)
    if (mesh.X(i, 2) == zmax) top.push_back(i);
  fixed.insert(fixed.end(), top.begin(), top.end());
  ModelOptions o;
  o.gravity.setZero();
  auto model = buildModel(mesh, {softTissue()}, fixed, o);
  ASSERT_TRUE(model.ok());
  State s = makeState(*model, mesh);
  double previous = 0.0;
  for (double depth : {0.1, 0.2, 0.4}) {
    for (int i : top) s.x(i, 2) = zmax - depth;
    ASSERT_TRUE(solveStatic(*model, s).converged) << depth;
    const NodeVectors f = staticForces(*model, s.x, nullptr);
    double push = 0.0;
    for (int i : top) push += f(i, 2);  // the springs push the held nodes back up
    EXPECT_GT(push, previous) << depth;
    previous = push;
  }
}

}  // namespace
}  // namespace hysim::sim
