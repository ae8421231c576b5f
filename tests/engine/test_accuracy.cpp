// The accuracy study's pieces: the CalculiX deck and .dat reader, the beam against its closed
// forms, the orderings of the integrators' errors, the Bullet peer.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "hysim/engine/accuracy/calculix.hpp"
#include "hysim/engine/accuracy/cases.hpp"
#include "hysim/engine/accuracy/runs.hpp"
#include "hysim/sim/static_solve.hpp"
#include "test_dir.hpp"

namespace hysim::engine::accuracy {
namespace {

BeamSpec smallBeam() {
  BeamSpec s;
  s.cell_mm = 5.0;
  return s;
}

TEST(AccuracyCalculix, ReadsDisplacementsTotalsAndFrequencies) {
  const std::string dat =
      "\n displacements (vx,vy,vz) for set NALL and time  0.1000000E+01\n\n"
      "         1  1.000000E-01  0.000000E+00 -2.500000E-01\n"
      "         2  0.000000E+00  3.000000E-01  0.000000E+00\n"
      "         7  9.000000E+00  9.000000E+00  9.000000E+00\n"  // a mid-edge node: not ours
      "\n total force (fx,fy,fz) for set INDENTER and time  0.1000000E+01\n\n"
      "        1.500000E+03  2.000000E+00  0.000000E+00\n"
      "\n     E I G E N V A L U E   O U T P U T\n\n"
      "      1   0.1882349E+05   0.1371987E+03   0.2183586E+02   0.0000000E+00\n"
      "     P A R T I C I P A T I O N   F A C T O R S\n"
      "      1   0.2907811E-08   0.1278268E+01  -0.1278268E+01   0.1108860E+00\n";
  auto s = parseCalculixDat(dat, 2);
  ASSERT_TRUE(s.ok()) << s.error();
  EXPECT_DOUBLE_EQ(s->u(0, 2), -0.25);
  EXPECT_DOUBLE_EQ(s->u(1, 1), 0.3);
  EXPECT_DOUBLE_EQ(s->indenter_force.x(), 1500.0);
  ASSERT_EQ(s->frequencies_hz.size(), 1u);  // the participation table is not a mode
  EXPECT_NEAR(s->frequencies_hz[0], 21.83586, 1e-9);
}

TEST(AccuracyCalculix, BadOutputIsAnErrorNamingTheLine) {
  auto s = parseCalculixDat(" displacements (vx,vy,vz) for set NALL\n        0  1.0 2.0 3.0\n", 2);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().find("line 2"), std::string::npos) << s.error();
  EXPECT_FALSE(parseCalculixDat("nothing here\n", 2).ok());
}

TEST(AccuracyCalculix, QuadraticDeckClampsTheMidNodesOfTheClampedFace) {
  const AccuracyCase beam = beamCase(smallBeam());
  FeOptions o;
  const std::string deck = calculixDeck(beam, o);
  EXPECT_NE(deck.find("TYPE=C3D10"), std::string::npos);
  EXPECT_NE(deck.find("*DLOAD"), std::string::npos);
  // 9 clamped corner nodes on a 2 x 2 face; its 6-tet cubes add the face's 16 edges' mid nodes.
  const size_t at = deck.find("*NSET, NSET=FIXED\n");
  ASSERT_NE(at, std::string::npos);
  const std::string set = deck.substr(at + 18, deck.find('*', at + 1) - at - 18);
  std::string numbers = set;
  std::replace(numbers.begin(), numbers.end(), ',', ' ');
  std::istringstream entries(numbers);
  int count = 0;
  for (int node; entries >> node;) ++count;
  EXPECT_EQ(count, 9 + 16) << set;
  o.quadratic = false;
  EXPECT_NE(calculixDeck(beam, o).find("TYPE=C3D4"), std::string::npos);
}

// CalculiX is installed by tools/install-deps: its absence is a failure, not a skip.
TEST(AccuracyCalculix, BeamAgreesWithEulerBernoulli) {
  ASSERT_TRUE(calculixAvailable()) << "ccx not found: run tools/install-deps";
  BeamSpec spec;
  spec.cell_mm = 2.5;
  const AccuracyCase beam = beamCase(spec);
  const std::string dir = hysim::testing::testDir("AccuracyCalculix").string();
  FeOptions o;
  auto fe = solveCalculix(beam, o, dir, "beam");
  ASSERT_TRUE(fe.ok()) << fe.error();
  double tip = 0.0;
  for (int i = 0; i < beam.mesh.numNodes(); ++i)
    if (beam.mesh.X(i, 0) == spec.length_mm) tip = std::max(tip, -fe->u(i, 2));
  EXPECT_NEAR(tip, beamTipSagMm(spec), 0.1 * beamTipSagMm(spec));  // shear and the clamp add a little
  o.frequencies = 1;
  auto f = solveCalculix(beam, o, dir, "beam_frequency");
  ASSERT_TRUE(f.ok()) << f.error();
  ASSERT_FALSE(f->frequencies_hz.empty());
  EXPECT_NEAR(f->frequencies_hz[0], beamFirstFrequencyHz(spec), 0.1 * beamFirstFrequencyHz(spec));
}

Setting symplectic(int substeps) {
  Setting s;
  s.family = "symplectic_euler";
  s.options.max_substeps = 0;
  s.options.substeps = substeps;
  return s;
}

Setting implicitEuler(int iterations, double dt) {
  Setting s;
  s.family = "implicit_euler";
  s.options.integrator = sim::Integrator::ImplicitEuler;
  s.options.implicit_iterations = iterations;
  s.options.dt = dt;
  return s;
}

TEST(AccuracyOrderings, SymplecticErrorFallsAsSubstepsGrow) {
  const AccuracyCase beam = beamCase(smallBeam());
  RunSpec spec;
  spec.duration_s = 0.1;
  spec.sample_every_s = 0.01;
  auto model = caseModel(beam, symplectic(0).options);
  ASSERT_TRUE(model.ok());
  const int n = model->substeps;
  const Trajectory ref = runTrajectory(beam, symplectic(16 * n), spec);
  double previous = INFINITY;
  for (int factor : {1, 2, 4}) {
    const double e = trajectoryError(runTrajectory(beam, symplectic(factor * n), spec), ref, beam.mesh.X);
    EXPECT_LT(e, previous) << factor << "x substeps";
    previous = e;
  }
  EXPECT_LT(previous, 0.01);
  // A third of the automatic substeps is past the stability limit: caught, never NaN.
  const Trajectory unstable = runTrajectory(beam, symplectic(std::max(1, n / 3)), spec);
  EXPECT_TRUE(unstable.diverged);
  EXPECT_TRUE(std::isinf(trajectoryError(unstable, ref, beam.mesh.X)));
}

TEST(AccuracyOrderings, ImplicitEulerConvergesToTheStaticSolution) {
  AccuracyCase beam = beamCase(smallBeam());
  beam.drag_per_s = 40.0;  // settles within the run
  auto model = caseModel(beam, implicitEuler(1, 5e-3).options);
  ASSERT_TRUE(model.ok());
  sim::State rest = sim::makeState(*model, beam.mesh);
  ASSERT_TRUE(sim::solveStatic(*model, rest).converged);
  const double sag = (rest.x - beam.mesh.X).norm();
  RunSpec spec;
  spec.duration_s = 2.0;
  spec.sample_every_s = 0.05;
  // Local/global iterations approach the static solution slowly in the beam's soft bending
  // mode: more iterations per step, closer after the same time.
  double previous = INFINITY;
  for (int it : {1, 4, 16, 64}) {
    const Trajectory t = runTrajectory(beam, implicitEuler(it, 5e-3), spec);
    ASSERT_FALSE(t.diverged);
    const double e = (t.samples.back() - rest.x).norm() / sag;
    EXPECT_LT(e, previous) << it << " iterations";
    previous = e;
  }
  EXPECT_LT(previous, 1e-3);
  // 33 ms steps stay bounded.
  const Trajectory slow = runTrajectory(beam, implicitEuler(8, 33e-3), spec);
  EXPECT_FALSE(slow.diverged);
  EXPECT_TRUE(slow.samples.back().allFinite());
}

TEST(AccuracyBullet, PeerRunsTheSameBodyAndStaysFinite) {
  const AccuracyCase beam = beamCase(smallBeam());
  Setting s;
  s.family = "bullet";
  s.bullet = true;
  RunSpec spec;
  spec.duration_s = 0.05;
  spec.sample_every_s = 0.01;
  const Trajectory t = runTrajectory(beam, s, spec);
  ASSERT_FALSE(t.diverged);
  ASSERT_EQ(t.samples.size(), 6u);
  EXPECT_EQ(t.samples.back().rows(), beam.mesh.numNodes());
  EXPECT_TRUE(t.samples.back().allFinite());
  // It sags: the free end moves down, the clamped face does not.
  double clamped = 0.0, tip = 0.0;
  for (int i = 0; i < beam.mesh.numNodes(); ++i) {
    const double dz = t.samples.back()(i, 2) - beam.mesh.X(i, 2);
    if (beam.mesh.X(i, 0) == 0.0) clamped = std::max(clamped, std::abs(dz));
    if (beam.mesh.X(i, 0) == 50.0) tip = std::min(tip, dz);
  }
  EXPECT_EQ(clamped, 0.0);
  EXPECT_LT(tip, 0.0);
}

}  // namespace
}  // namespace hysim::engine::accuracy
