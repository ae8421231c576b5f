// Tissue model: Van Gelder springs, lumped masses, stability estimate, integrators.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#define HYSIM_DEFINE_ALLOC_HOOKS  // this file defines the malloc hooks for the executable
#include "alloc_counter.hpp"
#include "box_mesh.hpp"
#include "hysim/sim/model.hpp"

namespace hysim::sim {
namespace {

using cutting::TetMesh;

TetMesh regularTet(double a) {
  TetMesh m;
  m.X.resize(4, 3);
  m.X << 0, 0, 0, a, 0, 0, a / 2, a * std::sqrt(3.0) / 2, 0, a / 2, a * std::sqrt(3.0) / 6, a * std::sqrt(2.0 / 3.0);
  m.T.resize(1, 4);
  m.T << 0, 1, 2, 3;
  m.material = cutting::Labels::Constant(1, 1);
  return m;
}

Material tissue(double e_pa = 60e3, double rho = 1.05e-3, double beta = 0.0) {
  Material m;
  m.name = "tissue";
  m.label = 1;
  m.young_modulus_pa = e_pa;
  m.density_g_mm3 = rho;
  m.stiffness_damping_s = beta;
  return m;
}

ModelOptions noGravity(double dt = 1e-3) {
  ModelOptions o;
  o.dt = dt;
  o.gravity.setZero();
  return o;
}

TEST(VanGelder, SingleTetStiffnessAndLumpedMass) {
  const double a = 3.0, e = 60e3, rho = 1.05e-3;
  const TetMesh mesh = regularTet(a);
  const double volume = a * a * a / (6.0 * std::sqrt(2.0));
  auto model = buildModel(mesh, {tissue(e, rho)}, {}, noGravity());
  ASSERT_TRUE(model.ok()) << model.error();
  ASSERT_EQ(model->springs.rows(), 6);
  for (int s = 0; s < 6; ++s) {
    EXPECT_NEAR(model->rest_length[s], a, 1e-12);
    // k = E * sum(incident volumes) / |e|^2, one incident tet here.
    EXPECT_NEAR(model->stiffness[s], e * volume / (a * a), 1e-9 * e);
  }
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(model->mass[i], rho * volume / 4.0, 1e-15);
}

TEST(VanGelder, SharedEdgeSumsIncidentTetsOfEachMaterial) {
  // Two tets sharing face (0,1,2): edges of that face get both tets' E*V.
  TetMesh m;
  m.X.resize(5, 3);
  m.X << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1;
  m.T.resize(2, 4);
  m.T << 0, 1, 2, 3, 0, 2, 1, 4;
  m.material.resize(2);
  m.material << 1, 2;
  Material soft = tissue(30e3), stiff = tissue(150e3);
  stiff.label = 2;
  auto model = buildModel(m, {soft, stiff}, {}, noGravity());
  ASSERT_TRUE(model.ok()) << model.error();
  EXPECT_EQ(model->springs.rows(), 9);
  const double v = 1.0 / 6.0;
  for (int s = 0; s < model->springs.rows(); ++s) {
    const int i = model->springs(s, 0), j = model->springs(s, 1);
    const double l2 = (m.X.row(i) - m.X.row(j)).squaredNorm();
    const bool shared = i <= 2 && j <= 2;
    const double expected = shared ? (30e3 + 150e3) * v / l2 : (j == 3 ? 30e3 : 150e3) * v / l2;
    EXPECT_NEAR(model->stiffness[s], expected, 1e-9 * expected) << "spring " << i << "-" << j;
  }
}

TEST(VanGelder, MissingMaterialIsAnError) {
  TetMesh m = regularTet(1.0);
  m.material[0] = 7;
  auto model = buildModel(m, {tissue()}, {}, noGravity());
  ASSERT_FALSE(model.ok());
  EXPECT_NE(model.error().find("label 7"), std::string::npos) << model.error();
}

// One free node on three fixed ones (regular tet): the highest frequency is analytic,
// omega^2 = 2k/m (the stiffness along the tet's height is 3 k cos^2 = 2k).
TEST(Stability, CriticalStepMatchesAnalyticLimit) {
  const TetMesh mesh = regularTet(3.0);
  auto model = buildModel(mesh, {tissue()}, {0, 1, 2}, noGravity());
  ASSERT_TRUE(model.ok());
  const double k = model->stiffness[0], mass = model->mass[3];
  EXPECT_NEAR(model->omega_max, std::sqrt(2.0 * k / mass), 1e-3 * model->omega_max);
  EXPECT_NEAR(model->critical_dt, 2.0 / std::sqrt(2.0 * k / mass), 1e-3 * model->critical_dt);
}

double runEnergy(double dt_factor, int steps, int* warnings, double* max_energy, double* last_energy) {
  const TetMesh mesh = regularTet(3.0);
  auto probe = buildModel(mesh, {tissue()}, {0, 1, 2}, noGravity());
  ModelOptions o = noGravity(dt_factor * probe->critical_dt);
  o.substeps = 1;
  auto model = buildModel(mesh, {tissue()}, {0, 1, 2}, o);
  State s = makeState(*model, mesh);
  s.x(3, 2) += 0.01;  // small: the linear analysis below applies
  const double e0 = springEnergy(*model, s);
  *max_energy = e0;
  for (int i = 0; i < steps; ++i) {
    step(*model, s, {});
    *last_energy = kineticEnergy(*model, s) + springEnergy(*model, s);
    *max_energy = std::max(*max_energy, *last_energy);
  }
  *warnings = s.warnings;
  return e0;
}

TEST(Stability, JustBelowLimitStaysBounded) {
  int warnings = 0;
  double max_e = 0, last_e = 0;
  const double e0 = runEnergy(0.8, 20000, &warnings, &max_e, &last_e);
  EXPECT_EQ(warnings, 0);
  // Symplectic Euler conserves a modified energy y^2 + v^2 - 2a y v (y = omega x,
  // a = omega h / 2): the true energy stays within a factor 1/(1 - a) = 5 of its start at
  // 0.8 of the limit, however long it runs.
  EXPECT_LT(max_e, 5.0 * 1.05 * e0);
}

TEST(Stability, JustAboveLimitDivergesWithWarningNotCrash) {
  int warnings = 0;
  double max_e = 0, last_e = 0;
  runEnergy(1.05, 20000, &warnings, &max_e, &last_e);
  EXPECT_EQ(warnings, 1);  // counted once, then the state is frozen
  EXPECT_TRUE(std::isfinite(last_e));
}

TEST(SymplecticEuler, UndampedEnergyBoundedOnABlock) {
  const TetMesh mesh = testing::boxTetMesh(4, 3, 3, 2.0);
  std::vector<int> fixed;
  for (int i = 0; i < mesh.numNodes(); ++i)
    if (mesh.X(i, 0) == 0.0) fixed.push_back(i);
  auto model = buildModel(mesh, {tissue()}, fixed, noGravity());
  ASSERT_TRUE(model.ok());
  EXPECT_GT(model->substeps, 1);  // the automatic substep respects the stability limit
  State s = makeState(*model, mesh);
  for (int i = 0; i < mesh.numNodes(); ++i)
    if (!model->fixed[i]) s.v.row(i) << std::sin(i * 1.7) * 20.0, std::cos(i * 0.9) * 20.0, std::sin(i * 0.3) * 20.0;
  const double e0 = kineticEnergy(*model, s);
  // Bounded (within the modified-energy factor of the automatic substep, see above) and no
  // drift: the mean energy of the last fifth of the run is that of the first fifth.
  const int steps = 5000;
  double mean_first = 0, mean_last = 0, hi = 0;
  for (int i = 0; i < steps; ++i) {
    step(*model, s, {});
    const double e = kineticEnergy(*model, s) + springEnergy(*model, s);
    hi = std::max(hi, e);
    if (i < steps / 5) mean_first += e / (steps / 5);
    if (i >= steps - steps / 5) mean_last += e / (steps / 5);
  }
  EXPECT_EQ(s.warnings, 0);
  EXPECT_LT(hi, e0 / (1.0 - model->options.stability_safety));
  EXPECT_NEAR(mean_last, mean_first, 0.02 * mean_first);
}

// Gravity sag of a cantilever block: both integrators reach the same static equilibrium,
// the implicit one also with a step far above the explicit stability limit.
TEST(Integrators, SameStaticEquilibrium) {
  const TetMesh mesh = testing::boxTetMesh(6, 2, 2, 2.0);
  std::vector<int> fixed;
  for (int i = 0; i < mesh.numNodes(); ++i)
    if (mesh.X(i, 0) == 0.0) fixed.push_back(i);
  ModelOptions o;
  o.dt = 1e-3;
  o.drag_per_s = 200.0;
  o.gravity = {0, 0, -9810.0 * 20};  // make the sag visible
  auto explicit_model = buildModel(mesh, {tissue(20e3)}, fixed, o);
  o.integrator = Integrator::ImplicitEuler;
  o.dt = 5e-3;
  o.implicit_iterations = 20;
  auto implicit_model = buildModel(mesh, {tissue(20e3)}, fixed, o);
  ASSERT_TRUE(explicit_model.ok() && implicit_model.ok());
  EXPECT_GT(o.dt, 5.0 * implicit_model->critical_dt);
  State se = makeState(*explicit_model, mesh), si = makeState(*implicit_model, mesh);
  for (int i = 0; i < 1500; ++i) step(*explicit_model, se, {});
  for (int i = 0; i < 300; ++i) step(*implicit_model, si, {});
  EXPECT_EQ(se.warnings, 0);
  EXPECT_EQ(si.warnings, 0);
  int tip = 0;
  for (int i = 0; i < mesh.numNodes(); ++i)
    if (mesh.X(i, 0) > mesh.X(tip, 0)) tip = i;
  const double sag_e = mesh.X(tip, 2) - se.x(tip, 2), sag_i = mesh.X(tip, 2) - si.x(tip, 2);
  EXPECT_GT(sag_e, 0.05);
  EXPECT_NEAR(sag_i, sag_e, 0.02 * sag_e);
  EXPECT_LT(se.v.norm(), 1.0);  // at rest
  EXPECT_LT(si.v.norm(), 1.0);
}

// A cap on the automatic substeps is met by adding mass where the frequency is highest,
// and the model stays stable.
TEST(Stability, MassScalingRespectsTheSubstepCap) {
  const TetMesh mesh = testing::boxTetMesh(4, 3, 3, 1.0);
  ModelOptions o = noGravity();
  auto free_model = buildModel(mesh, {tissue(150e3)}, {0, 1, 2, 3}, o);
  ASSERT_TRUE(free_model.ok());
  ASSERT_GT(free_model->substeps, 3);
  o.max_substeps = 3;
  auto capped = buildModel(mesh, {tissue(150e3)}, {0, 1, 2, 3}, o);
  ASSERT_TRUE(capped.ok());
  EXPECT_LE(capped->substeps, 3);
  EXPECT_GT(capped->added_mass, 0.0);
  EXPECT_LE(capped->substep, 0.85 * capped->critical_dt * 1.0001);
  State s = makeState(*capped, mesh);
  for (int i = 0; i < mesh.numNodes(); ++i) s.v(i, 0) = 50.0 * std::sin(0.7 * i);
  for (int i = 0; i < 1000; ++i) step(*capped, s, {});
  EXPECT_EQ(s.warnings, 0);
}

TEST(Step, AllocatesNothing) {
  const TetMesh mesh = testing::boxTetMesh(4, 4, 4, 2.0);
  for (Integrator integrator : {Integrator::SymplecticEuler, Integrator::ImplicitEuler, Integrator::Xpbd}) {
    ModelOptions o;
    o.integrator = integrator;
    o.xpbd_iterations = 2;
    auto model = buildModel(mesh, {tissue()}, {0, 1, 2, 3, 4}, o);
    ASSERT_TRUE(model.ok());
    State s = makeState(*model, mesh);
    NodeVectors external = NodeVectors::Constant(mesh.numNodes(), 3, 1.0);
    StepInput in;
    in.external_force = &external;
    step(*model, s, in);  // warm-up
    long count = 0;
    {
      testing::AllocationCounter counter;
      for (int i = 0; i < 10; ++i) step(*model, s, in);
      count = counter.count();
    }
    EXPECT_EQ(count, 0) << "integrator " << static_cast<int>(integrator);
  }
}

// The AVX2 spring loop and the baseline one must agree bit for bit, or a scene would hash
// differently on different CPUs.
// Both meshes, with and without an external force; the spring counts cover the AVX2 loop's
// scalar tail (a count that is not a multiple of 4) and a count without one.
TEST(Step, SimdAndBaselineSpringLoopsAreBitIdentical) {
  std::vector<int> tails;
  for (const TetMesh& mesh : {testing::boxTetMesh(5, 4, 3, 2.0), testing::boxTetMesh(3, 2, 2, 2.0)}) {
    for (const bool with_force : {false, true}) {
      ModelOptions o;
      o.drag_per_s = 5.0;
      auto with_simd = buildModel(mesh, {tissue(60e3, 1.05e-3, 1e-4)}, {0, 1, 2, 3}, o);
      o.simd = false;
      auto baseline = buildModel(mesh, {tissue(60e3, 1.05e-3, 1e-4)}, {0, 1, 2, 3}, o);
      ASSERT_TRUE(with_simd.ok() && baseline.ok());
      tails.push_back(with_simd->step_springs.size() % 4);
      State a = makeState(*with_simd, mesh), b = makeState(*baseline, mesh);
      for (int i = 0; i < mesh.numNodes(); ++i) a.v(i, 2) = b.v(i, 2) = 30.0 * std::sin(0.37 * i);
      NodeVectors force = NodeVectors::Zero(mesh.numNodes(), 3);
      for (int i = 0; i < mesh.numNodes(); ++i) force.row(i) << 0.3 * std::cos(1.3 * i), -0.2, 0.1 * std::sin(0.7 * i);
      StepInput in;
      if (with_force) in.external_force = &force;
      for (int i = 0; i < 300; ++i) {
        step(*with_simd, a, in);
        step(*baseline, b, in);
      }
      EXPECT_EQ(stateHash(a), stateHash(b)) << mesh.numNodes() << " nodes, force " << with_force;
      EXPECT_EQ(std::memcmp(a.x.data(), b.x.data(), sizeof(double) * a.x.size()), 0);
      EXPECT_GT(a.v.norm(), 0.0);
    }
  }
  EXPECT_TRUE(std::count(tails.begin(), tails.end(), 0) > 0 && std::count(tails.begin(), tails.end(), 0) < 4)
      << "no mesh without or none with a scalar tail";
}

TEST(Step, LockstepCopiesAreBitIdentical) {
  const TetMesh mesh = testing::boxTetMesh(3, 3, 3, 2.0);
  auto model = buildModel(mesh, {tissue(60e3, 1.05e-3, 1e-4)}, {0, 1, 2, 3}, ModelOptions{});
  State a = makeState(*model, mesh), b = makeState(*model, mesh);
  for (int i = 0; i < 200; ++i) {
    step(*model, a, {});
    step(*model, b, {});
    ASSERT_EQ(stateHash(a), stateHash(b)) << "step " << i;
  }
  EXPECT_EQ(std::memcmp(a.x.data(), b.x.data(), sizeof(double) * a.x.size()), 0);
  b.v(10, 0) += 1e-12;
  EXPECT_NE(stateHash(a), stateHash(b));
}

}  // namespace
}  // namespace hysim::sim
