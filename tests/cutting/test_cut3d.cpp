// 3D cutting: the hybrid cases, the baselines, the hard numerical cases and randomized cuts,
// each result checked by validate(), side separation, volume and the TopologyChange.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <random>

#include "box_mesh.hpp"
#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/mesh_io.hpp"
#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::cutting {
namespace {

using Vec3 = Eigen::Vector3d;

using testing::singleTet;

Cut3DOptions withMethod(CutMethod method) {
  Cut3DOptions o;
  o.method = method;
  return o;
}

// Checks every invariant of a plane cut; returns the result.
Cut3DResult cutAndCheck(const TetMesh& mesh, const Vec3& p, const Vec3& n, const Cut3DOptions& options,
                        double volumeTol = 1e-9) {
  auto plane = CutSurface::plane(p, n);
  EXPECT_TRUE(plane.ok());
  auto r = cut3d(mesh, *plane, options);
  EXPECT_TRUE(r.ok()) << r.error();
  if (!r.ok()) return {};
  const auto v = validate(r->mesh);
  EXPECT_TRUE(v.ok()) << v.error();
  // Exact side checks, except that with through-node routing the elements around a routed
  // node may straddle the plane by that node's distance (see Cut3DOptions::through_node_fraction).
  if (options.through_node_fraction == 0) {
    EXPECT_EQ(r->report.routed_nodes, 0);
  }
  if (r->report.routed_nodes == 0) {
    EXPECT_EQ(r->report.max_route_deviation_mm, 0.0);
  }
  const double eps = std::max(1e-7, r->report.max_route_deviation_mm * (1 + 1e-9));
  EXPECT_EQ(countStraddling(r->mesh, p, n, eps), 0);
  EXPECT_EQ(countFacesSharedAcross(r->mesh, p, n, eps), 0);
  const double v0 = totalVolume(mesh);
  if (options.method != CutMethod::Delete) {
    EXPECT_NEAR(totalVolume(r->mesh), v0, volumeTol * std::abs(v0));
  }
  // TopologyChange consistency.
  const auto& c = r->change;
  EXPECT_EQ(c.old_num_nodes, mesh.numNodes());
  EXPECT_EQ(c.old_num_elements, mesh.numTets());
  EXPECT_EQ(c.new_num_nodes, r->mesh.numNodes());
  EXPECT_EQ(c.new_num_elements, r->mesh.numTets());
  EXPECT_EQ(static_cast<int>(c.node_old_to_new.size()), mesh.numNodes());
  EXPECT_EQ(static_cast<int>(c.element_old_to_new.size()), mesh.numTets());
  for (size_t i = 1; i < c.new_nodes.size(); ++i) EXPECT_LT(c.new_nodes[i - 1].id, c.new_nodes[i].id);
  for (const auto& nn : c.new_nodes) {
    double sum = 0;
    for (int k = 0; k < nn.num_parents; ++k) {
      EXPECT_GE(nn.parents[k], 0);
      EXPECT_LT(nn.parents[k], mesh.numNodes());
      sum += nn.weights[k];
    }
    EXPECT_NEAR(sum, 1.0, 1e-12);
  }
  int removed = 0;
  for (int t = 0; t < mesh.numTets(); ++t) removed += c.element_old_to_new[t] < 0;
  EXPECT_EQ(removed, static_cast<int>(c.removed_elements.size()));
  EXPECT_EQ(r->mesh.numTets(), mesh.numTets() - removed + static_cast<int>(c.added_elements.size()));
  return std::move(r).value();
}

int components(const TetMesh& m) { return tetComponents(m).count; }

// --- single tet: the subdivision patterns -------------------------------------------------

TEST(Cut3D, SingleTetOneThreeSplitStandard) {
  const TetMesh m = singleTet();
  const auto r = cutAndCheck(m, Vec3(0.5, 0, 0), Vec3(1, 1, 1), withMethod(CutMethod::Standard));
  EXPECT_EQ(r.report.split_edges, 3);
  EXPECT_EQ(r.mesh.numTets(), 4);          // 1 on the node's side + 3 (prism)
  EXPECT_EQ(r.report.duplicated_nodes, 3); // the cut triangle, one copy per side
  EXPECT_EQ(r.mesh.numNodes(), 10);
  EXPECT_EQ(components(r.mesh), 2);
  EXPECT_EQ(r.change.cut_faces.size(), 2u);
  EXPECT_EQ(r.change.removed_elements, std::vector<std::int32_t>{0});
  EXPECT_EQ(r.change.added_elements.size(), 4u);
}

TEST(Cut3D, SingleTetTwoTwoSplitStandard) {
  const TetMesh m = singleTet();
  // Nodes 0, 3 (x + y small) against 1, 2.
  const auto r = cutAndCheck(m, Vec3(0.5, 0, 0), Vec3(1, 1, 0), withMethod(CutMethod::Standard));
  EXPECT_EQ(r.report.split_edges, 4);
  EXPECT_EQ(r.mesh.numTets(), 6);
  EXPECT_EQ(r.report.duplicated_nodes, 4);
  EXPECT_EQ(components(r.mesh), 2);
}

TEST(Cut3D, SingleTetThroughOneNodeSplitsOppositeEdgesOnly) {
  const TetMesh m = singleTet();
  // Plane through node 0 separating node 1 from nodes 2, 3: a cut through a node.
  const auto r = cutAndCheck(m, Vec3(0, 0, 0), Vec3(1, -1, -1), withMethod(CutMethod::Standard));
  EXPECT_EQ(r.report.split_edges, 2);   // edges 1-2 and 1-3
  EXPECT_EQ(r.mesh.numTets(), 3);
  EXPECT_EQ(components(r.mesh), 2);
}

TEST(Cut3D, SingleTetThroughEdgeSplitsOneEdge) {
  const TetMesh m = singleTet();
  // Plane containing edge 0-3 (the z axis), separating node 1 from node 2.
  const auto r = cutAndCheck(m, Vec3(0, 0, 0), Vec3(1, -1, 0), withMethod(CutMethod::Standard));
  EXPECT_EQ(r.report.split_edges, 1);
  EXPECT_EQ(r.mesh.numTets(), 2);
  EXPECT_EQ(r.report.duplicated_nodes, 3);
  EXPECT_EQ(components(r.mesh), 2);
}

TEST(Cut3D, SingleTetFacePlaneAndBoundaryIsNoOp) {
  const TetMesh m = singleTet();
  for (CutMethod method : {CutMethod::Hybrid, CutMethod::Standard, CutMethod::Snap, CutMethod::Delete}) {
    const auto r = cutAndCheck(m, Vec3(0, 0, 0), Vec3(0, 0, 1), withMethod(method));
    EXPECT_EQ(r.mesh.numTets(), 1);
    EXPECT_EQ(r.mesh.numNodes(), 4);
    EXPECT_TRUE(r.change.new_nodes.empty());
    EXPECT_EQ(r.mesh.X, m.X);
  }
}

TEST(Cut3D, DeleteRemovesCrossedTet) {
  const TetMesh box = testing::boxTetMesh(2, 2, 2, 1.0);
  const auto r = cutAndCheck(box, Vec3(0, 0, 1.5), Vec3(0, 0, 1), withMethod(CutMethod::Delete));
  EXPECT_EQ(r.mesh.numTets(), 48 - 24);
  EXPECT_EQ(r.report.deleted_elements, 24);
  EXPECT_EQ(components(r.mesh), 1);
  EXPECT_TRUE(validate(r.mesh, {.requireAllNodesUsed = true}).ok());
}

// --- the four hybrid cases (0..3 nodes of a tet separated) on a box ------------------------

TEST(Cut3D, HybridNearNodesSnapsInsteadOfSubdividing) {
  const TetMesh box = testing::boxTetMesh(2, 2, 2, 1.0);
  auto o = withMethod(CutMethod::Hybrid);
  o.optimize.enabled = false;
  const auto r = cutAndCheck(box, Vec3(0, 0, 1.1), Vec3(0, 0, 1), o);
  // The interior node and the four face-centre nodes at z = 1 slide up; the four nodes on the
  // box's vertical edges are on straight ridges and slide up along them (still on the ridge,
  // volume exact), so nothing is subdivided.
  EXPECT_EQ(r.report.snapped_nodes, 9);
  EXPECT_EQ(r.report.boundary_snaps, 8);
  EXPECT_EQ(r.report.ridge_snaps, 4);
  EXPECT_EQ(r.report.split_edges, 0);
  EXPECT_EQ(components(r.mesh), 2);
  // Tets whose three nodes were snapped have a face in the cut: three nodes separated.
  EXPECT_GT(r.report.cut_faces, 0);
  const auto s0 = computeStats(box), s1 = computeStats(r.mesh);
  EXPECT_LE(s1.elements, s0.elements * 1.5);
}

TEST(Cut3D, HybridInteriorPlaneCutFourCases) {
  // A finer box: the plane at z = 2.2 crosses edges at t = 0.2 from the z = 2 nodes.
  const TetMesh box = testing::boxTetMesh(4, 4, 4, 1.0);
  auto o = withMethod(CutMethod::Hybrid);
  o.optimize.enabled = false;
  const auto r = cutAndCheck(box, Vec3(0, 0, 2.2), Vec3(0, 0, 1), o);
  EXPECT_GE(r.report.snapped_nodes, 9);   // at least the 3x3 interior nodes
  EXPECT_EQ(components(r.mesh), 2);
  // Only the feature nodes (box edges) subdivide.
  EXPECT_LE(r.mesh.numTets(), box.numTets() * 1.1);
}

TEST(Cut3D, HybridTiltedPlaneAllCasesValid) {
  const TetMesh box = testing::boxTetMesh(4, 4, 4, 1.0);
  const auto r = cutAndCheck(box, Vec3(2.1, 2.0, 1.9), Vec3(0.3, 0.2, 1.0), withMethod(CutMethod::Hybrid), 1e-9);
  EXPECT_GT(r.report.snapped_nodes, 0);
  EXPECT_GT(r.report.split_edges, 0);
  EXPECT_EQ(components(r.mesh), 2);
}

TEST(Cut3D, SnapThresholdPlusMinusEpsilon) {
  const TetMesh box = testing::boxTetMesh(2, 2, 2, 1.0);
  auto o = withMethod(CutMethod::Hybrid);
  o.snap_region = 0.3;
  o.optimize.enabled = false;
  const auto below = cutAndCheck(box, Vec3(0, 0, 1.3 - 1e-6), Vec3(0, 0, 1), o);
  const auto above = cutAndCheck(box, Vec3(0, 0, 1.3 + 1e-6), Vec3(0, 0, 1), o);
  EXPECT_GT(below.report.snapped_nodes, 0);
  EXPECT_EQ(above.report.snapped_nodes, 0);
  EXPECT_EQ(above.report.split_edges, above.report.crossed_edges);
}

TEST(Cut3D, InFacePlaneSeparatesWithoutNewElements) {
  const TetMesh box = testing::boxTetMesh(2, 2, 2, 1.0);
  for (CutMethod method : {CutMethod::Hybrid, CutMethod::Standard, CutMethod::Snap}) {
    const auto r = cutAndCheck(box, Vec3(0, 0, 1), Vec3(0, 0, 1), withMethod(method));
    EXPECT_EQ(r.mesh.numTets(), box.numTets());
    EXPECT_EQ(r.report.duplicated_nodes, 9);
    EXPECT_EQ(components(r.mesh), 2);
  }
  // x = y is a union of Kuhn faces too.
  const auto d = cutAndCheck(box, Vec3(0, 0, 0), Vec3(1, -1, 0), withMethod(CutMethod::Standard));
  EXPECT_EQ(d.mesh.numTets(), box.numTets());
  EXPECT_EQ(components(d.mesh), 2);
}

TEST(Cut3D, ThroughNodeAndAlongEdge) {
  const TetMesh box = testing::boxTetMesh(3, 3, 3, 1.0);
  for (CutMethod method : {CutMethod::Hybrid, CutMethod::Standard, CutMethod::Snap, CutMethod::Delete}) {
    // Through node (1,1,1), general direction.
    cutAndCheck(box, Vec3(1, 1, 1), Vec3(1, 2, 3), withMethod(method), 1e-9);
    // Along the vertical edges at x = y = 1 without containing a face.
    const auto r = cutAndCheck(box, Vec3(1, 1, 0), Vec3(1, 2, 0), withMethod(method), 1e-9);
    if (method != CutMethod::Delete) {
      EXPECT_EQ(components(r.mesh), 2);
    }
  }
}

TEST(Cut3D, RepeatedCutAtSamePlaceIsNoOp) {
  const TetMesh box = testing::boxTetMesh(3, 3, 3, 1.0);
  for (CutMethod method : {CutMethod::Hybrid, CutMethod::Standard}) {
    const auto a = cutAndCheck(box, Vec3(0, 0, 1.5), Vec3(0.1, 0, 1), withMethod(method));
    const auto b = cutAndCheck(a.mesh, Vec3(0, 0, 1.5), Vec3(0.1, 0, 1), withMethod(method));
    EXPECT_EQ(b.mesh.numTets(), a.mesh.numTets());
    EXPECT_EQ(b.mesh.numNodes(), a.mesh.numNodes());
    EXPECT_TRUE(b.change.new_nodes.empty());
  }
}

// The first cut keeps the box's volume exactly (its moves and snaps stay in flat faces); the
// later ones cross the earlier cuts' faces, where the cut's snaps sliding along ridges
// (feature_slide_fraction) and the optimisation's late snaps and collapses (within its
// volume_budget, 5e-4 of the mesh per cut) may change it: here up to 6.3e-5 per cut, 6.7e-5
// in all (1e-4 allowed; the acceptance for plane cuts: 0.1%).
TEST(Cut3D, SuccessiveParallelCuts) {
  TetMesh m = testing::boxTetMesh(4, 4, 4, 1.0);
  const double v0 = totalVolume(m);
  for (int i = 0; i < 6; ++i) {
    const auto r = cutAndCheck(m, Vec3(0, 0, 0.37 + 0.55 * i), Vec3(0.05, 0.02, 1), withMethod(CutMethod::Hybrid),
                               i == 0 ? 1e-9 : 1e-4);
    m = r.mesh;
  }
  EXPECT_NEAR(totalVolume(m), v0, 1e-4 * v0);
  EXPECT_GE(components(m), 5);
}

TEST(Cut3D, StandardSplitNodesInterpolateParents) {
  const TetMesh box = testing::boxTetMesh(3, 3, 3, 1.0);
  const auto r = cutAndCheck(box, Vec3(1.3, 1.4, 1.5), Vec3(1, 0.4, 0.7), withMethod(CutMethod::Standard));
  for (const auto& nn : r.change.new_nodes) {
    Vec3 x = Vec3::Zero();
    for (int k = 0; k < nn.num_parents; ++k) x += nn.weights[k] * box.X.row(nn.parents[k]).transpose();
    EXPECT_LT((x - r.mesh.X.row(nn.id).transpose()).norm(), 1e-12);
  }
  // Every cut face has a twin with the same positions, opposite orientation.
  EXPECT_EQ(r.change.cut_faces.size() % 2, 0u);
  EXPECT_EQ(static_cast<int>(r.change.cut_faces.size()), 2 * r.report.cut_faces);
}

TEST(Cut3D, RandomizedPlanesAllMethods) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const TetMesh meshes[] = {testing::boxTetMesh(3, 3, 3, 1.0), testing::boxTetMesh(5, 3, 4, 0.7)};
  for (const auto& mesh : meshes) {
    const Vec3 lo = mesh.X.colwise().minCoeff().transpose(), hi = mesh.X.colwise().maxCoeff().transpose();
    for (int trial = 0; trial < 12; ++trial) {
      const Vec3 p = 0.5 * (lo + hi) + 0.3 * Vec3(u(rng), u(rng), u(rng)).cwiseProduct(hi - lo);
      const Vec3 n(u(rng), u(rng), u(rng));
      for (CutMethod method : {CutMethod::Hybrid, CutMethod::Standard, CutMethod::Snap, CutMethod::Delete}) {
        SCOPED_TRACE(std::string(cutMethodName(method)) + " trial " + std::to_string(trial));
        // Hybrid peels slivers and collapses edges on the cut: volume within 0.1%.
        const auto r = cutAndCheck(mesh, p, n, withMethod(method), method == CutMethod::Hybrid ? 1e-3 : 1e-9);
        if (method == CutMethod::Standard) {
          EXPECT_EQ(r.report.split_edges, r.report.crossed_edges);
        }
      }
      // Hybrid with through-node routing and feature sliding (box corners are corners of flat
      // facets and never slide; the optimisation's peeling and collapses change the volume).
      SCOPED_TRACE("hybrid, routing + feature slide, trial " + std::to_string(trial));
      Cut3DOptions o;
      o.through_node_fraction = 0.1;
      o.feature_slide_fraction = 0.15;
      cutAndCheck(mesh, p, n, o, 1e-3);
      // Without the optimisation the hybrid cut keeps a flat-sided mesh's volume exactly.
      o.optimize.enabled = false;
      cutAndCheck(mesh, p, n, o, 1e-9);
    }
  }
}

