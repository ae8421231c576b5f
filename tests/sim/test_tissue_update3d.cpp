// Tissue update after 3D cuts: positive masses that keep the ten moments, remapped state.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cstring>
#include <limits>
#include <map>
#include <random>

#include "box_mesh.hpp"
#include "hysim/cutting/cut3d.hpp"
#include "hysim/sim/tissue_update3d.hpp"
#include "../../sim/src/model_internal.hpp"  // topTridiagonalEigenvalue

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

// Two updated models with the same bits: masses, springs, stability.
void expectSameModel(const Model& a, const Model& b) {
  EXPECT_EQ(a.num_nodes, b.num_nodes);
  EXPECT_TRUE(a.mass == b.mass);
  EXPECT_TRUE(a.springs == b.springs);
  EXPECT_TRUE(a.stiffness == b.stiffness);
  EXPECT_TRUE(a.damping == b.damping);
  EXPECT_TRUE(a.rest_length == b.rest_length);
  EXPECT_EQ(a.omega_max, b.omega_max);
  EXPECT_EQ(a.substeps, b.substeps);
  EXPECT_TRUE(a.stability_mode == b.stability_mode);
}

// A one-material model of `mesh` with the nodes below z = 0.5 held.
auto modelHeldBelowHalf(const cutting::TetMesh& mesh) {
  Material mat;
  mat.label = 1;
  std::vector<int> fixed;
  for (int i = 0; i < mesh.numNodes(); ++i)
    if (mesh.X(i, 2) < 0.5) fixed.push_back(i);
  return buildModel(mesh, {mat}, fixed, {});
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

// Eigen's cache sizes are global: the tests that set them put them back on every way out.
struct RestoreCacheSizes {
  std::ptrdiff_t l1 = 0, l2 = 0, l3 = 0;
  RestoreCacheSizes() { Eigen::internal::manage_caching_sizes(Eigen::GetAction, &l1, &l2, &l3); }
  ~RestoreCacheSizes() { Eigen::setCpuCacheSizes(l1, l2, l3); }
};

// The masses after a cut do not depend on the CPU's cache sizes. (Eigen's general product
// sizes its blocks of a long inner dimension from them; with > ~550 unknowns, A Aᵀ in the
// moment correction rounded differently on a 48 KiB L1 than on a 32 KiB one, and the default
// run diverged between machines.)
TEST(TissueUpdate3D, MassesAreTheSameForAnyCpuCacheSizes) {
  const auto box = testing::boxTetMesh(14, 14, 14, 0.25);
  const Eigen::VectorXd m0 = lumpedMasses3D(box, Eigen::VectorXd::Constant(box.numTets(), 1e-3));
  auto r = cutting::cut3d(box, *cutting::CutSurface::plane(Vec3(1.71, 1.63, 1.77), Vec3(0.3, 0.2, 1)), {});
  ASSERT_TRUE(r.ok()) << r.error();
  const Eigen::VectorXd density = Eigen::VectorXd::Constant(r->mesh.numTets(), 1e-3);
  RestoreCacheSizes restore;
  std::vector<Eigen::VectorXd> masses;
  MassUpdate3DReport report;
  for (const std::ptrdiff_t kib : {32, 48, 64}) {
    Eigen::setCpuCacheSizes(kib * 1024, 1280 * 1024, 32 * 1024 * 1024);
    auto m = updateMasses3D(box, m0, r->mesh, r->change, density, {}, &report);
    ASSERT_TRUE(m.ok()) << m.error();
    masses.push_back(*m);
  }
  EXPECT_GT(report.unknowns, 1000);  // well past where the blocking splits the sum
  EXPECT_LT(report.moment_residual, 1e-9);
  for (size_t k = 1; k < masses.size(); ++k) {
    ASSERT_EQ(masses[k].size(), masses[0].size());
    EXPECT_EQ(0, std::memcmp(masses[k].data(), masses[0].data(), sizeof(double) * masses[0].size()))
        << "L1 setting " << k;
  }
}

// gramFixedOrder, as the 2D update calls it (a dynamic 6-row matrix): A Aᵀ to rounding,
// symmetric, and the same bits whatever the cache sizes Eigen is told.
TEST(TissueUpdate3D, GramInFixedOrderIsTheProductWithTheSameBitsForAnyCacheSizes) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd A(6, 3000);
  for (Eigen::Index j = 0; j < A.cols(); ++j)
    for (int i = 0; i < 6; ++i) A(i, j) = u(rng);
  RestoreCacheSizes restore;
  Eigen::setCpuCacheSizes(32 * 1024, 1280 * 1024, 32 * 1024 * 1024);
  const Eigen::Matrix<double, 6, 6> B = gramFixedOrder<6>(A);
  const Eigen::MatrixXd ref = A * A.transpose();
  EXPECT_LT((B - ref).cwiseAbs().maxCoeff(), 1e-12 * ref.cwiseAbs().maxCoeff());
  EXPECT_TRUE(B == B.transpose());
  Eigen::setCpuCacheSizes(48 * 1024, 1280 * 1024, 32 * 1024 * 1024);
  const Eigen::Matrix<double, 6, 6> B48 = gramFixedOrder<6>(A);
  EXPECT_EQ(0, std::memcmp(B.data(), B48.data(), sizeof(double) * 36));
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

// The incremental update after a cut gives buildModel's springs (same edges, Van Gelder
// stiffness, rest lengths) and masses that keep the moments, positive, after each of
// several cuts, with the piece cut free removed.
TEST(TissueUpdate3D, IncrementalUpdateMatchesARebuild) {
  cutting::TetMesh mesh = testing::boxTetMesh(6, 6, 6, 1.0);
  Material mat;
  mat.label = 1;
  mat.stiffness_damping_s = 1e-5;
  auto anchoredAt = [](const cutting::TetMesh& m) {
    std::vector<std::uint8_t> fixed(static_cast<size_t>(m.numNodes()), 0);
    for (int i = 0; i < m.numNodes(); ++i) fixed[i] = m.X(i, 2) < 0.5 ? 1 : 0;
    return fixed;
  };
  auto fixedList = [](const std::vector<std::uint8_t>& f) {
    std::vector<int> out;
    for (int i = 0; i < static_cast<int>(f.size()); ++i)
      if (f[i]) out.push_back(i);
    return out;
  };
  auto built = buildModel(mesh, {mat}, fixedList(anchoredAt(mesh)), {});
  ASSERT_TRUE(built.ok()) << built.error();
  Model model = *built;
  for (int cut = 0; cut < 3; ++cut) {
    const Vec3 point(3.0, 3.0, 4.3 - 0.8 * cut), normal(0.15 * cut, 0.2, 1.0);
    auto r = cutting::cut3d(mesh, *cutting::CutSurface::plane(point, normal));
    ASSERT_TRUE(r.ok()) << r.error();
    const cutting::TetMesh& after = r->mesh;
    // Remove the top piece (free: no anchored node), renumbering the rest in order.
    const auto fixed_after = anchoredAt(after);
    const auto comps = cutting::tetComponents(after, fixedList(fixed_after));
    std::vector<std::int32_t> keep(static_cast<size_t>(after.numNodes()), -1);
    std::vector<int> tets;
    for (int t = 0; t < after.numTets(); ++t)
      if (!comps.free[comps.label[t]]) {
        tets.push_back(t);
        for (int k = 0; k < 4; ++k) keep[after.T(t, k)] = 0;
      }
    int n = 0;
    for (auto& k : keep)
      if (k == 0) k = n++;
    cutting::TetMesh kept;
    kept.X.resize(n, 3);
    for (int i = 0; i < after.numNodes(); ++i)
      if (keep[i] >= 0) kept.X.row(keep[i]) = after.X.row(i);
    kept.T.resize(static_cast<Eigen::Index>(tets.size()), 4);
    kept.material.resize(static_cast<Eigen::Index>(tets.size()));
    for (size_t k = 0; k < tets.size(); ++k) {
      for (int c = 0; c < 4; ++c) kept.T(static_cast<Eigen::Index>(k), c) = keep[after.T(tets[k], c)];
      kept.material[static_cast<Eigen::Index>(k)] = after.material[tets[k]];
    }
    // Moments the kept masses must have: the cut's moment-preserving masses on the whole
    // cut mesh, less the removed piece.
    const Model previous = model;
    CutUpdate3DReport report;
    ASSERT_TRUE(updateModelAfterCut3D(model, mesh, after, r->change, fixed_after, keep, {}, &report).ok());
    EXPECT_LT(report.masses.moment_residual, 1e-9) << "cut " << cut;
    EXPECT_GT(report.touched_nodes, 0);
    ASSERT_EQ(model.num_nodes, n);
    auto rebuilt = buildModel(kept, {mat}, fixedList(anchoredAt(kept)), {});
    ASSERT_TRUE(rebuilt.ok());
    ASSERT_EQ(model.springs.rows(), rebuilt->springs.rows()) << "cut " << cut;
    std::map<std::pair<int, int>, int> index;
    for (int s = 0; s < rebuilt->springs.rows(); ++s) index[{rebuilt->springs(s, 0), rebuilt->springs(s, 1)}] = s;
    for (int s = 0; s < model.springs.rows(); ++s) {
      int a = model.springs(s, 0), b = model.springs(s, 1);
      if (a > b) std::swap(a, b);
      ASSERT_TRUE(index.count({a, b})) << "cut " << cut << " spring " << a << "-" << b;
      const int o = index[{a, b}];
      EXPECT_NEAR(model.stiffness[s], rebuilt->stiffness[o], 1e-9 * rebuilt->stiffness[o]);
      EXPECT_NEAR(model.damping[s], rebuilt->damping[o], 1e-9 * rebuilt->damping[o]);
      EXPECT_NEAR(model.rest_length[s], rebuilt->rest_length[o], 1e-12);
    }
    for (int i = 0; i < n; ++i) {
      EXPECT_EQ(model.fixed[i], rebuilt->fixed[i]);
      EXPECT_GT(model.mass[i], 0.0);
    }
    // Step springs: every spring with a free end, each node's incident list complete.
    EXPECT_EQ(model.step_springs.size(), rebuilt->step_springs.size());
    EXPECT_EQ(model.step_springs.node_offset, rebuilt->step_springs.node_offset);
    // Stability: the estimate near the cut (or the global one) agrees with a global
    // estimate of the same model (nothing touched, global forced).
    {
      Model global = model;
      cutting::TopologyChange identity;
      identity.old_num_nodes = identity.new_num_nodes = n;
      for (int i = 0; i < n; ++i) identity.node_old_to_new.push_back(i);
      for (int t = 0; t < kept.numTets(); ++t) identity.element_old_to_new.push_back(t);
      std::vector<std::uint8_t> flags(model.fixed.begin(), model.fixed.end());
      CutUpdate3DOptions options;
      options.mode_overlap = -1.0;
      options.max_held_estimates = 0;  // never the previous estimate held as a bound
      ASSERT_TRUE(updateModelAfterCut3D(global, kept, kept, identity, flags, {}, options).ok());
      EXPECT_GT(model.omega_max, 0.97 * global.omega_max) << "cut " << cut << (report.global_stability ? " global" : " local");
    }
    EXPECT_GE(model.substeps, 1);
    EXPECT_DOUBLE_EQ(model.substep * model.substeps, model.options.dt);
    mesh = kept;
    (void)previous;
  }
}

// A cut that ends inside the mesh: elements on one side keep their identity but are
// renumbered onto duplicated nodes; their edges change although some of their nodes are
// not on the cut. The springs must still be buildModel's.
TEST(TissueUpdate3D, IncrementalUpdateAfterAPartialCut) {
  const cutting::TetMesh mesh = testing::boxTetMesh(6, 6, 6, 1.0);
  Material mat;
  mat.label = 1;
  std::vector<std::uint8_t> flags;
  auto built = buildModel(mesh, {mat}, {}, {});
  ASSERT_TRUE(built.ok());
  cutting::Positions V(4, 3);
  V << -1, -1, 3.3, 3.4, -1, 3.35, 3.4, 7, 3.35, -1, 7, 3.3;
  cutting::Tris F(2, 3);
  F << 0, 1, 2, 0, 2, 3;
  auto r = cutting::cut3d(mesh, *cutting::CutSurface::triangles(V, F));
  ASSERT_TRUE(r.ok()) << r.error();
  Model model = *built;
  flags.assign(static_cast<size_t>(r->mesh.numNodes()), 0);
  ASSERT_TRUE(updateModelAfterCut3D(model, mesh, r->mesh, r->change, flags, {}).ok());
  auto rebuilt = buildModel(r->mesh, {mat}, {}, {});
  ASSERT_TRUE(rebuilt.ok());
  ASSERT_EQ(model.springs.rows(), rebuilt->springs.rows());
  std::map<std::pair<int, int>, int> index;
  for (int s = 0; s < rebuilt->springs.rows(); ++s) index[{rebuilt->springs(s, 0), rebuilt->springs(s, 1)}] = s;
  for (int s = 0; s < model.springs.rows(); ++s) {
    int a = model.springs(s, 0), b = model.springs(s, 1);
    if (a > b) std::swap(a, b);
    ASSERT_TRUE(index.count({a, b})) << a << "-" << b;
    const int o = index[{a, b}];
    EXPECT_NEAR(model.stiffness[s], rebuilt->stiffness[o], 1e-9 * model.stiffness[s]);
  }
  EXPECT_GT(model.mass.minCoeff(), 0.0);
  EXPECT_NEAR(model.mass.sum(), built->mass.sum(), 1e-9 * built->mass.sum());
}

// An update that drops the pieces cut free (node_to_kept) reports its steps' wall times; the
// same update of another copy gives the same model to the last bit; an update that is
// refused (fixed flags of the wrong size) leaves the model as it was.
TEST(TissueUpdate3D, UpdateDroppingPiecesIsRepeatableAndRefusedLeavesTheModel) {
  const cutting::TetMesh mesh = testing::boxTetMesh(6, 6, 6, 1.0);
  auto built = modelHeldBelowHalf(mesh);
  ASSERT_TRUE(built.ok());
  // Cut off the top layer: its nodes leave (node_to_kept < 0), the rest is renumbered.
  auto r = cutting::cut3d(mesh, *cutting::CutSurface::plane(Vec3(0, 0, 5.5), Vec3(0.05, 0.02, 1)));
  ASSERT_TRUE(r.ok()) << r.error();
  const int n = r->mesh.numNodes();
  std::vector<std::uint8_t> fixed(static_cast<size_t>(n), 0);
  for (int i = 0; i < n; ++i) fixed[i] = r->mesh.X(i, 2) < 0.5 ? 1 : 0;
  std::vector<std::int32_t> keep(static_cast<size_t>(n), -1);
  std::vector<std::uint8_t> low(static_cast<size_t>(n), 0);
  for (int t = 0; t < r->mesh.numTets(); ++t) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) c += r->mesh.X.row(r->mesh.T(t, k)).transpose() / 4.0;
    if (c.z() < 5.5)
      for (int k = 0; k < 4; ++k) low[r->mesh.T(t, k)] = 1;
  }
  for (int i = 0, kept = 0; i < n; ++i)
    if (low[i]) keep[i] = kept++;
  Model one = *built, two = *built;
  CutUpdate3DReport rep_one, rep_two;
  ASSERT_TRUE(updateModelAfterCut3D(one, mesh, r->mesh, r->change, fixed, keep, {}, &rep_one).ok());
  ASSERT_TRUE(updateModelAfterCut3D(two, mesh, r->mesh, r->change, fixed, keep, {}, &rep_two).ok());
  EXPECT_LT(one.num_nodes, n);
  expectSameModel(one, two);
  EXPECT_EQ(rep_one.lanczos_steps, rep_two.lanczos_steps);
  EXPECT_EQ(rep_one.touched_nodes, rep_two.touched_nodes);
  EXPECT_GT(rep_one.prepare_ms, 0.0);
  EXPECT_GT(rep_one.springs_ms, 0.0);
  EXPECT_GT(rep_one.stability_ms, 0.0);
  Model refused_model = *built;
  const std::vector<std::uint8_t> short_flags(static_cast<size_t>(n - 1), 0);
  const Status refused = updateModelAfterCut3D(refused_model, mesh, r->mesh, r->change, short_flags, keep);
  EXPECT_FALSE(refused.ok());
  EXPECT_NE(refused.error().find("fixed flags"), std::string::npos) << refused.error();
  EXPECT_EQ(refused_model.num_nodes, built->num_nodes);
  EXPECT_TRUE(refused_model.mass == built->mass);
  EXPECT_TRUE(refused_model.springs == built->springs);
}

