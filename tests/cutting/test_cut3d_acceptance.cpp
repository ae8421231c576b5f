// Acceptance checks of issue 4 that the 3D cut meets today, over many random planes through
// quality meshes (the uterus mesh, the Table 2 Gmsh ellipsoid). What does not hold yet
// (q*_min >= 0.25x and min edge >= 0.2x the initial for every plane through the uterus mesh;
// 20 successive cuts) is measured by `hysim tables --table 2` and reported, not asserted.
#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/mesh_io.hpp"
#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::cutting {
namespace {

using Vec3 = Eigen::Vector3d;

void randomPlanes(const TetMesh& mesh, int planes, const Cut3DOptions& options, double* worstQ, double* worstE) {
  const auto s0 = computeStats(mesh);
  const double v0 = totalVolume(mesh);
  const Vec3 lo = mesh.X.colwise().minCoeff().transpose(), hi = mesh.X.colwise().maxCoeff().transpose();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.3, 0.7), g(-1, 1);
  *worstQ = *worstE = 1e300;
  for (int p = 0; p < planes; ++p) {
    const Vec3 c = lo + (hi - lo).cwiseProduct(Vec3(u(rng), u(rng), u(rng)));
    const Vec3 n(g(rng), g(rng), g(rng));
    auto r = cut3d(mesh, *CutSurface::plane(c, n), options);
    ASSERT_TRUE(r.ok()) << r.error();
    const auto v = validate(r->mesh);
    ASSERT_TRUE(v.ok()) << "plane " << p << ": " << v.error();
    EXPECT_EQ(countStraddling(r->mesh, c, n, 1e-7), 0) << "plane " << p;
    EXPECT_EQ(countFacesSharedAcross(r->mesh, c, n, 1e-7), 0) << "plane " << p;
    EXPECT_LE(r->mesh.numTets(), 1.10 * mesh.numTets()) << "plane " << p;
    EXPECT_NEAR(totalVolume(r->mesh), v0, 1e-3 * v0) << "plane " << p;
    for (int t = 0; t < r->mesh.numTets(); ++t) ASSERT_GT(tetVolume(r->mesh, t), 0.0);
    const auto s = computeStats(r->mesh);
    *worstQ = std::min(*worstQ, s.q_min / s0.q_min);
    *worstE = std::min(*worstE, s.edge_min / s0.edge_min);
  }
}

TEST(Cut3DAcceptance, UterusRandomPlanesValidGrowthVolume) {
  const std::string path = std::string(HYSIM_SOURCE_DIR) + "/assets/uterus_myoma.msh";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "no " << path;
  auto mesh = readTetMesh(path);
  ASSERT_TRUE(mesh.ok()) << mesh.error();
  double q = 0, e = 0;
  randomPlanes(*mesh, 40, {}, &q, &e);
  // Reported, not yet asserted (acceptance wants >= 0.25 and >= 0.2 for every plane).
  RecordProperty("worst_q_ratio", std::to_string(q));
  RecordProperty("worst_edge_ratio", std::to_string(e));
  std::printf("uterus, 40 random planes: worst q*_min ratio %.3f, worst min edge ratio %.3f\n", q, e);
}

// With feature nodes allowed to slide a short way along their feature edges at corners and
// bent ridges (moves the corner, so volume is kept to ~1e-4, not exactly; off by default).
// Measured 0.065 / 0.079 on these planes; asserted with margin as a regression check.
TEST(Cut3DAcceptance, UterusRandomPlanesFeatureSlide) {
  const std::string path = std::string(HYSIM_SOURCE_DIR) + "/assets/uterus_myoma.msh";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "no " << path;
  auto mesh = readTetMesh(path);
  ASSERT_TRUE(mesh.ok()) << mesh.error();
  Cut3DOptions o;
  o.feature_slide_fraction = 0.15;
  double q = 0, e = 0;
  randomPlanes(*mesh, 40, o, &q, &e);
  std::printf("uterus, 40 random planes, feature slide 0.15: worst q*_min ratio %.3f, worst min edge ratio %.3f\n", q, e);
  EXPECT_GE(q, 0.03);
  EXPECT_GE(e, 0.04);
}

TEST(Cut3DAcceptance, Table2EllipsoidHybridKeepsQuality) {
  auto mesh = readTetMesh(std::string(HYSIM_TEST_DATA_DIR) + "/cutting/table2_ellipsoid.msh");
  ASSERT_TRUE(mesh.ok()) << mesh.error();
  EXPECT_EQ(mesh->numTets(), 135);
  Cut3DOptions o;
  o.feature_angle_deg = 60.0;  // as in hysim tables --table 2 (a coarse curved boundary)
  const auto s0 = computeStats(*mesh);
  for (const auto& [p, n] : {std::pair{Vec3(0.5, 0.3, 0.2), Vec3(0.15, 0.1, 1.0)},
                             std::pair{Vec3(1.1, -0.7, 0.0), Vec3(1.0, 0.35, 0.2)}}) {
    auto r = cut3d(*mesh, *CutSurface::plane(p, n), o);
    ASSERT_TRUE(r.ok());
    ASSERT_TRUE(validate(r->mesh).ok());
    EXPECT_EQ(countStraddling(r->mesh, p, n, 1e-7), 0);
    const auto s = computeStats(r->mesh);
    EXPECT_LE(s.elements, 1.10 * s0.elements);
    EXPECT_GE(s.q_min, 0.25 * s0.q_min);
    EXPECT_GE(s.edge_min, 0.2 * s0.edge_min);
    EXPECT_GE(tetComponents(r->mesh).count, 2);
  }
}

}  // namespace
}  // namespace hysim::cutting