// The report's volume kept: the input's and output's volumes, per material and in all, and
// their difference; a flat-sided box cut by planes without the optimisation loses nothing.
TEST(Cut3D, ReportsTheVolumeKept) {
  TetMesh box = testing::boxTetMesh(5, 3, 4, 0.7);
  for (int t = 0; t < box.numTets(); ++t) {  // two materials: the tets left and right of x = 1.4
    double x = 0;
    for (int k = 0; k < 4; ++k) x += 0.25 * box.X(box.T(t, k), 0);
    box.material(t) = x < 1.4 ? 3 : 7;
  }
  auto labelVolume = [](const TetMesh& m, int label) {
    double v = 0;
    for (int t = 0; t < m.numTets(); ++t) v += m.material(t) == label ? tetVolume(m, t) : 0.0;
    return v;
  };
  const double v0 = totalVolume(box);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 8; ++trial) {
    SCOPED_TRACE(trial);
    const Vec3 p(1.75 + 0.5 * u(rng), 1.05 + 0.3 * u(rng), 1.4 + 0.4 * u(rng)), n(u(rng), u(rng), u(rng));
    for (const bool optimise : {false, true}) {
      Cut3DOptions o;
      o.optimize.enabled = optimise;
      const auto r = cut3d(box, *CutSurface::plane(p, n), o);
      ASSERT_TRUE(r.ok()) << r.error();
      const Cut3DReport& rep = r->report;
      EXPECT_NEAR(rep.volume_before, v0, 1e-12 * v0);
      EXPECT_NEAR(rep.volume_after, totalVolume(r->mesh), 1e-12 * v0);
      EXPECT_DOUBLE_EQ(rep.volume_drift, rep.volume_before - rep.volume_after);
      ASSERT_EQ(rep.material_volumes.size(), 2u);
      double drift = 0;
      for (const MaterialVolume& m : rep.material_volumes) {
        EXPECT_NEAR(m.before, labelVolume(box, m.label), 1e-12 * v0);
        EXPECT_NEAR(m.after, labelVolume(r->mesh, m.label), 1e-12 * v0);
        drift += m.drift();
      }
      EXPECT_EQ(rep.material_volumes[0].label, 3);
      EXPECT_EQ(rep.material_volumes[1].label, 7);
      EXPECT_NEAR(drift, rep.volume_drift, 1e-12 * v0);
      // Snapping keeps the total (it may move the interface between the materials); the
      // optimisation makes up for what it and the snaps changed, per material.
      EXPECT_LE(std::abs(rep.volume_drift), (optimise ? 1e-5 : 1e-9) * v0);
      if (optimise) {
        for (const MaterialVolume& m : rep.material_volumes) EXPECT_LE(std::abs(m.drift()), 1e-5 * v0) << m.label;
      }
    }
  }
}