// The same update twice gives the same model to the last bit (no state carries over from
// one update to the next), for the SIMD and the baseline forms, after complete cuts and
// after partial cuts (a small one in a larger box, whose masses sum over the touched nodes'
// tets rather than over all tets), also where rounds of mass scaling follow (max_substeps
// 1). Updates that fail (an unknown material, masses that cannot be kept, tets of
// non-positive volume) name the cause and leave the model as it was.
TEST(TissueUpdate3D, TheSameUpdateTwiceGivesTheSameModel) {
  const cutting::TetMesh box6 = testing::boxTetMesh(6, 6, 6, 1.0);
  const cutting::TetMesh box12 = testing::boxTetMesh(12, 12, 12, 1.0);
  Material mat;
  mat.label = 1;
  mat.stiffness_damping_s = 1e-4;
  const cutting::CutSurface complete = *cutting::CutSurface::plane(Vec3(0, 0, 3.04), Vec3(0.03, 0.02, 1));
  // Strips ending inside the box: partial cuts.
  auto strip = [](double x0, double x1, double y0, double y1, double z) {
    cutting::Positions sx(4, 3);
    sx << x0, y0, z, x1, y0, z + 0.1, x0, y1, z + 0.05, x1, y1, z + 0.15;
    cutting::Tris sf(2, 3);
    sf << 0, 1, 3, 0, 3, 2;
    return *cutting::CutSurface::triangles(sx, sf);
  };
  const cutting::CutSurface partial = strip(-1, 3.5, -1, 7, 2.6), small = strip(-1, 2.5, 4.3, 7.7, 6.55);
  const std::pair<const cutting::TetMesh*, const cutting::CutSurface*> cases[] = {
      {&box6, &complete}, {&box6, &partial}, {&box12, &small}, {&box12, &complete}};
  for (const auto& [mesh_ptr, surface] : cases) {
    const cutting::TetMesh& mesh = *mesh_ptr;
    std::vector<int> fixed;
    for (int i = 0; i < mesh.numNodes(); ++i)
      if (mesh.X(i, 2) < 0.5) fixed.push_back(i);
    auto r = cutting::cut3d(mesh, *surface);
    ASSERT_TRUE(r.ok()) << r.error();
    ASSERT_GT(r->change.new_nodes.size(), 0u);
    std::vector<std::uint8_t> flags(static_cast<size_t>(r->mesh.numNodes()), 0);
    for (int i = 0; i < r->mesh.numNodes(); ++i) flags[i] = r->mesh.X(i, 2) < 0.5 ? 1 : 0;
    for (const auto& [simd, max_substeps] : {std::pair{true, 32}, {false, 32}, {true, 1}}) {
      ModelOptions model_options;
      model_options.simd = simd;
      model_options.max_substeps = max_substeps;
      auto built = buildModel(mesh, {mat}, fixed, model_options);
      ASSERT_TRUE(built.ok());
      Model first = *built, second = *built;
      CutUpdate3DReport ra, rb;
      ASSERT_TRUE(updateModelAfterCut3D(first, mesh, r->mesh, r->change, flags, {}, {}, &ra).ok());
      ASSERT_TRUE(updateModelAfterCut3D(second, mesh, r->mesh, r->change, flags, {}, {}, &rb).ok());
      expectSameModel(first, second);
      EXPECT_TRUE(first.inv_mass == second.inv_mass);
      EXPECT_EQ(first.added_mass, second.added_mass);
      if (max_substeps == 1 && surface != &small) {  // (after the small cut the previous estimate is carried)
        EXPECT_GT(first.added_mass, built->added_mass);  // rounds of mass scaling ran
      }
      const StepSprings &sa = first.step_springs, &sb = second.step_springs;
      EXPECT_TRUE(sa.a == sb.a && sa.b == sb.b && sa.node_offset == sb.node_offset && sa.incident == sb.incident);
      EXPECT_TRUE(sa.rest_length == sb.rest_length && sa.stiffness == sb.stiffness && sa.damping == sb.damping &&
                  sa.sign == sb.sign);
      EXPECT_GT(ra.springs_recomputed, 0);
      EXPECT_LT(ra.touched_nodes, r->mesh.numNodes());
      EXPECT_EQ(ra.touched_nodes, rb.touched_nodes);
      EXPECT_EQ(ra.springs_recomputed, rb.springs_recomputed);
      EXPECT_EQ(ra.lanczos_steps, rb.lanczos_steps);
      EXPECT_EQ(ra.global_stability, rb.global_stability);
    }
    auto built = buildModel(mesh, {mat}, fixed, {});
    ASSERT_TRUE(built.ok());
    auto expectRefused = [&](const cutting::TetMesh& after, Model model, const std::string& cause) {
      const Eigen::VectorXd mass = model.mass;
      const Status st = updateModelAfterCut3D(model, mesh, after, r->change, flags, {});
      ASSERT_FALSE(st.ok());
      EXPECT_NE(st.error().find(cause), std::string::npos) << st.error();
      EXPECT_EQ(model.num_nodes, mesh.numNodes());
      ASSERT_EQ(model.mass.size(), mass.size());
      EXPECT_EQ(0, std::memcmp(model.mass.data(), mass.data(), sizeof(double) * mass.size()));  // (NaN too)
    };
    {
      cutting::TetMesh unknown = r->mesh;  // a material the model does not know
      unknown.material[unknown.numTets() / 2] = 7;
      expectRefused(unknown, *built, "material label 7");
    }
    {
      Model broken = *built;  // masses that cannot be kept (the old ones not finite)
      broken.mass.setConstant(std::numeric_limits<double>::quiet_NaN());
      expectRefused(r->mesh, broken, "non-finite or negative mass");
    }
    if (mesh_ptr == &box12 && surface == &complete) {
      // Every element the cut kept turned inside out (two nodes swapped: the same element to
      // the comparison, of negative volume).
      cutting::TetMesh inverted = r->mesh;
      std::vector<std::uint8_t> added(static_cast<size_t>(inverted.numTets()), 0);
      for (int t : r->change.added_elements) added[t] = 1;
      for (int t = 0; t < inverted.numTets(); ++t)
        if (!added[t]) std::swap(inverted.T(t, 0), inverted.T(t, 1));
      expectRefused(inverted, *built, "non-positive volume");
    }
  }
}

