// The fixed-step loop on the default scene: determinism, contact, a sane run.
#include <gtest/gtest.h>

#define HYSIM_DEFINE_ALLOC_HOOKS  // this file defines the malloc hooks for the executable
#include "alloc_counter.hpp"
#include "hysim/engine/run.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/simulation.hpp"

namespace hysim::engine {
namespace {

// The diagnostic look-around (no cutting): the loop presses on the myoma at 2 s.
Scene defaultScene() {
  auto scene = loadScene(std::string(HYSIM_SOURCE_DIR) + "/scenes/diagnostic.yaml");
  EXPECT_TRUE(scene.ok()) << scene.error();
  return *scene;
}

TEST(Simulation, DefaultSceneIsBigEnoughAndStable) {
  auto sim = Simulation::create(defaultScene());
  ASSERT_TRUE(sim.ok()) << sim.error();
  const auto& mesh = (*sim)->mesh();
  int deformable = 0;  // tets with at least one free node
  for (int t = 0; t < mesh.numTets(); ++t) {
    bool moves = false;
    for (int c = 0; c < 4; ++c) moves |= !(*sim)->model().fixed[mesh.T(t, c)];
    deformable += moves;
  }
  EXPECT_GE(deformable, 10000);
  EXPECT_EQ(deformable, (*sim)->numDeformableTets());
  EXPECT_GT((*sim)->numAnchored(), 0);
  EXPECT_LE((*sim)->model().substep, 0.85 * (*sim)->model().critical_dt * 1.0001);
  for (int i = 0; i < 300; ++i) (*sim)->step();
  EXPECT_EQ((*sim)->state().warnings, 0);
  EXPECT_TRUE((*sim)->state().x.allFinite());
}

TEST(Simulation, SameSceneTwiceGivesTheSameHash) {
  const Scene scene = defaultScene();
  RunOptions options;
  options.steps = 400;
  auto a = Simulation::create(scene);
  auto b = Simulation::create(scene);
  ASSERT_TRUE(a.ok() && b.ok());
  auto ra = run(**a, options);
  auto rb = run(**b, options);
  ASSERT_TRUE(ra.ok() && rb.ok());
  EXPECT_EQ(hashHex(ra->state_hash), hashHex(rb->state_hash));
  EXPECT_NE(ra->state_hash, sim::stateHash(sim::makeState((*a)->model(), (*a)->mesh())));  // it moved
}

TEST(Simulation, LoopPushesTheMyomaAndFeelsIt) {
  // Default path: at 2 s the extended loop presses on the myoma.
  Scene scene = defaultScene();
  auto with = Simulation::create(scene);
  scene.contact.enabled = false;
  auto without = Simulation::create(scene);
  ASSERT_TRUE(with.ok() && without.ok());
  double max_force = 0;
  for (int i = 0; i < 2300; ++i) {
    (*with)->step();
    (*without)->step();
    max_force = std::max(max_force, (*with)->toolForceN().norm());
  }
  EXPECT_GT(max_force, 0.05);  // newtons
  EXPECT_LT(max_force, 20.0);
  const double moved = ((*with)->state().x - (*without)->state().x).rowwise().norm().maxCoeff();
  EXPECT_GT(moved, 0.5);  // mm
  EXPECT_EQ((*with)->state().warnings, 0);
}

// The loop pressing on the myoma (as above): with the spring coupling the tool lags the
// device by about the force over the coupling's stiffness, and the hand feels the tissue's
// reaction as the proxy's balance predicted it (last step's force plus the tissue stiffness
// times the proxy's move); with a rigid coupling the tool is the device.
TEST(Simulation, TheToolFollowsTheDeviceThroughTheCoupling) {
  Scene scene = defaultScene();
  auto spring = Simulation::create(scene);
  scene.coupling.mode = CouplingSettings::Mode::Rigid;
  auto rigid = Simulation::create(scene);
  ASSERT_TRUE(spring.ok() && rigid.ok());
  Simulation& s = **spring;
  const double k = s.couplingGains().stiffness_n_per_mm;
  double max_offset = 0.0, max_force = 0.0;
  for (int i = 0; i < 2300; ++i) {
    const Eigen::Vector3d f = s.toolForceN(), tip = s.toolPose().tip;
    const Eigen::Matrix3d kt = s.toolStiffnessNPerMm();
    s.step();
    (*rigid)->step();
    max_offset = std::max(max_offset, s.couplingOffsetMm());
    max_force = std::max(max_force, s.toolForceN().norm());
    ASSERT_LT((s.handForceN() - (f + kt * (s.toolPose().tip - tip))).norm(), 1e-9) << "step " << i;
    ASSERT_EQ((*rigid)->toolPose().tip, (*rigid)->deviceState().pose.tip);
  }
  EXPECT_GT(max_force, 0.05);
  EXPECT_GT(max_offset, 0.5 * max_force / k);
  EXPECT_LT(max_offset, 2.0 * max_force / k + 0.01);
  EXPECT_EQ(s.state().warnings, 0);
}

TEST(Simulation, CouplingBeyondTheDeviceIsAnError) {
  Scene scene = defaultScene();
  scene.coupling.stiffness_n_per_mm = 50.0;
  auto stiff = Simulation::create(scene);
  ASSERT_FALSE(stiff.ok());
  EXPECT_NE(stiff.error().find("coupling.stiffness_n_per_mm 50"), std::string::npos) << stiff.error();
  scene.coupling.stiffness_n_per_mm = 1.0;
  scene.coupling.damping_n_s_per_mm = 1e-4;  // below k T / 2 = 5e-4: not passive
  auto loose = Simulation::create(scene);
  ASSERT_FALSE(loose.ok());
  EXPECT_NE(loose.error().find("passivity bound"), std::string::npos) << loose.error();
  scene.coupling.damping_n_s_per_mm = 0.8e-3;  // passive, but below the k T the device asks for
  EXPECT_FALSE(Simulation::create(scene).ok());
  scene.coupling.damping_n_s_per_mm = 1e-3;
  EXPECT_TRUE(Simulation::create(scene).ok());
}

TEST(Simulation, SnapshotCarriesSurfaceCameraAndTool) {
  auto sim = Simulation::create(defaultScene());
  ASSERT_TRUE(sim.ok());
  render::RenderSnapshot snap;
  (*sim)->fillSnapshot(snap);
  EXPECT_EQ(snap.tissue.positions.size(), 3 * snap.tissue.material.size());
  EXPECT_EQ(snap.tissue.triangles.size() % 3, 0u);
  EXPECT_GT(snap.tissue.triangles.size(), 3000u);
  size_t myoma = 0;
  for (auto m : snap.tissue.material) myoma += m == render::SurfaceMaterial::Myoma;
  EXPECT_GT(myoma, 30u);
  EXPECT_TRUE(snap.tool_visible);
  EXPECT_FLOAT_EQ(snap.camera.lens_deg, 30.0f);
  EXPECT_FLOAT_EQ(snap.camera.tip[2], -24.0f);
}

TEST(Simulation, StepAndSnapshotAllocateNothing) {
  auto sim = Simulation::create(defaultScene());
  ASSERT_TRUE(sim.ok());
  render::RenderSnapshot snap;
  (*sim)->step();
  (*sim)->fillSnapshot(snap);  // first fill sizes the buffers
  long count = 0;
  {
    testing::AllocationCounter counter;
    for (int i = 0; i < 20; ++i) (*sim)->step();
    (*sim)->fillSnapshot(snap);
    count = counter.count();
  }
  EXPECT_EQ(count, 0);
}

TEST(Surface, MissingOrBadToolFileIsAnError) {
  auto missing = loadSurface("/nonexistent/tool.stl", render::SurfaceMaterial::Tool);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().find("/nonexistent/tool.stl"), std::string::npos);
  auto tool = loadSurface(std::string(HYSIM_SOURCE_DIR) + "/assets/resectoscope.stl", render::SurfaceMaterial::Tool);
  ASSERT_TRUE(tool.ok()) << tool.error();
  EXPECT_GT(tool->triangles.size(), 300u);
}

}  // namespace
}  // namespace hysim::engine