// --- triangulated cut surfaces -----------------------------------------------------------

// A strip of a cylinder (axis along y, radius R, centred at c), the loop's swept surface.
CutSurface cylinderStrip(const Vec3& c, double radius, double angle0, double angle1, double y0, double y1, int nu,
                         int nv) {
  Positions X((nu + 1) * (nv + 1), 3);
  Tris F(2 * nu * nv, 3);
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) {
      const double a = angle0 + (angle1 - angle0) * i / nu;
      X.row(j * (nu + 1) + i) << c.x() + radius * std::cos(a), y0 + (y1 - y0) * j / nv, c.z() + radius * std::sin(a);
    }
  int f = 0;
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const int v00 = j * (nu + 1) + i, v10 = v00 + 1, v01 = v00 + nu + 1, v11 = v01 + 1;
      F.row(f++) << v00, v10, v11;
      F.row(f++) << v00, v11, v01;
    }
  return *CutSurface::triangles(X, F);
}

TEST(Cut3D, CurvedSurfaceFullCutSeparatesPiece) {
  const TetMesh box = testing::boxTetMesh(6, 6, 6, 1.0 / 6);
  // Cylinder of radius 0.5 around (0.5, y, 1.05): a scoop off the top, all the way through y.
  const CutSurface s = cylinderStrip(Vec3(0.5, 0, 1.05), 0.5, M_PI * 0.95, M_PI * 2.05, -0.1, 1.1, 40, 4);
  for (CutMethod method : {CutMethod::Hybrid, CutMethod::Standard, CutMethod::Snap, CutMethod::Delete}) {
    SCOPED_TRACE(cutMethodName(method));
    auto r = cut3d(box, s, withMethod(method));
    ASSERT_TRUE(r.ok()) << r.error();
    const auto v = validate(r->mesh);
    EXPECT_TRUE(v.ok()) << v.error();
    if (method != CutMethod::Delete) {
      EXPECT_NEAR(totalVolume(r->mesh), 1.0, method == CutMethod::Hybrid ? 1e-3 : 1e-6);
      EXPECT_EQ(components(r->mesh), 2);
    }
    // No tet has nodes clearly inside and clearly outside the cylinder (within the strip).
    int straddling = 0;
    for (int t = 0; t < r->mesh.numTets(); ++t) {
      bool in = false, outside = false;
      for (int k = 0; k < 4; ++k) {
        const Vec3 x = r->mesh.X.row(r->mesh.T(t, k)).transpose();
        const double d = std::hypot(x.x() - 0.5, x.z() - 1.05) - 0.5;
        in = in || d < -1e-3;
        outside = outside || d > 1e-3;
      }
      straddling += in && outside;
    }
    EXPECT_EQ(straddling, 0);
  }
}

// Point i of a deterministic low-discrepancy set over the test strip's box and around it.
Vec3 pointAroundStrip(int i) {
  return Vec3(-0.2 + 1.4 * std::fmod(i * 0.6180339887, 1.0), -0.3 + 1.6 * std::fmod(i * 0.7548776662, 1.0),
              0.3 + 1.0 * std::fmod(i * 0.5698402910, 1.0));
}