// An estimate that is followed by a round of mass scaling whatever its exact value stops as
// soon as its Ritz value shows that: the model is the one of estimates run to convergence,
// to the last bit, in fewer Lanczos steps.
TEST(TissueUpdate3D, DecidedEstimatesStopEarlyWithTheSameModel) {
  const cutting::TetMesh mesh = testing::boxTetMesh(6, 6, 6, 1.0);
  Material mat;
  mat.label = 1;
  ModelOptions mo;
  mo.max_substeps = 2;  // every update scales masses
  std::vector<int> fixed;
  for (int i = 0; i < mesh.numNodes(); ++i)
    if (mesh.X(i, 2) < 0.5) fixed.push_back(i);
  auto built = buildModel(mesh, {mat}, fixed, mo);
  ASSERT_TRUE(built.ok());
  // A cut close to a layer of nodes: small elements, stiff springs, mass scaling.
  auto r = cutting::cut3d(mesh, *cutting::CutSurface::plane(Vec3(0, 0, 3.04), Vec3(0.03, 0.02, 1)));
  ASSERT_TRUE(r.ok()) << r.error();
  std::vector<std::uint8_t> flags(static_cast<size_t>(r->mesh.numNodes()), 0);
  for (int i = 0; i < r->mesh.numNodes(); ++i) flags[i] = r->mesh.X(i, 2) < 0.5 ? 1 : 0;
  for (const bool global : {false, true}) {
    CutUpdate3DOptions full, early;
    full.stop_decided_estimates = false;
    if (global) full.mode_overlap = early.mode_overlap = -1.0;
    if (global) full.max_held_estimates = early.max_held_estimates = 0;
    Model a = *built, b = *built;
    CutUpdate3DReport ra, rb;
    ASSERT_TRUE(updateModelAfterCut3D(a, mesh, r->mesh, r->change, flags, {}, full, &ra).ok());
    ASSERT_TRUE(updateModelAfterCut3D(b, mesh, r->mesh, r->change, flags, {}, early, &rb).ok());
    EXPECT_GT(a.added_mass, built->added_mass) << "global " << global;
    EXPECT_EQ(a.omega_max, b.omega_max) << "global " << global;
    EXPECT_EQ(a.critical_dt, b.critical_dt);
    EXPECT_EQ(a.substeps, b.substeps);
    EXPECT_EQ(a.added_mass, b.added_mass);
    EXPECT_TRUE(a.mass == b.mass);
    EXPECT_TRUE(a.stability_mode == b.stability_mode);
    EXPECT_EQ(a.stability_held, b.stability_held);
    EXPECT_LT(rb.lanczos_steps, ra.lanczos_steps) << "global " << global;
  }
}

