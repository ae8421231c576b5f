// Numerical hard cases of 3D cutting: planes exactly through a node, along an edge, in a face
// plane and at the snap threshold +- epsilon, and 20 successive cuts, where the hybrid keeps
// the explicit critical step and standard subdivision loses it to slivers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "box_mesh.hpp"
#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/mesh_stats.hpp"
#include "hysim/sim/model.hpp"

namespace hysim::cutting {
namespace {

using Vec3 = Eigen::Vector3d;

// A cut result's health: valid, every tet of positive volume; returns its q*_min.
double checkedQuality(const TetMesh& mesh, const std::string& what) {
  const auto v = validate(mesh);
  EXPECT_TRUE(v.ok()) << what << ": " << v.error();
  double min_volume = 1e300;
  for (int t = 0; t < mesh.numTets(); ++t) min_volume = std::min(min_volume, tetVolume(mesh, t));
  EXPECT_GT(min_volume, 0.0) << what;
  return computeStats(mesh).q_min;
}

TetMesh cutPlane(const TetMesh& mesh, const Vec3& p, const Vec3& n, const Cut3DOptions& o, const std::string& what) {
  auto plane = CutSurface::plane(p, n);
  EXPECT_TRUE(plane.ok());
  auto r = cut3d(mesh, *plane, o);
  EXPECT_TRUE(r.ok()) << what << ": " << r.error();
  if (!r.ok()) return mesh;
  EXPECT_EQ(countStraddling(r->mesh, p, n, 1e-7), 0) << what;  // the cut separates
  return std::move(r->mesh);
}

// The q* floor below: the box's Kuhn tets have q* 0.23; a hybrid cut may lower it to its
// snapping guard (min_quality 0.08) but never to a sliver.
constexpr double kQualityFloor = 0.05;

// Degenerate placements: the cut contains a node, an edge, a whole face plane.
TEST(HardCuts, ThroughNodeAlongEdgeInFacePlaneStayValid) {
  const TetMesh box = testing::boxTetMesh(3, 3, 3, 1.0);
  const struct {
    const char* what;
    Vec3 p, n;
  } cuts[] = {{"through node", {1, 1, 1}, {1, 2, 3}},
              {"along edge", {1, 1, 0}, {1, 2, 0}},
              {"face plane", {0, 0, 1}, {0, 0, 1}},
              {"diagonal face plane", {0, 0, 0}, {1, -1, 0}}};
  for (const auto& c : cuts) {
    const TetMesh cut = cutPlane(box, c.p, c.n, {}, c.what);
    const double q = checkedQuality(cut, c.what);
    RecordProperty(std::string("q_min_") + c.what, std::to_string(q));
    EXPECT_GE(q, kQualityFloor) << c.what;
    EXPECT_GE(tetComponents(cut).count, 2) << c.what;
  }
}

// Crossings at the snap threshold (0.45 of the edge) +- epsilon, and just off a node (1e-12 is
// within the on-surface tolerance, the others cross): each side of every threshold is valid.
TEST(HardCuts, SnapThresholdAndNearNodePlusMinusEpsilon) {
  const TetMesh box = testing::boxTetMesh(3, 3, 3, 1.0);
  const Cut3DOptions o;
  double worst = 1.0;
  for (double base : {1.0 + o.snap_region, 1.0})
    for (double eps : {-1e-6, -1e-9, -1e-12, 1e-12, 1e-9, 1e-6, 1e-3}) {
      const std::string what = "z = " + std::to_string(base) + " + " + std::to_string(eps);
      // Horizontal: every vertical edge is crossed at the same fraction, box edges included.
      const TetMesh cut = cutPlane(box, Vec3(1.5, 1.5, base + eps), Vec3(0, 0, 1), o, what);
      const double q = checkedQuality(cut, what);
      worst = std::min(worst, q);
      EXPECT_GE(q, kQualityFloor) << what;
      EXPECT_EQ(tetComponents(cut).count, 2) << what;
    }
  RecordProperty("q_min_worst", std::to_string(worst));
}

// The model's critical explicit step (Van Gelder springs, E 60 kPa, no anchors, no mass scaling).
double criticalStep(const TetMesh& mesh) {
  sim::Material tissue;
  tissue.label = 1;
  sim::ModelOptions o;
  o.max_substeps = 0;  // mass scaling would hide the slivers
  auto model = sim::buildModel(mesh, {tissue}, {}, o);
  EXPECT_TRUE(model.ok()) << model.error();
  return model.ok() ? model->critical_dt : 0.0;
}

// 20 slightly tilted parallel planes 1.1 mm apart along a 3 x 3 x 24 mm bar of 1 mm cells:
// every slab stays thicker than a cell, but the tilt and the 1.1 mm spacing sweep the
// crossings along the edges, some within a hair of a node, where standard subdivision
// leaves slivers (the classic failure) and the hybrid snaps.
std::vector<std::pair<Vec3, Vec3>> parallelPlanes(int count) {
  std::vector<std::pair<Vec3, Vec3>> planes;
  for (int i = 0; i < count; ++i) planes.emplace_back(Vec3(1.5, 1.5, 1.1 + 1.1 * i), Vec3(0.05, 0.03, 1.0));
  return planes;
}

double criticalRatioAfterCuts(CutMethod method, const std::vector<std::pair<Vec3, Vec3>>& planes, double* q_min) {
  TetMesh mesh = testing::boxTetMesh(3, 3, 24, 1.0);
  const double initial = criticalStep(mesh);
  Cut3DOptions o;
  o.method = method;
  for (size_t i = 0; i < planes.size(); ++i)
    mesh = cutPlane(mesh, planes[i].first, planes[i].second, o, std::string(cutMethodName(method)) + " cut " + std::to_string(i));
  *q_min = checkedQuality(mesh, cutMethodName(method));
  return criticalStep(mesh) / initial;
}

// The hybrid keeps the critical step within a factor ~2 of the fresh bar's (snaps may shorten
// an edge to min_edge_fraction = 0.3 of its length and a Van Gelder spring stiffens as
// 1/|e|^2, so the 0.5 hoped for is not what the defaults give), while standard subdivision's
// drops below 0.1 (slivers from the first cut on). The gap between them is the point.
TEST(HardCuts, TwentyCutsKeepTheCriticalStepHybridButNotStandard) {
  const auto planes = parallelPlanes(20);
  double q_hybrid = 0, q_standard = 0;
  const double hybrid = criticalRatioAfterCuts(CutMethod::Hybrid, planes, &q_hybrid);
  const double standard = criticalRatioAfterCuts(CutMethod::Standard, planes, &q_standard);
  RecordProperty("critical_dt_ratio_hybrid", std::to_string(hybrid));
  RecordProperty("critical_dt_ratio_standard", std::to_string(standard));
  RecordProperty("q_min_hybrid", std::to_string(q_hybrid));
  RecordProperty("q_min_standard", std::to_string(q_standard));
  EXPECT_GE(hybrid, 0.4);
  EXPECT_LT(standard, 0.1);
  EXPECT_GT(hybrid, 10.0 * standard);
  EXPECT_GE(q_hybrid, kQualityFloor);
}

}  // namespace
}  // namespace hysim::cutting