// CutSurface::within answers |signedDistance| <= r; mayTouch rules out boxes that meet the
// surface's bounding box but no part of the surface (the inside of a curved strip).
TEST(Cut3D, SurfaceWithinAndMayTouch) {
  const CutSurface s = cylinderStrip(Vec3(0.5, 0, 1.05), 0.5, M_PI * 0.95, M_PI * 2.05, -0.1, 1.1, 40, 4);
  int near = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3 x = pointAroundStrip(i);
    for (double r : {1e-3, 0.05, 0.3}) {
      const bool expect = std::abs(s.signedDistance(x)) <= r;
      EXPECT_EQ(s.within(x, r), expect) << x.transpose() << " r " << r;
      near += expect;
    }
    // A point's own box touches the surface iff the point is within eps of it (up to the
    // leaf boxes being larger than their triangles: mayTouch may say yes, never wrongly no).
    const Eigen::AlignedBox3d box(x, x);
    if (std::abs(s.signedDistance(x)) <= 0.05) {
      EXPECT_TRUE(s.mayTouch(box, 0.05));
    }
  }
  EXPECT_GT(near, 100);
  // The axis of the cylinder lies inside the strip's bounding box, 0.5 from every triangle.
  const Eigen::AlignedBox3d axis(Vec3(0.45, 0.2, 1.0), Vec3(0.55, 0.8, 1.1));
  EXPECT_TRUE(s.bounds().intersects(axis));
  EXPECT_FALSE(s.mayTouch(axis, 1e-6));
  EXPECT_FALSE(s.within(Vec3(0.5, 0.5, 1.05), 0.4));
  EXPECT_TRUE(s.within(Vec3(0.5, 0.5, 1.05), 0.5 + 1e-9));
  // Planes: within is |signed distance| <= r.
  const CutSurface p = *CutSurface::plane(Vec3(0, 0, 1), Vec3(0, 0, 1));
  EXPECT_TRUE(p.within(Vec3(3, 4, 1.2), 0.2 + 1e-12));
  EXPECT_FALSE(p.within(Vec3(3, 4, 0.7), 0.2));
}

// CutSurface::signedDistanceNear gives signedDistance's value and nearest point, bit for bit,
// whatever the bound: a bound at or above the distance (the bounded search), below it (the
// full search after all), or infinite.
TEST(Cut3D, SurfaceSignedDistanceNearIsSignedDistance) {
  const CutSurface s = cylinderStrip(Vec3(0.5, 0, 1.05), 0.5, M_PI * 0.95, M_PI * 2.05, -0.1, 1.1, 40, 4);
  int bounded = 0;
  for (int i = 0; i < 1000; ++i) {
    const Vec3 x = pointAroundStrip(i);
    Vec3 c;
    const double d = s.signedDistance(x, &c);
    for (double r : {0.0, 0.5 * std::abs(d), std::abs(d), std::abs(d) + 1e-3, 2.0 * std::abs(d) + 0.1,
                     std::numeric_limits<double>::infinity()}) {
      Vec3 cn;
      const double dn = s.signedDistanceNear(x, r, &cn);
      EXPECT_EQ(dn, d) << x.transpose() << " r " << r;
      EXPECT_EQ(cn, c) << x.transpose() << " r " << r;
      bounded += r >= std::abs(d);
    }
  }
  EXPECT_GT(bounded, 3000);
  // Planes: the signed distance and the foot point, whatever r.
  const CutSurface p = *CutSurface::plane(Vec3(0, 0, 1), Vec3(0, 0, 1));
  Vec3 c;
  EXPECT_DOUBLE_EQ(p.signedDistanceNear(Vec3(3, 4, 0.7), 0.01, &c), -0.3);
  EXPECT_TRUE(c.isApprox(Vec3(3, 4, 1)));
}

// The surface's tree (built once per surface from per-triangle boxes and keys) answers as a
// walk over every triangle would: the nearest distance, and the nearest crossing of a segment
// by the documented predicate (both ends off the triangle's plane by more than eps on
// opposite sides, the crossing inside the triangle with a 1e-12 relative slack).
TEST(Cut3D, SurfaceTreeQueriesMatchBruteForce) {
  // A wavy strip of 2 x 48 x 9 triangles (a deep tree), plus a degenerate triangle.
  const int nu = 48, nv = 9;
  Positions X((nu + 1) * (nv + 1) + 1, 3);
  std::vector<std::array<int, 3>> tris;
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i)
      X.row(j * (nu + 1) + i) << 1.2 * i / nu - 0.1, 1.2 * j / nv - 0.1,
          0.5 + 0.15 * std::sin(7.0 * i / nu) * std::cos(3.0 * j / nv) + 0.01 * std::fmod(i * 0.618 + j * 0.754, 1.0);
  X.row((nu + 1) * (nv + 1)) = X.row(0);
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const int v00 = j * (nu + 1) + i, v10 = v00 + 1, v01 = v00 + nu + 1, v11 = v01 + 1;
      tris.push_back({v00, v10, v11});
      tris.push_back({v00, v11, v01});
    }
  tris.push_back({0, (nu + 1) * (nv + 1), 1});  // degenerate: dropped
  Tris F(static_cast<Eigen::Index>(tris.size()), 3);
  for (size_t f = 0; f < tris.size(); ++f) F.row(static_cast<Eigen::Index>(f)) << tris[f][0], tris[f][1], tris[f][2];
  const CutSurface s = *CutSurface::triangles(X, F);
  ASSERT_EQ(s.numTriangles(), 2 * nu * nv);
  auto corner = [&](int f, int k) -> Vec3 { return X.row(tris[f][k]).transpose(); };
  for (int i = 0; i < 600; ++i) {
    const Vec3 x = pointAroundStrip(i);
    double best = std::numeric_limits<double>::infinity();
    for (int f = 0; f < 2 * nu * nv; ++f)
      best = std::min(best, (closestPointOnTriangle(x, corner(f, 0), corner(f, 1), corner(f, 2)) - x).squaredNorm());
    EXPECT_EQ(std::abs(s.signedDistance(x)), std::sqrt(best)) << x.transpose();
  }
  const double eps = 1e-9;
  int hits = 0;
  for (int i = 0; i < 600; ++i) {
    const Vec3 a = pointAroundStrip(i), b = pointAroundStrip(i + 7919) + Vec3(0, 0, 0.3 * ((i % 3) - 1));
    double bestT = 2.0;
    for (int f = 0; f < 2 * nu * nv; ++f) {
      const Vec3 p0 = corner(f, 0), p1 = corner(f, 1), p2 = corner(f, 2);
      const Vec3 n = (p1 - p0).cross(p2 - p0).normalized();
      const double da = n.dot(a - p0), db = n.dot(b - p0);
      if (!((da > eps && db < -eps) || (da < -eps && db > eps))) continue;
      const double t = da / (da - db);
      const Vec3 p = a + t * (b - a);
      const double slack = -1e-12 * n.dot((p1 - p0).cross(p2 - p0));
      if (n.dot((p1 - p).cross(p2 - p)) < slack || n.dot((p2 - p).cross(p0 - p)) < slack ||
          n.dot((p0 - p).cross(p1 - p)) < slack)
        continue;
      bestT = std::min(bestT, t);
    }
    CutSurface::Hit hit;
    const bool found = s.intersectSegment(a, b, eps, &hit);
    EXPECT_EQ(found, bestT < 2.0) << a.transpose() << " / " << b.transpose();
    if (found && bestT < 2.0) {
      EXPECT_EQ(hit.t, bestT);
    }
    hits += found;
  }
  EXPECT_GT(hits, 100);
}

TEST(Cut3D, PartialCutStaysConnectedAndValid) {
  const TetMesh box = testing::boxTetMesh(6, 6, 6, 1.0 / 6);
  // A square patch in the middle of the box, slightly tilted: the cut ends inside.
  Positions X(4, 3);
  X << 0.2, 0.2, 0.52, 0.8, 0.2, 0.55, 0.8, 0.8, 0.53, 0.2, 0.8, 0.5;
  Tris F(2, 3);
  F << 0, 1, 2, 0, 2, 3;
  const CutSurface s = *CutSurface::triangles(X, F);
  for (CutMethod method : {CutMethod::Hybrid, CutMethod::Standard, CutMethod::Snap}) {
    SCOPED_TRACE(cutMethodName(method));
    auto r = cut3d(box, s, withMethod(method));
    ASSERT_TRUE(r.ok()) << r.error();
    const auto v = validate(r->mesh);
    EXPECT_TRUE(v.ok()) << v.error();
    EXPECT_NEAR(totalVolume(r->mesh), 1.0, 1e-9);
    EXPECT_EQ(components(r->mesh), 1);
    EXPECT_GT(r->report.cut_faces, 0);
    EXPECT_GT(r->report.duplicated_nodes, 0);
  }
}