// The AVX2 forms (the Lanczos operator and step, the same-element test) and the baseline
// ones must agree bit for bit, or a scene would hash differently by CPU.
TEST(TissueUpdate3D, SimdAndBaselineUpdatesAreBitIdentical) {
  const cutting::TetMesh mesh = testing::boxTetMesh(6, 6, 6, 1.0);
  Material mat;
  mat.label = 1;
  mat.stiffness_damping_s = 1e-4;
  std::vector<int> fixed;
  for (int i = 0; i < mesh.numNodes(); ++i)
    if (mesh.X(i, 2) < 0.5) fixed.push_back(i);
  auto r = cutting::cut3d(mesh, *cutting::CutSurface::plane(Vec3(0, 0, 3.04), Vec3(0.03, 0.02, 1)));
  ASSERT_TRUE(r.ok()) << r.error();
  std::vector<std::uint8_t> flags(static_cast<size_t>(r->mesh.numNodes()), 0);
  for (int i = 0; i < r->mesh.numNodes(); ++i) flags[i] = r->mesh.X(i, 2) < 0.5 ? 1 : 0;
  for (const int max_substeps : {2, 0})
    for (const bool global : {false, true}) {
      ModelOptions simd, baseline;
      simd.max_substeps = baseline.max_substeps = max_substeps;  // 2: every update scales masses
      baseline.simd = false;
      auto a0 = buildModel(mesh, {mat}, fixed, simd), b0 = buildModel(mesh, {mat}, fixed, baseline);
      ASSERT_TRUE(a0.ok() && b0.ok());
      CutUpdate3DOptions options;
      if (global) options.mode_overlap = -1.0;
      if (global) options.max_held_estimates = 0;
      Model a = *a0, b = *b0;
      CutUpdate3DReport ra, rb;
      ASSERT_TRUE(updateModelAfterCut3D(a, mesh, r->mesh, r->change, flags, {}, options, &ra).ok());
      ASSERT_TRUE(updateModelAfterCut3D(b, mesh, r->mesh, r->change, flags, {}, options, &rb).ok());
      EXPECT_GT(ra.lanczos_steps, 0);
      EXPECT_EQ(ra.lanczos_steps, rb.lanczos_steps);
      EXPECT_EQ(ra.touched_nodes, rb.touched_nodes);
      EXPECT_EQ(a.omega_max, b.omega_max) << "global " << global << " max_substeps " << max_substeps;
      EXPECT_EQ(a.critical_dt, b.critical_dt);
      EXPECT_EQ(a.substeps, b.substeps);
      EXPECT_EQ(a.added_mass, b.added_mass);
      EXPECT_TRUE(a.mass == b.mass);
      EXPECT_TRUE(a.springs == b.springs);
      EXPECT_TRUE(a.stiffness == b.stiffness);
      EXPECT_TRUE(a.stability_mode == b.stability_mode);
      EXPECT_TRUE(a.step_springs.incident == b.step_springs.incident);
      EXPECT_TRUE(a.step_springs.stiffness == b.step_springs.stiffness);
    }
}

