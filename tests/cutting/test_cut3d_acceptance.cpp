// Acceptance checks of issue 4 over many random planes through quality meshes (the uterus
// mesh, the Table 2 Gmsh ellipsoid). With exact plane cuts (the default) a few planes passing
// within a few percent of an edge of a boundary corner node stay below q*_min >= 0.25x and
// min edge >= 0.2x; with through-node routing every plane here meets both (asserted). The 20
// successive cuts are measured by `hysim tables --table 2`.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <random>

#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/mesh_io.hpp"
#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::cutting {
namespace {

using Vec3 = Eigen::Vector3d;

void randomPlanes(const TetMesh& mesh, int planes, const Cut3DOptions& options, double* worstQ, double* worstE,
                  int* routed, double* deviation) {
  const auto s0 = computeStats(mesh);
  double edgeMax = 0;
  for (int t = 0; t < mesh.numTets(); ++t)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b)
        edgeMax = std::max(edgeMax, (mesh.X.row(mesh.T(t, a)) - mesh.X.row(mesh.T(t, b))).norm());
  const double v0 = totalVolume(mesh);
  const Vec3 lo = mesh.X.colwise().minCoeff().transpose(), hi = mesh.X.colwise().maxCoeff().transpose();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.3, 0.7), g(-1, 1);
  *worstQ = *worstE = 1e300;
  *routed = 0;
  *deviation = 0;
  for (int p = 0; p < planes; ++p) {
    const Vec3 c = lo + (hi - lo).cwiseProduct(Vec3(u(rng), u(rng), u(rng)));
    const Vec3 n(g(rng), g(rng), g(rng));
    auto r = cut3d(mesh, *CutSurface::plane(c, n), options);
    ASSERT_TRUE(r.ok()) << r.error();
    const auto v = validate(r->mesh);
    ASSERT_TRUE(v.ok()) << "plane " << p << ": " << v.error();
    // Exact sides, or within the routed nodes' distance (Cut3DOptions::through_node_fraction).
    if (options.through_node_fraction == 0) {
      EXPECT_EQ(r->report.routed_nodes, 0);
    }
    const double eps = std::max(1e-7, r->report.max_route_deviation_mm * (1 + 1e-9));
    EXPECT_LE(r->report.max_route_deviation_mm, options.through_node_fraction * edgeMax) << "plane " << p;
    EXPECT_EQ(countStraddling(r->mesh, c, n, eps), 0) << "plane " << p;
    EXPECT_EQ(countFacesSharedAcross(r->mesh, c, n, eps), 0) << "plane " << p;
    *routed += r->report.routed_nodes;
    *deviation = std::max(*deviation, r->report.max_route_deviation_mm);
    EXPECT_LE(r->mesh.numTets(), 1.10 * mesh.numTets()) << "plane " << p;
    EXPECT_NEAR(totalVolume(r->mesh), v0, 1e-5 * v0) << "plane " << p;
    for (int t = 0; t < r->mesh.numTets(); ++t) ASSERT_GT(tetVolume(r->mesh, t), 0.0);
    const auto s = computeStats(r->mesh);
    *worstQ = std::min(*worstQ, s.q_min / s0.q_min);
    *worstE = std::min(*worstE, s.edge_min / s0.edge_min);
  }
}

TEST(Cut3DAcceptance, UterusRandomPlanesValidGrowthVolume) {
  const std::string path = std::string(HYSIM_SOURCE_DIR) + "/assets/uterus_myoma.msh";
  ASSERT_TRUE(std::filesystem::exists(path)) << "missing " << path << ", an asset shipped in the repository";
  auto mesh = readTetMesh(path);
  ASSERT_TRUE(mesh.ok()) << mesh.error();
  double q = 0, e = 0, dev = 0;
  int routed = 0;
  randomPlanes(*mesh, 40, {}, &q, &e, &routed, &dev);
  RecordProperty("worst_q_ratio", std::to_string(q));
  RecordProperty("worst_edge_ratio", std::to_string(e));
  std::printf("uterus, 40 random planes: worst q*_min ratio %.3f, worst min edge ratio %.3f\n", q, e);
  // Measured 0.243 / 0.120 on these planes; regression floors.
  EXPECT_GE(q, 0.2);
  EXPECT_GE(e, 0.1);
}

// Without feature sliding (corners and bent ridges stay where they are; on by default).
TEST(Cut3DAcceptance, UterusRandomPlanesNoFeatureSlide) {
  const std::string path = std::string(HYSIM_SOURCE_DIR) + "/assets/uterus_myoma.msh";
  ASSERT_TRUE(std::filesystem::exists(path)) << "missing " << path << ", an asset shipped in the repository";
  auto mesh = readTetMesh(path);
  ASSERT_TRUE(mesh.ok()) << mesh.error();
  Cut3DOptions o;
  o.feature_slide_fraction = 0.0;
  double q = 0, e = 0, dev = 0;
  int routed = 0;
  randomPlanes(*mesh, 40, o, &q, &e, &routed, &dev);
  std::printf("uterus, 40 random planes, no feature slide: worst q*_min ratio %.3f, worst min edge ratio %.3f\n", q, e);
  EXPECT_GE(q, 0.03);
  EXPECT_GE(e, 0.04);
}

// Through-node routing as a last resort (crossings still within 0.1 |e| of a node after
// snapping, the away move and ridge/feature sliding were refused) together with feature
// sliding: elements around a routed node straddle the plane by at most its distance, checked
// with that tolerance. Measured 0.753 / 0.470 on these planes (0.45 / 0.33 and 0.34 / 0.38
// worst over 100 planes with seeds 7 / 11; routed nodes <= 0.41 mm off the plane).
TEST(Cut3DAcceptance, UterusRandomPlanesRoutingAndFeatureSlide) {
  const std::string path = std::string(HYSIM_SOURCE_DIR) + "/assets/uterus_myoma.msh";
  ASSERT_TRUE(std::filesystem::exists(path)) << "missing " << path << ", an asset shipped in the repository";
  auto mesh = readTetMesh(path);
  ASSERT_TRUE(mesh.ok()) << mesh.error();
  Cut3DOptions o;
  o.through_node_fraction = 0.1;
  o.feature_slide_fraction = 0.15;
  double q = 0, e = 0, dev = 0;
  int routed = 0;
  randomPlanes(*mesh, 40, o, &q, &e, &routed, &dev);
  std::printf("uterus, 40 random planes, routing 0.1 + feature slide 0.15: worst q*_min ratio %.3f, worst min edge "
              "ratio %.3f, %d routed nodes, max deviation %.3f mm\n",
              q, e, routed, dev);
  EXPECT_GE(e, 0.2);   // the acceptance bounds
  EXPECT_GE(q, 0.25);
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