TEST(Cut3D, SurfaceOnPlaneMatchesPlaneCut) {
  const TetMesh box = testing::boxTetMesh(3, 3, 3, 1.0);
  Positions X(4, 3);
  X << -1, -1, 1.4, 4, -1, 1.4, 4, 4, 1.4, -1, 4, 1.4;
  Tris F(2, 3);
  F << 0, 1, 2, 0, 2, 3;
  const CutSurface s = *CutSurface::triangles(X, F);
  const CutSurface p = *CutSurface::plane(Vec3(0, 0, 1.4), Vec3(0, 0, 1));
  for (CutMethod method : {CutMethod::Hybrid, CutMethod::Standard}) {
    const auto a = cut3d(box, s, withMethod(method));
    const auto b = cut3d(box, p, withMethod(method));
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(a->mesh.numTets(), b->mesh.numTets());
    EXPECT_EQ(a->mesh.numNodes(), b->mesh.numNodes());
  }
}

TEST(Cut3D, BadInput) {
  EXPECT_FALSE(CutSurface::plane(Vec3(0, 0, 0), Vec3(0, 0, 0)).ok());
  Positions X(3, 3);
  X << 0, 0, 0, 1, 0, 0, 2, 0, 0;
  Tris F(1, 3);
  F << 0, 1, 2;
  EXPECT_FALSE(CutSurface::triangles(X, F).ok());  // degenerate only
  F << 0, 1, 5;
  EXPECT_FALSE(CutSurface::triangles(X, F).ok());
  TetMesh empty;
  EXPECT_FALSE(cut3d(empty, *CutSurface::plane(Vec3(0, 0, 0), Vec3(0, 0, 1))).ok());
  TetMesh bad = singleTet();
  bad.T(0, 3) = 7;
  EXPECT_FALSE(cut3d(bad, *CutSurface::plane(Vec3(0, 0, 0), Vec3(0, 0, 1))).ok());
}

// The same cut twice gives the same result to the last bit (no state carries over from one
// cut to the next, no uninitialised scratch is read), also for a cut that is refused. A
// curved strip through a box, every move list that can be split split in two parts.
TEST(Cut3D, TheSameCutTwiceGivesTheSameResult) {
  const TetMesh box = testing::boxTetMesh(6, 6, 6, 1.0);
  const int rows = 9, row_size = 7;
  Positions X(rows * row_size, 3);
  for (int r = 0; r < rows; ++r)
    for (int i = 0; i < row_size; ++i) {
      const double a = M_PI + M_PI * i / (row_size - 1), z = 8.0 * r / (rows - 1) - 1.0;
      X.row(r * row_size + i) << 3.1 + 2.2 * std::cos(a) + 0.05 * z, 3.0 + 0.1 * z, 6.2 + 2.9 * std::sin(a);
    }
  const auto surface = CutSurface::strip(X, rows, row_size);
  ASSERT_TRUE(surface.ok());
  Cut3DOptions options;
  options.method = CutMethod::Hybrid;
  options.optimize.parallel_min_nodes = 2;
  const auto a = cut3d(box, *surface, options);
  const auto b = cut3d(box, *surface, options);
  ASSERT_TRUE(a.ok() && b.ok()) << (a.ok() ? b.error() : a.error());
  EXPECT_GT(a->report.cut_faces, 0);
  EXPECT_GT(a->report.optimize_iterations, 0);
  EXPECT_TRUE(a->mesh.X == b->mesh.X);
  EXPECT_TRUE(a->mesh.T == b->mesh.T);
  EXPECT_TRUE(a->mesh.material == b->mesh.material);
  EXPECT_EQ(a->change.node_old_to_new, b->change.node_old_to_new);
  EXPECT_EQ(a->change.element_old_to_new, b->change.element_old_to_new);
  EXPECT_EQ(a->change.added_elements, b->change.added_elements);
  EXPECT_EQ(a->change.moved_nodes, b->change.moved_nodes);
  EXPECT_EQ(a->change.cut_faces, b->change.cut_faces);
  // Refused (a mesh whose nodes all coincide): the same error both times.
  TetMesh flat = box;
  flat.X.setZero();
  const auto refused = cut3d(flat, *surface, options), again = cut3d(flat, *surface, options);
  ASSERT_FALSE(refused.ok());
  ASSERT_FALSE(again.ok());
  EXPECT_EQ(refused.error(), again.error());
}

// The report's step times: non-negative; the cut's steps are the time up to cut_ms, the
// optimisation's steps within optimize_ms (a hybrid plane cut through a box that collapses
// and moves nodes); a standard cut has no optimisation steps.
TEST(Cut3D, ReportStepTimesAddUp) {
  const TetMesh box = testing::boxTetMesh(8, 8, 8, 1.0);
  const auto plane = CutSurface::plane(Vec3(0, 0, 4.07), Vec3(0.11, 0.07, 1.0).normalized());
  ASSERT_TRUE(plane.ok());
  const auto r = cut3d(box, *plane);
  ASSERT_TRUE(r.ok()) << r.error();
  const Cut3DReport& rep = r->report;
  EXPECT_GT(rep.optimize_iterations, 0);
  for (const double ms : {rep.classify_ms, rep.snap_ms, rep.subdivide_ms, rep.separate_ms, rep.assemble_ms,
                          rep.compact_ms, rep.collapse_ms, rep.late_snap_ms, rep.move_ms})
    EXPECT_GE(ms, 0.0);
  const double cutSteps = rep.classify_ms + rep.snap_ms + rep.subdivide_ms + rep.separate_ms;
  EXPECT_NEAR(cutSteps, rep.cut_ms, 1e-9 * (1.0 + rep.cut_ms));  // (the same clock readings)
  EXPECT_GT(rep.move_ms, 0.0);
  EXPECT_LE(rep.collapse_ms + rep.late_snap_ms + rep.move_ms, rep.optimize_ms);
  Cut3DOptions standard;
  standard.method = CutMethod::Standard;
  const auto s = cut3d(box, *plane, standard);
  ASSERT_TRUE(s.ok()) << s.error();
  EXPECT_EQ(s->report.optimize_ms, 0.0);
  EXPECT_EQ(s->report.collapse_ms + s->report.late_snap_ms + s->report.move_ms, 0.0);
  EXPECT_GT(s->report.classify_ms + s->report.subdivide_ms, 0.0);
}