// Global Lanczos estimate of `model` as it is (nothing changed, every node's mode "near"),
// with the Lanczos options of `base`; *steps (optional) gets the Lanczos steps taken.
double globalOmega(const Model& model, const cutting::TetMesh& mesh, const CutUpdate3DOptions& base = {},
                   int* steps = nullptr) {
  Model global = model;
  cutting::TopologyChange identity;
  identity.old_num_nodes = identity.new_num_nodes = mesh.numNodes();
  for (int i = 0; i < mesh.numNodes(); ++i) identity.node_old_to_new.push_back(i);
  for (int t = 0; t < mesh.numTets(); ++t) identity.element_old_to_new.push_back(t);
  std::vector<std::uint8_t> flags(model.fixed.begin(), model.fixed.end());
  CutUpdate3DOptions options = base;
  options.mode_overlap = -1.0;
  options.max_held_estimates = 0;
  CutUpdate3DReport report;
  EXPECT_TRUE(updateModelAfterCut3D(global, mesh, mesh, identity, flags, {}, options, &report).ok());
  EXPECT_TRUE(report.global_stability);
  if (steps) *steps = report.lanczos_steps;
  return global.omega_max;
}

// Cuts near the previous highest mode: the previous estimate is held as a bound for the
// rest of the mesh (never below the global estimate of the cut model), at most
// max_held_estimates updates in a row; the first update after buildModel (power iteration)
// and the one after that many holds estimate over all nodes. With max_held_estimates = 0
// every such update is global.
TEST(TissueUpdate3D, HeldStabilityBoundStaysAboveTheGlobalEstimate) {
  for (const int max_held : {2, 0}) {
    cutting::TetMesh mesh = testing::boxTetMesh(6, 6, 6, 1.0);
    auto built = modelHeldBelowHalf(mesh);
    ASSERT_TRUE(built.ok());
    Model model = *built;
    EXPECT_EQ(model.stability_held, -1);
    CutUpdate3DOptions options;
    options.mode_overlap = -1.0;  // every cut counts as near the previous mode
    options.max_held_estimates = max_held;
    int holds = 0, globals = 0, held_in_a_row = 0;
    for (int cut = 0; cut < 8; ++cut) {
      const Vec3 point(1.3 + 0.45 * cut, 2.9, 3.1), normal(1.0, 0.1 * (cut % 3), 0.2);
      auto r = cutting::cut3d(mesh, *cutting::CutSurface::plane(point, normal));
      ASSERT_TRUE(r.ok()) << r.error();
      std::vector<std::uint8_t> flags(static_cast<size_t>(r->mesh.numNodes()), 0);
      for (int i = 0; i < r->mesh.numNodes(); ++i) flags[i] = r->mesh.X(i, 2) < 0.5 ? 1 : 0;
      const int held_before = model.stability_held;
      CutUpdate3DReport report;
      ASSERT_TRUE(updateModelAfterCut3D(model, mesh, r->mesh, r->change, flags, {}, options, &report).ok());
      mesh = r->mesh;
      const bool must_be_global = held_before < 0 || held_before >= max_held;
      EXPECT_EQ(report.global_stability, must_be_global) << "cut " << cut << " held before " << held_before;
      EXPECT_FALSE(report.global_stability && report.held_stability);
      if (report.held_stability) {
        EXPECT_EQ(model.omega_max, report.omega_previous);
        EXPECT_LT(report.omega_local, report.omega_previous);
        EXPECT_EQ(model.stability_held, held_before + 1);
      } else {
        EXPECT_EQ(model.stability_held, 0);
      }
      held_in_a_row = report.held_stability ? held_in_a_row + 1 : 0;
      EXPECT_LE(held_in_a_row, max_held);
      holds += report.held_stability ? 1 : 0;
      globals += report.global_stability ? 1 : 0;
      // The held bound, like the local estimate, is not below the whole mesh's estimate.
      const double global = globalOmega(model, mesh);
      EXPECT_GT(model.omega_max, 0.97 * global) << "cut " << cut;
      EXPECT_EQ(model.critical_dt > 0.0, true);
    }
    if (max_held > 0) {
      EXPECT_GT(holds, 0);
      EXPECT_LT(globals, 8);
    } else {
      EXPECT_EQ(holds, 0);
      EXPECT_EQ(globals, 8);
    }
  }
}

