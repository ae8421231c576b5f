// XPBD integrator: closed-form spring, static equilibrium and convergence against the other
// integrators, energy, determinism, anchors, degenerate elements, the model after a cut.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>

#include "box_mesh.hpp"
#include "hysim/cutting/cut3d.hpp"
#include "hysim/sim/model.hpp"
#include "hysim/sim/tissue_update3d.hpp"

namespace hysim::sim {
namespace {

using cutting::TetMesh;

Material tissue(double e_pa = 60e3, double beta = 0.0) {
  Material m;
  m.name = "tissue";
  m.label = 1;
  m.young_modulus_pa = e_pa;
  m.stiffness_damping_s = beta;
  return m;
}

ModelOptions xpbd(int substeps = 0) {
  ModelOptions o;
  o.integrator = Integrator::Xpbd;
  o.xpbd_substeps = substeps;
  return o;
}

// Nodes on the plane x = 0 (a cantilever's clamped end).
std::vector<int> clampedEnd(const TetMesh& mesh) {
  std::vector<int> fixed;
  for (int i = 0; i < mesh.numNodes(); ++i)
    if (mesh.X(i, 0) == 0.0) fixed.push_back(i);
  return fixed;
}

// One spring by hand: node 0 anchored at the origin, node 1 (mass m) on the x axis.
struct OneSpring {
  Model model;
  State state;
};
OneSpring oneSpring(double k, double c, double mass, double rest, double stretch, int substeps) {
  OneSpring o;
  Model& m = o.model;
  m.num_nodes = 2;
  m.mass = Eigen::Vector2d(mass, mass);
  m.inv_mass = Eigen::Vector2d(0.0, 1.0 / mass);
  m.fixed = {1, 0};
  m.springs.resize(1, 2);
  m.springs << 0, 1;
  m.rest_length = Eigen::VectorXd::Constant(1, rest);
  m.stiffness = Eigen::VectorXd::Constant(1, k);
  m.damping = Eigen::VectorXd::Constant(1, c);
  m.options = xpbd(substeps);
  m.options.gravity.setZero();
  m.substeps = substeps;
  m.substep = m.options.dt / substeps;
  o.state.x = NodeVectors::Zero(2, 3);
  o.state.x(1, 0) = rest + stretch;
  o.state.v = NodeVectors::Zero(2, 3);
  sizeStepArrays(m, o.state);
  return o;
}

// Largest deviation of the free end from the damped oscillator's closed form over `steps`.
double oscillatorError(double zeta, int substeps, int steps) {
  const double mass = 1e-3, omega = 2.0 * std::numbers::pi * 50.0, k = mass * omega * omega;
  const double c = 2.0 * zeta * std::sqrt(k * mass), amplitude = 0.5, rest = 4.0;
  OneSpring o = oneSpring(k, c, mass, rest, amplitude, substeps);
  const double wd = omega * std::sqrt(1.0 - zeta * zeta);
  double worst = 0.0;
  for (int i = 0; i < steps; ++i) {
    step(o.model, o.state, {});
    const double t = o.state.time;
    const double u = amplitude * std::exp(-zeta * omega * t) * (std::cos(wd * t) + zeta * omega / wd * std::sin(wd * t));
    worst = std::max(worst, std::abs(o.state.x(1, 0) - rest - u));
    EXPECT_EQ(o.state.x.row(0).norm(), 0.0);
  }
  EXPECT_EQ(o.state.warnings, 0);
  return worst / amplitude;
}

// A spring released from a stretch follows x(t) = A e^(-zeta w t)(cos w_d t + ...), undamped
// and damped (c as XPBD's constraint damping). Substeps of h = 1 us: backward Euler's
// numerical damping, about w^2 h t / 2 of A after t, bounds the error; it is first order in
// h, so 4x the substep gives about 4x the error.
TEST(Xpbd, SpringMatchesClosedForm) {
  for (const double zeta : {0.0, 0.1}) {
    const double fine = oscillatorError(zeta, 1000, 100), coarse = oscillatorError(zeta, 250, 100);
    EXPECT_LT(fine, 0.01) << "zeta " << zeta;
    EXPECT_GT(coarse, 3.0 * fine) << "zeta " << zeta;
    EXPECT_LT(coarse, 5.0 * fine) << "zeta " << zeta;
  }
}

// The cantilever of Integrators.SameStaticEquilibrium (gravity x20, drag), run to rest.
struct Cantilever {
  TetMesh mesh = testing::boxTetMesh(6, 2, 2, 2.0);
  std::vector<int> fixed = clampedEnd(mesh);
  ModelOptions options(Integrator integrator) const {
    ModelOptions o;
    o.integrator = integrator;
    o.drag_per_s = 200.0;
    o.gravity = {0, 0, -9810.0 * 20};
    return o;
  }
  State run(const ModelOptions& o, double seconds) const {
    auto model = buildModel(mesh, {tissue(20e3)}, fixed, o);
    EXPECT_TRUE(model.ok());
    State s = makeState(*model, mesh);
    const int steps = static_cast<int>(std::lround(seconds / o.dt));
    for (int i = 0; i < steps; ++i) step(*model, s, {});
    EXPECT_EQ(s.warnings, 0);
    return s;
  }
  // Largest node distance between two states, relative to the largest displacement of `ref`.
  double error(const State& s, const State& ref) const {
    return (s.x - ref.x).rowwise().norm().maxCoeff() / (ref.x - mesh.X).rowwise().norm().maxCoeff();
  }
};

State implicitRest(const Cantilever& c) {
  ModelOptions o = c.options(Integrator::ImplicitEuler);
  o.dt = 5e-3;
  o.implicit_iterations = 40;
  return c.run(o, 3.0);
}

// Static sag against implicit Euler run to rest (many local/global iterations: converged).
// One Gauss-Seidel sweep per substep leaves each spring acting softer by about w k h^2 (w its
// ends' inverse masses), so the rest shape is biased by O(h^2) and each doubling of the
// substeps cuts the bias about 4x; the automatic count
// here is 4 (omega_max h = 1.4), hence the 5% bound (and 0.3% at 16).
TEST(Xpbd, StaticEquilibriumMatchesImplicitEuler) {
  const Cantilever c;
  const State ref = implicitRest(c);
  ModelOptions o = c.options(Integrator::Xpbd);
  auto model = buildModel(c.mesh, {tissue(20e3)}, c.fixed, o);
  ASSERT_TRUE(model.ok());
  ASSERT_EQ(model->substeps, 4);
  const State s = c.run(o, 3.0);
  EXPECT_LT(s.v.norm(), 1.0);  // at rest
  EXPECT_LT(c.error(s, ref), 0.05);
  double previous = 1e300;
  for (int n : {1, 2, 4, 8, 16}) {
    o.xpbd_substeps = n;
    const double e = c.error(c.run(o, 3.0), ref);
    EXPECT_LT(e, previous / 2.5) << n << " substeps";  // about second order
    previous = e;
  }
  EXPECT_LT(previous, 0.003);
}

// Error after a fixed simulated time (20 ms, mid-swing) against a converged reference
// (symplectic Euler with 1 us substeps): it falls monotonically as the substeps grow.
TEST(Xpbd, ErrorFallsAsSubstepsGrow) {
  const Cantilever c;
  ModelOptions r = c.options(Integrator::SymplecticEuler);
  r.substeps = 1000;
  const State ref = c.run(r, 0.02);
  ModelOptions o = c.options(Integrator::Xpbd);
  double previous = 1e300;
  for (int n : {1, 2, 4, 8, 16}) {
    o.xpbd_substeps = n;
    const double err = c.error(c.run(o, 0.02), ref);
    EXPECT_LT(err, previous) << n << " substeps";
    previous = err;
  }
}

// No gravity, no damping: a block released from a 5% stretch. XPBD loses energy (the
// numerical damping of its backward-Euler-like substeps, about proportional to h) but never
// gains any: the total falls from step to step.
double releasedEnergy(int substeps, double* hi, double* rise) {
  const TetMesh mesh = testing::boxTetMesh(4, 3, 3, 2.0);
  ModelOptions o = xpbd(substeps);
  o.gravity.setZero();
  auto model = buildModel(mesh, {tissue()}, clampedEnd(mesh), o);
  EXPECT_TRUE(model.ok());
  State s = makeState(*model, mesh);
  s.x.col(0) *= 1.05;
  const double e0 = springEnergy(*model, s);
  *hi = 0.0;
  double last = 1.0;
  for (int i = 0; i < 10; ++i) {
    step(*model, s, {});
    const double e = (kineticEnergy(*model, s) + springEnergy(*model, s)) / e0;
    *rise = std::max(*rise, e - last);
    last = e;
    *hi = std::max(*hi, e);
  }
  EXPECT_EQ(s.warnings, 0);
  return last;
}

TEST(Xpbd, UndampedEnergyDoesNotGrow) {
  double previous = 0.0;
  for (int n : {0, 16, 64, 1000}) {
    double hi = 0.0, rise = -1.0;
    const double last = releasedEnergy(n, &hi, &rise);
    EXPECT_LE(hi, 1.0) << n << " substeps";
    EXPECT_LT(rise, 1e-6) << n << " substeps";  // it only falls
    EXPECT_GT(last, previous) << n << " substeps";
    previous = last;
  }
}

TEST(Xpbd, SameInputSameHash) {
  const TetMesh mesh = testing::boxTetMesh(3, 3, 3, 2.0);
  ModelOptions o = xpbd();
  o.drag_per_s = 5.0;
  o.xpbd_iterations = 2;
  auto m1 = buildModel(mesh, {tissue(60e3, 1e-4)}, {0, 1, 2, 3}, o);
  auto m2 = buildModel(mesh, {tissue(60e3, 1e-4)}, {0, 1, 2, 3}, o);
  ASSERT_TRUE(m1.ok() && m2.ok());
  NodeVectors force = NodeVectors::Zero(mesh.numNodes(), 3);
  for (int i = 0; i < mesh.numNodes(); ++i) force.row(i) << 0.3 * std::cos(1.3 * i), -0.2, 0.1 * std::sin(0.7 * i);
  StepInput in;
  in.external_force = &force;
  State a = makeState(*m1, mesh), b = makeState(*m2, mesh);
  for (int i = 0; i < 200; ++i) {
    step(*m1, a, in);
    step(*m2, b, in);
    ASSERT_EQ(stateHash(a), stateHash(b)) << "step " << i;
  }
  EXPECT_GT(a.v.norm(), 0.0);
  b.x(20, 1) += 1e-12;
  EXPECT_NE(stateHash(a), stateHash(b));
}

// Anchored nodes keep their rest positions to the bit, whatever pushes on them.
TEST(Xpbd, AnchoredNodesNeverMove) {
  const TetMesh mesh = testing::boxTetMesh(4, 2, 2, 2.0);
  const std::vector<int> fixed = clampedEnd(mesh);
  auto model = buildModel(mesh, {tissue(20e3, 1e-4)}, fixed, xpbd());
  ASSERT_TRUE(model.ok());
  NodeVectors force = NodeVectors::Constant(mesh.numNodes(), 3, 50.0);
  StepInput in;
  in.external_force = &force;
  State s = makeState(*model, mesh);
  for (int i = 0; i < 300; ++i) step(*model, s, in);
  EXPECT_EQ(s.warnings, 0);
  EXPECT_GT((s.x - mesh.X).norm(), 0.1);
  for (int i : fixed) {
    EXPECT_TRUE(s.x.row(i) == mesh.X.row(i)) << "node " << i;
    EXPECT_TRUE(s.v.row(i).isZero(0.0)) << "node " << i;
  }
}

// An inverted tet, a zero-length spring and a tet collapsed to a point: finite, no warning.
TEST(Xpbd, DegenerateElementsStayFinite) {
  TetMesh mesh;
  mesh.X.resize(4, 3);
  mesh.X << 0, 0, 0, 3, 0, 0, 1.5, 2.6, 0, 1.5, 0.87, 2.45;
  mesh.T.resize(1, 4);
  mesh.T << 0, 1, 2, 3;
  mesh.material = cutting::Labels::Constant(1, 1);
  auto model = buildModel(mesh, {tissue(60e3, 1e-4)}, {0, 1, 2}, xpbd());
  ASSERT_TRUE(model.ok()) << model.error();
  auto free_model = buildModel(mesh, {tissue(60e3, 1e-4)}, {}, xpbd());
  ASSERT_TRUE(free_model.ok());
  State inverted = makeState(*model, mesh), zero = makeState(*model, mesh), point = makeState(*free_model, mesh);
  inverted.x(3, 2) = -2.45;
  zero.x.row(3) = zero.x.row(0);
  for (int i = 0; i < 4; ++i) point.x.row(i) = mesh.X.row(0);
  for (int i = 0; i < 500; ++i) {
    step(*model, inverted, {});
    step(*model, zero, {});
    step(*free_model, point, {});
  }
  for (const State* s : {&inverted, &zero, &point}) {
    EXPECT_EQ(s->warnings, 0);
    EXPECT_TRUE(s->x.allFinite() && s->v.allFinite());
  }
  EXPECT_GT((zero.x.row(3) - zero.x.row(0)).norm(), 1.0);  // pushed apart by the other springs
}

// A state whose per-step arrays were not sized for the model freezes with one warning instead
// of writing out of bounds.
TEST(Xpbd, UnsizedStateFreezesWithAWarning) {
  const TetMesh mesh = testing::boxTetMesh(2, 2, 2, 2.0);
  auto model = buildModel(mesh, {tissue()}, {0, 1, 2}, xpbd());
  ASSERT_TRUE(model.ok());
  State s = makeState(*model, mesh);
  s.xpbd_lambda.clear();
  const NodeVectors x0 = s.x;
  for (int i = 0; i < 3; ++i) step(*model, s, {});
  EXPECT_EQ(s.warnings, 1);
  EXPECT_TRUE(s.diverged);
  EXPECT_TRUE(s.x == x0);
}

// Automatic substeps: symplectic Euler's count under the cap, never mass scaling; explicit
// counts and iterations as given; bad values are errors.
TEST(Xpbd, SubstepRuleAndOptions) {
  const TetMesh mesh = testing::boxTetMesh(4, 3, 3, 1.0);
  ModelOptions se;
  auto symplectic = buildModel(mesh, {tissue(150e3)}, {0, 1, 2, 3}, se);
  auto automatic = buildModel(mesh, {tissue(150e3)}, {0, 1, 2, 3}, xpbd());
  ASSERT_TRUE(symplectic.ok() && automatic.ok());
  EXPECT_EQ(automatic->substeps, symplectic->substeps);
  ModelOptions capped = xpbd();
  capped.max_substeps = 3;
  auto c = buildModel(mesh, {tissue(150e3)}, {0, 1, 2, 3}, capped);
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->substeps, 3);
  EXPECT_EQ(c->added_mass, 0.0);
  EXPECT_TRUE(c->mass == automatic->mass);
  auto fixed_count = buildModel(mesh, {tissue(150e3)}, {0, 1, 2, 3}, xpbd(7));
  ASSERT_TRUE(fixed_count.ok());
  EXPECT_EQ(fixed_count->substeps, 7);
  EXPECT_DOUBLE_EQ(fixed_count->substep, fixed_count->options.dt / 7);
  ModelOptions bad = xpbd();
  bad.xpbd_iterations = 0;
  auto refused = buildModel(mesh, {tissue()}, {}, bad);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().find("xpbd_iterations"), std::string::npos) << refused.error();
}