// CutSurface::strip is the surface triangles() makes of the same grid (same triangle
// numbers), only with a tree that follows the grid: every query answers the same, bit for
// bit, and cut3d cuts the same. The strip: a half-cylinder loop swept along a bent path,
// with a collapsed quad (degenerate triangles, dropped by both).
TEST(Cut3D, StripIsTheSameSurfaceAsItsTriangles) {
  const int rows = 23, row_size = 13;
  Positions X(rows * row_size, 3);
  for (int r = 0; r < rows; ++r)
    for (int i = 0; i < row_size; ++i) {
      const double a = M_PI + M_PI * i / (row_size - 1), z = 1.2 * r / (rows - 1) - 0.1;
      X.row(r * row_size + i) << 0.5 + 0.4 * std::cos(a) + 0.3 * z * z, 0.9 + 0.4 * std::sin(a) + 0.1 * z, z;
    }
  X.row(5 * row_size + 4) = X.row(5 * row_size + 3);  // quad (5, 3) collapses to a triangle's edge
  X.row(6 * row_size + 4) = X.row(6 * row_size + 3);
  const Tris F = CutSurface::stripTriangles(rows, row_size);
  ASSERT_EQ(F.rows(), 2 * (rows - 1) * (row_size - 1));
  const auto sorted = CutSurface::triangles(X, F);
  const auto grid = CutSurface::strip(X, rows, row_size);
  ASSERT_TRUE(sorted.ok() && grid.ok());
  EXPECT_EQ(grid->numTriangles(), sorted->numTriangles());
  // Dropped: quad (5, 3)'s two triangles, and one each of quads (4, 3) and (6, 3).
  EXPECT_EQ(grid->numTriangles(), 2 * (rows - 1) * (row_size - 1) - 4);
  EXPECT_EQ(grid->bounds().min(), sorted->bounds().min());
  EXPECT_EQ(grid->bounds().max(), sorted->bounds().max());
  const double eps = 1e-9;
  int hits = 0;
  for (int i = 0; i < 800; ++i) {
    const Vec3 x = pointAroundStrip(i);
    Vec3 p, q;
    EXPECT_EQ(grid->signedDistance(x, &p), sorted->signedDistance(x, &q)) << x.transpose();
    EXPECT_EQ(p, q);
    EXPECT_EQ(grid->signedDistanceNear(x, 0.2, &p), sorted->signedDistanceNear(x, 0.2, &q));
    EXPECT_EQ(p, q);
    for (double r : {1e-3, 0.05, 0.3}) EXPECT_EQ(grid->within(x, r), sorted->within(x, r));
    const Vec3 b = pointAroundStrip(i + 7919);
    CutSurface::Hit h1, h2;
    const bool f1 = grid->intersectSegment(x, b, eps, &h1), f2 = sorted->intersectSegment(x, b, eps, &h2);
    EXPECT_EQ(f1, f2) << x.transpose() << " / " << b.transpose();
    if (f1 && f2) {
      EXPECT_EQ(h1.t, h2.t);
      EXPECT_EQ(h1.normal, h2.normal);
    }
    hits += f1;
  }
  EXPECT_GT(hits, 100);
  // The same cut of a block of tets.
  const TetMesh block = testing::boxTetMesh(4, 4, 4, 0.25);
  const auto c1 = cut3d(block, *grid), c2 = cut3d(block, *sorted);
  ASSERT_TRUE(c1.ok() && c2.ok());
  EXPECT_EQ(c1->mesh.X, c2->mesh.X);
  EXPECT_EQ(c1->mesh.T, c2->mesh.T);
  EXPECT_GT(c1->report.crossed_edges, 0);
  // Bad shapes: too few rows or columns, or vertices that do not make rows x row_size.
  EXPECT_FALSE(CutSurface::strip(X, 1, rows * row_size).ok());
  EXPECT_FALSE(CutSurface::strip(X, rows, 1).ok());
  EXPECT_FALSE(CutSurface::strip(X, rows - 1, row_size).ok());
}

TEST(Cut3D, ComponentsFreeAndVolumes) {
  const TetMesh box = testing::boxTetMesh(2, 2, 2, 1.0);
  const auto r = cutAndCheck(box, Vec3(0, 0, 1), Vec3(0, 0, 1), withMethod(CutMethod::Hybrid));
  const auto c = tetComponents(r.mesh, {0});  // node 0 (z = 0) anchored
  ASSERT_EQ(c.count, 2);
  EXPECT_NEAR(c.volume[0] + c.volume[1], 8.0, 1e-12);
  EXPECT_NEAR(c.volume[0], 4.0, 1e-12);
  EXPECT_EQ(static_cast<int>(c.free[0]) + static_cast<int>(c.free[1]), 1);
  EXPECT_FALSE(c.free[c.label(r.mesh.numTets() > 0 ? 0 : 0)] && false);
}

TEST(Cut3D, UterusPlaneCutQuality) {
  const std::string path = std::string(HYSIM_SOURCE_DIR) + "/assets/uterus_myoma.msh";
  ASSERT_TRUE(std::filesystem::exists(path)) << "missing " << path << ", an asset shipped in the repository";
  const auto mesh = readTetMesh(path);
  ASSERT_TRUE(mesh.ok()) << mesh.error();
  const auto s0 = computeStats(*mesh);
  const Vec3 lo = mesh->X.colwise().minCoeff().transpose(), hi = mesh->X.colwise().maxCoeff().transpose();
  const Vec3 c = 0.5 * (lo + hi);
  const auto h = cutAndCheck(*mesh, c, Vec3(0.2, 0.1, 1.0), withMethod(CutMethod::Hybrid), 1e-3);
  const auto s1 = computeStats(h.mesh);
  EXPECT_LE(s1.elements, 1.10 * s0.elements);
  EXPECT_GE(s1.q_min, 0.25 * s0.q_min);
  EXPECT_GE(s1.edge_min, 0.2 * s0.edge_min);
  const auto st = cutAndCheck(*mesh, c, Vec3(0.2, 0.1, 1.0), withMethod(CutMethod::Standard), 1e-9);
  EXPECT_GT(st.mesh.numTets(), h.mesh.numTets());
}

// An open half-cylinder strip (radius 3.5 around the z axis line x = 0, y = -0.5, lower half,
// z in [-6, 14]) dipping 3 mm into the top of the myoma (sphere around (0, -9, 4), radius 8):
// its long edges lie above the myoma surface and its ends outside the myoma, so the cap of
// tissue between the strip and the myoma surface is enclosed and must come off. The strip is
// curved on the scale of the elements (edges ~4 mm): the flat faces through the crossings lie
// off the surface by their sagitta, and they must still count as cut faces.
// The strip's vertices: rows along z (kHalfCylinderRows of them), kHalfCylinderRowSize around.
constexpr double kHalfCylinderRadius = 3.5, kHalfCylinderAxisY = -0.5;
constexpr int kHalfCylinderRowSize = 17, kHalfCylinderRows = 21;
Positions halfCylinderStrip() {
  const double z0 = -6, z1 = 14;
  const int nu = kHalfCylinderRowSize - 1, nv = kHalfCylinderRows - 1;
  Positions X((nu + 1) * (nv + 1), 3);
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) {
      const double a = M_PI + M_PI * i / nu;
      X.row(j * (nu + 1) + i) << kHalfCylinderRadius * std::cos(a), kHalfCylinderAxisY + kHalfCylinderRadius * std::sin(a),
          z0 + (z1 - z0) * j / nv;
    }
  return X;
}