// The Lanczos estimate over the whole mesh is at least the power iteration's (no change:
// an empty cut keeps every node; the overlap threshold < 0 forces the global estimate).
TEST(TissueUpdate3D, LanczosEstimateReachesThePowerIteration) {
  const cutting::TetMesh mesh = testing::boxTetMesh(6, 5, 4, 1.0);
  auto built = modelHeldBelowHalf(mesh);
  ASSERT_TRUE(built.ok());
  Model model = *built;
  cutting::TopologyChange identity;
  identity.old_num_nodes = identity.new_num_nodes = mesh.numNodes();
  identity.old_num_elements = identity.new_num_elements = mesh.numTets();
  for (int i = 0; i < mesh.numNodes(); ++i) identity.node_old_to_new.push_back(i);
  for (int t = 0; t < mesh.numTets(); ++t) identity.element_old_to_new.push_back(t);
  const std::vector<std::uint8_t> flags(model.fixed.begin(), model.fixed.end());
  CutUpdate3DOptions options;
  options.mode_overlap = -1.0;
  options.max_held_estimates = 0;
  CutUpdate3DReport report;
  ASSERT_TRUE(updateModelAfterCut3D(model, mesh, mesh, identity, flags, {}, options, &report).ok());
  EXPECT_TRUE(report.global_stability);
  EXPECT_EQ(report.touched_nodes, 0);
  EXPECT_GE(model.omega_max, built->omega_max * (1.0 - 1e-6));
  EXPECT_LT(model.omega_max, built->omega_max * 1.05);
  EXPECT_EQ(model.mass, built->mass);
  EXPECT_EQ(model.stiffness, built->stiffness);
}