// After a partial cut the incrementally updated model steps with XPBD (no factorisation to
// redo) and sags like a model built from scratch on the cut mesh (not exactly: the update
// keeps the mass moments rather than relumping, so the masses differ a little).
TEST(Xpbd, WorksAfterACutUpdate) {
  const Cantilever c;
  const ModelOptions o = c.options(Integrator::Xpbd);
  auto built = buildModel(c.mesh, {tissue(20e3)}, c.fixed, o);
  ASSERT_TRUE(built.ok());
  cutting::Positions V(4, 3);
  V << 7.1, -1, 1.9, 7.15, 5, 1.95, 7.2, 5, 5, 7.1, -1, 5;
  cutting::Tris F(2, 3);
  F << 0, 1, 2, 0, 2, 3;
  auto r = cutting::cut3d(c.mesh, *cutting::CutSurface::triangles(V, F));
  ASSERT_TRUE(r.ok()) << r.error();
  const TetMesh& after = r->mesh;
  ASSERT_GT(after.numNodes(), c.mesh.numNodes());
  std::vector<std::uint8_t> flags(static_cast<size_t>(after.numNodes()), 0);
  for (int i = 0; i < after.numNodes(); ++i) flags[i] = after.X(i, 0) == 0.0 ? 1 : 0;
  Model updated = *built;
  ASSERT_TRUE(updateModelAfterCut3D(updated, c.mesh, after, r->change, flags, {}).ok());
  EXPECT_EQ(updated.implicit, nullptr);
  EXPECT_EQ(updated.added_mass, 0.0);
  std::vector<int> fixed;
  for (int i = 0; i < after.numNodes(); ++i)
    if (flags[i]) fixed.push_back(i);
  auto rebuilt = buildModel(after, {tissue(20e3)}, fixed, o);
  ASSERT_TRUE(rebuilt.ok());
  State su = makeState(updated, after), sr = makeState(*rebuilt, after);
  for (int i = 0; i < 3000; ++i) {
    step(updated, su, {});
    step(*rebuilt, sr, {});
  }
  EXPECT_EQ(su.warnings, 0);
  EXPECT_LT(su.v.norm(), 1.0);
  const double diff = (su.x - sr.x).rowwise().norm().maxCoeff() / (sr.x - after.X).rowwise().norm().maxCoeff();
  EXPECT_EQ(updated.substeps, rebuilt->substeps);
  EXPECT_LT(diff, 0.05);
  for (int i : fixed) EXPECT_TRUE(su.x.row(i) == after.X.row(i));
}

}  // namespace
}  // namespace hysim::sim