TEST(Cut3D, UterusHalfCylinderStripSeparatesCap) {
  const std::string path = std::string(HYSIM_SOURCE_DIR) + "/assets/uterus_myoma.msh";
  ASSERT_TRUE(std::filesystem::exists(path)) << "missing " << path << ", an asset shipped in the repository";
  const auto mesh = readTetMesh(path);
  ASSERT_TRUE(mesh.ok()) << mesh.error();
  const double radius = kHalfCylinderRadius, yAxis = kHalfCylinderAxisY;
  const int nu = kHalfCylinderRowSize - 1, nv = kHalfCylinderRows - 1;
  const Positions X = halfCylinderStrip();
  Tris F(2 * nu * nv, 3);
  int f = 0;
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const int v00 = j * (nu + 1) + i, v10 = v00 + 1, v01 = v00 + nu + 1, v11 = v01 + 1;
      F.row(f++) << v00, v10, v11;
      F.row(f++) << v00, v11, v01;
    }
  const CutSurface s = *CutSurface::triangles(X, F);
  // Enclosed volume: inside the sphere, above the strip (|x| < radius), by midpoint sums.
  const Vec3 centre(0, -9, 4);
  const double rs = 8;
  double analytic = 0;
  const int n = 200;
  const double hx = 2 * radius / n, hz = 2 * rs / n;
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < n; ++k) {
      const double x = -radius + (i + 0.5) * hx, z = centre.z() - rs + (k + 0.5) * hz;
      const double r2 = rs * rs - x * x - (z - centre.z()) * (z - centre.z());
      if (r2 <= 0) continue;
      const double top = centre.y() + std::sqrt(r2), bottom = yAxis - std::sqrt(radius * radius - x * x);
      if (top > bottom) analytic += (top - bottom) * hx * hz;
    }
  ASSERT_GT(analytic, 50.0);
  ASSERT_LT(analytic, 200.0);
  const double v0 = totalVolume(*mesh);
  for (CutMethod method : {CutMethod::Standard, CutMethod::Hybrid}) {
    SCOPED_TRACE(cutMethodName(method));
    auto r = cut3d(*mesh, s, withMethod(method));
    ASSERT_TRUE(r.ok()) << r.error();
    const auto v = validate(r->mesh);
    EXPECT_TRUE(v.ok()) << v.error();
    EXPECT_NEAR(totalVolume(r->mesh), v0, (method == CutMethod::Standard ? 1e-9 : 1e-3) * v0);
    const auto c = tetComponents(r->mesh);
    ASSERT_EQ(c.count, 2);
    const double cap = std::min(c.volume[0], c.volume[1]);
    // The faceted myoma and the coarse elements make the cap smaller than the exact one.
    EXPECT_GT(cap, 0.5 * analytic);
    EXPECT_LT(cap, 1.3 * analytic);
  }
}

// Pieces the cut cuts off (no anchored node) are left as the cut made them when the anchors
// are given: the cap of the half-cylinder strip through the myoma, with the nodes outside the
// default scene's ellipsoid anchored. The cap is then the unoptimised cut's cap, the rest is
// optimised and valid. With every node anchored nothing is cut off and the result is the
// plain hybrid cut's.
TEST(Cut3D, CutOffPiecesAreLeftAsCut) {
  const std::string path = std::string(HYSIM_SOURCE_DIR) + "/assets/uterus_myoma.msh";
  ASSERT_TRUE(std::filesystem::exists(path)) << "missing " << path << ", an asset shipped in the repository";
  const auto mesh = readTetMesh(path);
  ASSERT_TRUE(mesh.ok()) << mesh.error();
  const CutSurface s = *CutSurface::strip(halfCylinderStrip(), kHalfCylinderRows, kHalfCylinderRowSize);
  auto outside = [](const Vec3& p) {
    const double x = p.x() / 25, y = p.y() / 20, z = p.z() / 33;
    return x * x + y * y + z * z > 1;
  };
  std::vector<std::uint8_t> flags(static_cast<size_t>(mesh->numNodes()));
  for (int i = 0; i < mesh->numNodes(); ++i) flags[i] = outside(mesh->X.row(i).transpose()) ? 1 : 0;
  auto anchoredOf = [&](const TetMesh& m) {
    std::vector<int> a;
    for (int i = 0; i < m.numNodes(); ++i)
      if (outside(m.X.row(i).transpose())) a.push_back(i);
    return a;
  };
  const Cut3DOptions plain = withMethod(CutMethod::Hybrid);
  Cut3DOptions unoptimised = plain;
  unoptimised.optimize.enabled = false;
  const auto full = cut3d(*mesh, s, plain);
  const auto bare = cut3d(*mesh, s, unoptimised);
  ASSERT_TRUE(full.ok() && bare.ok());
  const auto bareC = tetComponents(bare->mesh, anchoredOf(bare->mesh));
  ASSERT_EQ(bareC.count, 2);
  const int bareCap = bareC.free[0] ? 0 : 1;
  ASSERT_TRUE(bareC.free[bareCap]);
  ASSERT_FALSE(bareC.free[1 - bareCap]);

  Cut3DOptions o = plain;
  o.anchored_nodes = &flags;
  o.anchored_at = outside;
  const auto r = cut3d(*mesh, s, o);
  ASSERT_TRUE(r.ok()) << r.error();
  const auto v = validate(r->mesh);
  EXPECT_TRUE(v.ok()) << v.error();
  EXPECT_EQ(r->report.cut_off_pieces, 1);
  const auto c = tetComponents(r->mesh, anchoredOf(r->mesh));
  ASSERT_EQ(c.count, 2);
  const int cap = c.free[0] ? 0 : 1;
  ASSERT_TRUE(c.free[cap]);
  EXPECT_EQ(r->report.cut_off_elements, c.elements[cap]);
  EXPECT_EQ(c.elements[cap], bareC.elements[bareCap]);
  EXPECT_NEAR(c.volume[cap], bareC.volume[bareCap], 1e-12 * bareC.volume[bareCap]);
  EXPECT_NEAR(r->report.cut_off_volume, c.volume[cap], 1e-12 * c.volume[cap]);
  // The cap's tets, as sorted corner positions, are the unoptimised cut's.
  auto capTets = [](const TetMesh& m, const Components3D& comps, int label) {
    std::vector<std::array<double, 12>> out;
    for (int t = 0; t < m.numTets(); ++t) {
      if (comps.label[t] != label) continue;
      std::array<std::array<double, 3>, 4> p;
      for (int k = 0; k < 4; ++k)
        for (int d = 0; d < 3; ++d) p[k][d] = m.X(m.T(t, k), d);
      std::sort(p.begin(), p.end());
      std::array<double, 12> flat;
      for (int k = 0; k < 4; ++k)
        for (int d = 0; d < 3; ++d) flat[3 * k + d] = p[k][d];
      out.push_back(flat);
    }
    std::sort(out.begin(), out.end());
    return out;
  };
  EXPECT_EQ(capTets(r->mesh, c, cap), capTets(bare->mesh, bareC, bareCap));
  EXPECT_NEAR(totalVolume(r->mesh), totalVolume(*mesh), 1e-3 * totalVolume(*mesh));
  // The optimisation did its work on the rest: its worst tet is no worse than the unoptimised.
  auto restQ = [](const TetMesh& m, const Components3D& comps, int skip) {
    double q = 1;
    for (int t = 0; t < m.numTets(); ++t)
      if (comps.label[t] != skip)
        q = std::min(q, radiusRatio(m.X.row(m.T(t, 0)).transpose(), m.X.row(m.T(t, 1)).transpose(),
                                    m.X.row(m.T(t, 2)).transpose(), m.X.row(m.T(t, 3)).transpose()));
    return q;
  };
  EXPECT_GE(restQ(r->mesh, c, cap), restQ(bare->mesh, bareC, bareCap));

  // Every node anchored: nothing cut off, the plain hybrid cut.
  std::vector<std::uint8_t> all(flags.size(), 1);
  o.anchored_nodes = &all;
  o.anchored_at = [](const Vec3&) { return true; };
  const auto held = cut3d(*mesh, s, o);
  ASSERT_TRUE(held.ok());
  EXPECT_EQ(held->report.cut_off_pieces, 0);
  EXPECT_TRUE(held->mesh.X == full->mesh.X);
  EXPECT_TRUE(held->mesh.T == full->mesh.T);
  // None anchored: the search does not look into the last piece left open when nothing holds
  // a piece (it would hold the tissue): the cap (seen first, being small) is cut off, the
  // rest optimised, as with the anchors.
  std::vector<std::uint8_t> none(flags.size(), 0);
  o.anchored_nodes = &none;
  o.anchored_at = nullptr;
  const auto loose = cut3d(*mesh, s, o);
  ASSERT_TRUE(loose.ok());
  EXPECT_EQ(loose->report.cut_off_pieces, 1);
  EXPECT_EQ(loose->report.cut_off_elements, r->report.cut_off_elements);
  EXPECT_TRUE(validate(loose->mesh).ok());
}