// The Lanczos estimate with the default options (lanczos_min_steps, lanczos_tolerance) is a
// safe stand-in for the converged top frequency: on meshes cut several times, the estimate
// over all free nodes is within 1e-3 below a Lanczos run to convergence (at least 150 steps,
// tolerance 1e-12; reorthogonalised, so its top Ritz value is the top eigenvalue) and never
// above it. The step's stability_safety (0.85) leaves 15 %.
TEST(TissueUpdate3D, DefaultLanczosEstimateIsConverged) {
  cutting::TetMesh mesh = testing::boxTetMesh(7, 6, 5, 1.0);
  auto built = modelHeldBelowHalf(mesh);
  ASSERT_TRUE(built.ok());
  Model model = *built;
  CutUpdate3DOptions converged;
  converged.lanczos_steps = 400;
  converged.lanczos_min_steps = 150;
  converged.lanczos_tolerance = 1e-12;
  for (int cut = 0; cut < 4; ++cut) {
    if (cut > 0) {
      const Vec3 point(1.1 + 1.3 * cut, 2.7, 2.9), normal(1.0, 0.15 * cut, 0.3);
      auto r = cutting::cut3d(mesh, *cutting::CutSurface::plane(point, normal));
      ASSERT_TRUE(r.ok()) << r.error();
      std::vector<std::uint8_t> flags(static_cast<size_t>(r->mesh.numNodes()), 0);
      for (int i = 0; i < r->mesh.numNodes(); ++i) flags[i] = r->mesh.X(i, 2) < 0.5 ? 1 : 0;
      ASSERT_TRUE(updateModelAfterCut3D(model, mesh, r->mesh, r->change, flags, {}).ok());
      mesh = r->mesh;
    }
    int steps = 0, steps_converged = 0;
    const double omega = globalOmega(model, mesh, {}, &steps);
    const double omega_converged = globalOmega(model, mesh, converged, &steps_converged);
    EXPECT_LE(omega, omega_converged * (1.0 + 1e-9)) << "cut " << cut;
    EXPECT_GE(omega, omega_converged * (1.0 - 1e-3)) << "cut " << cut << ", " << steps << " steps";
    EXPECT_LT(steps, steps_converged);
  }
}