// The surface's walks (nearest point, within, segment crossing) against plain loops over every
// triangle in input order, on random curved strips (a bent, wavy sheet, vertices jittered),
// both trees (the strip's grid tree and the centroid-sorted one), at random points near and on
// the surface: on triangles, on edges, at vertices, a little off them and farther out. The
// nearest point and the signed distance agree bit for bit (ties: the lower triangle index).
TEST(Cut3D, SurfaceWalksMatchBruteForce) {
  std::mt19937 rng(20261123);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (int strip = 0; strip < 12; ++strip) {
    const int rows = 2 + static_cast<int>(uni(rng) * 9), rowSize = 2 + static_cast<int>(uni(rng) * 25);
    const double radius = 0.3 + uni(rng), bend = 0.5 + 2.5 * uni(rng), wave = 0.05 * uni(rng);
    const double jitter = strip % 3 == 0 ? 0.0 : 0.01 * uni(rng);
    Positions X(rows * rowSize, 3);
    for (int r = 0; r < rows; ++r)
      for (int i = 0; i < rowSize; ++i) {
        const double a = bend * (static_cast<double>(i) / (rowSize - 1) - 0.5);
        const double y = 1.5 * r / (rows - 1) + wave * std::sin(7.0 * a);
        X.row(r * rowSize + i) << radius * std::sin(a) + jitter * (uni(rng) - 0.5),
            y + jitter * (uni(rng) - 0.5), radius * (1 - std::cos(a)) + wave * std::cos(5.0 * y);
      }
    const Tris F = CutSurface::stripTriangles(rows, rowSize);
    const auto grid = CutSurface::strip(X, rows, rowSize);
    const auto sorted = CutSurface::triangles(X, F);
    ASSERT_TRUE(grid.ok() && sorted.ok());
    ASSERT_EQ(grid->numTriangles(), F.rows());  // none degenerate
    auto vertex = [&](int f, int k) { return Vec3(X.row(F(f, k)).transpose()); };
    // Brute force, in input order (a strictly smaller distance replaces: ties keep the lower index).
    auto nearest = [&](const Vec3& x, Vec3* point) {
      double best = std::numeric_limits<double>::infinity();
      int bestF = -1;
      for (int f = 0; f < F.rows(); ++f) {
        const Vec3 q = closestPointOnTriangle(x, vertex(f, 0), vertex(f, 1), vertex(f, 2));
        const double d2 = (q - x).squaredNorm();
        if (d2 < best) {
          best = d2;
          bestF = f;
          *point = q;
        }
      }
      const Vec3 a = vertex(bestF, 0);
      const Vec3 n = (vertex(bestF, 1) - a).cross(vertex(bestF, 2) - a).normalized();
      const double d = std::sqrt(best);
      return n.dot(x - a) < 0 ? -d : d;
    };
    auto within = [&](const Vec3& x, double r) {
      for (int f = 0; f < F.rows(); ++f)
        if (std::sqrt((closestPointOnTriangle(x, vertex(f, 0), vertex(f, 1), vertex(f, 2)) - x).squaredNorm()) <= r)
          return true;
      return false;
    };
    auto crossing = [&](const Vec3& a, const Vec3& b, double eps, double* tBest) {
      bool found = false;
      *tBest = 2.0;
      for (int f = 0; f < F.rows(); ++f) {
        const Vec3 p0 = vertex(f, 0), p1 = vertex(f, 1), p2 = vertex(f, 2);
        const Vec3 n = (p1 - p0).cross(p2 - p0).normalized();
        const double da = n.dot(a - p0), db = n.dot(b - p0);
        if (!((da > eps && db < -eps) || (da < -eps && db > eps))) continue;
        const double t = da / (da - db);
        if (t >= *tBest) continue;
        const Vec3 p = a + t * (b - a);
        const double slack = -1e-12 * n.dot((p1 - p0).cross(p2 - p0));
        if (n.dot((p1 - p).cross(p2 - p)) < slack || n.dot((p2 - p).cross(p0 - p)) < slack ||
            n.dot((p0 - p).cross(p1 - p)) < slack)
          continue;
        found = true;
        *tBest = t;
      }
      return found;
    };
    const Eigen::AlignedBox3d bounds = grid->bounds();
    for (int i = 0; i < 400; ++i) {
      const int f = static_cast<int>(uni(rng) * F.rows());
      const Vec3 a = vertex(f, 0), b = vertex(f, 1), c = vertex(f, 2);
      const Vec3 n = (b - a).cross(c - a).normalized();
      Vec3 x;
      switch (i % 6) {
        case 0: x = i % 12 == 0 ? a : c; break;                      // a vertex
        case 1: x = a + uni(rng) * (b - a); break;                    // an edge
        case 2: {                                                     // in the triangle
          double s = uni(rng), t = uni(rng);
          if (s + t > 1) s = 1 - s, t = 1 - t;
          x = a + s * (b - a) + t * (c - a);
          break;
        }
        case 3: x = a + uni(rng) * (c - b) * 0.3 + std::pow(10.0, -12 + 11 * uni(rng)) * n; break;  // just off it
        case 4: x = a + (uni(rng) - 0.5) * 0.2 * Vec3(uni(rng), uni(rng), uni(rng)); break;         // around it
        default:                                                       // anywhere around the surface
          x = bounds.min() + (bounds.max() - bounds.min()).cwiseProduct(Vec3(uni(rng), uni(rng), uni(rng))) * 1.4 -
              0.2 * (bounds.max() - bounds.min());
      }
      Vec3 pRef;
      const double dRef = nearest(x, &pRef);
      for (const CutSurface* s : {&*grid, &*sorted}) {
        Vec3 p;
        const double d = s->signedDistance(x, &p);
        EXPECT_EQ(std::memcmp(&d, &dRef, sizeof d), 0) << strip << " " << i << " " << d << " " << dRef;
        EXPECT_EQ(std::memcmp(p.data(), pRef.data(), sizeof(double) * 3), 0) << strip << " " << i;
        for (double r : {0.0, 0.5 * std::abs(dRef), std::abs(dRef), std::abs(dRef) * (1 + 1e-12) + 1e-300,
                         2 * std::abs(dRef) + 0.01}) {
          Vec3 pn;
          const double dn = s->signedDistanceNear(x, r, &pn);
          EXPECT_EQ(std::memcmp(&dn, &dRef, sizeof dn), 0) << strip << " " << i << " r " << r;
          EXPECT_EQ(std::memcmp(pn.data(), pRef.data(), sizeof(double) * 3), 0) << strip << " " << i << " r " << r;
        }
        for (double r : {std::abs(dRef), std::abs(dRef) * (1 - 1e-9), std::abs(dRef) * (1 + 1e-9), 1e-3, 0.05})
          EXPECT_EQ(s->within(x, r), within(x, r)) << strip << " " << i << " r " << r;
        // A segment from x to a point across the surface (and one next to it).
        for (const Vec3& y : {Vec3(pRef + (pRef - x) + 0.01 * n), Vec3(x + 0.3 * (b - a))}) {
          double tRef;
          const bool fRef = crossing(x, y, 1e-9, &tRef);
          CutSurface::Hit hit;
          const bool found = s->intersectSegment(x, y, 1e-9, &hit);
          EXPECT_EQ(found, fRef) << strip << " " << i;
          if (found && fRef) {
            EXPECT_EQ(hit.t, tRef) << strip << " " << i;
          }
        }
        // mayTouch: a box meeting a triangle's box is (possibly) touched.
        const Eigen::AlignedBox3d box(x - Vec3::Constant(0.01), x + Vec3::Constant(0.01));
        bool meets = false;
        for (int g = 0; g < F.rows() && !meets; ++g) {
          Eigen::AlignedBox3d tb;
          tb.extend(vertex(g, 0)).extend(vertex(g, 1)).extend(vertex(g, 2));
          meets = tb.intersects(box);
        }
        if (meets) {
          EXPECT_TRUE(s->mayTouch(box, 0.0)) << strip << " " << i;
        }
      }
    }
  }
}

}  // namespace
}  // namespace hysim::cutting