// The Lanczos loop's per-step top Ritz value (Newton on the tridiagonal's characteristic
// polynomial) agrees with the dense solver's to round-off, or says it cannot (NaN): on
// tridiagonal reductions of symmetric matrices with well separated, clustered and repeated
// top eigenvalues, and on random tridiagonals with tiny couplings.
TEST(TissueUpdate3D, TopTridiagonalEigenvalueMatchesDenseSolver) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  int cases = 0, unsettled = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int n = 2 + trial % 59;
    Eigen::VectorXd diag(n), sub(n - 1);
    if (trial % 2 == 0) {
      Eigen::VectorXd lambda(n);
      for (int i = 0; i < n; ++i) lambda[i] = uni(rng);
      const int kind = (trial / 2) % 4;
      if (kind >= 1) lambda[0] = 1.0;
      if (kind == 2 && n > 2) lambda[1] = lambda[2] = 1.0 - 1e-7;  // clustered below the top
      if (kind == 3 && n > 1) lambda[1] = 1.0;                     // a double top eigenvalue
      Eigen::MatrixXd v = Eigen::MatrixXd::Random(n, n);
      const Eigen::HouseholderQR<Eigen::MatrixXd> qr(v);
      const Eigen::MatrixXd q = qr.householderQ();
      const Eigen::MatrixXd a = q * lambda.asDiagonal() * q.transpose();
      const Eigen::Tridiagonalization<Eigen::MatrixXd> tri(0.5 * (a + a.transpose()));
      diag = tri.diagonal();
      sub = tri.subDiagonal();
    } else {
      for (int i = 0; i < n; ++i) diag[i] = uni(rng);
      for (int i = 0; i + 1 < n; ++i) sub[i] = (uni(rng) - 0.5) * std::pow(10.0, -8.0 * uni(rng));
    }
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig;
    eig.computeFromTridiagonal(diag, sub, Eigen::EigenvaluesOnly);
    const double dense = eig.eigenvalues()[n - 1];
    const double norm = std::max(diag.cwiseAbs().maxCoeff(), sub.size() ? sub.cwiseAbs().maxCoeff() : 0.0);
    const double newton = topTridiagonalEigenvalue(diag, sub);
    ++cases;
    if (std::isnan(newton)) {
      ++unsettled;
      continue;
    }
    EXPECT_NEAR(newton, dense, 1e-12 * norm) << "trial " << trial << ", n " << n;
  }
  EXPECT_LE(unsettled, cases / 50);  // the dense solver is the fallback, not the rule
}

}  // namespace
}  // namespace hysim::sim
