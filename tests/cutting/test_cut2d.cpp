// 2D cutting: the cases of the paper's Figs. 4 and 5 on hand-made meshes, border and corner
// nodes, the baselines, and randomized cuts checked by validate() and the invariants.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>

#include "cut2d_meshes.hpp"
#include "hysim/cutting/cut2d.hpp"
#include "hysim/cutting/mesh_io.hpp"
#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::cutting {
namespace {

using Eigen::Vector2d;
using testing::gridTriMesh;

Cut2DOptions method(CutMethod m, bool optimize = true) {
  Cut2DOptions o;
  o.method = m;
  o.optimize.enabled = optimize;
  return o;
}

// Invariants every cut keeps.
void checkCut(const TriMesh& in, const Cut2DResult& r, bool complete) {
  ASSERT_TRUE(validate(r.mesh).ok()) << validate(r.mesh).error();
  const auto& tc = r.change;
  EXPECT_EQ(tc.old_num_nodes, in.numNodes());
  EXPECT_EQ(tc.old_num_elements, in.numTris());
  EXPECT_EQ(tc.new_num_nodes, r.mesh.numNodes());
  EXPECT_EQ(tc.new_num_elements, r.mesh.numTris());
  ASSERT_EQ(static_cast<int>(tc.node_old_to_new.size()), in.numNodes());
  ASSERT_EQ(static_cast<int>(tc.element_old_to_new.size()), in.numTris());
  int kept = 0;
  for (int e : tc.element_old_to_new) kept += e >= 0;
  EXPECT_EQ(kept + static_cast<int>(tc.added_elements.size()), r.mesh.numTris());
  EXPECT_EQ(kept + static_cast<int>(tc.removed_elements.size()), in.numTris());
  for (const auto& n : tc.new_nodes) {
    ASSERT_GE(n.id, 0);
    ASSERT_LT(n.id, r.mesh.numNodes());
    double wsum = 0;
    for (int k = 0; k < n.num_parents; ++k) {
      ASSERT_GE(n.parents[k], 0);
      ASSERT_LT(n.parents[k], in.numNodes());
      wsum += n.weights[k];
    }
    EXPECT_NEAR(wsum, 1.0, 1e-12);
  }
  // An element that kept its identity still has the same nodes (up to duplication).
  for (int o = 0; o < in.numTris(); ++o) {
    const int n = tc.element_old_to_new[o];
    if (n < 0) continue;
    for (int k = 0; k < 3; ++k) {
      const int oldNode = in.F(o, k), newNode = r.mesh.F(n, k);
      bool ok = tc.node_old_to_new[oldNode] == newNode;
      for (const auto& nn : tc.new_nodes)
        ok = ok || (nn.id == newNode && nn.duplicate && nn.num_parents == 1 && nn.parents[0] == oldNode);
      EXPECT_TRUE(ok) << "element " << o << " corner " << k;
    }
  }
  // The sides share no edge: every cut edge is a border edge of the new mesh.
  std::map<std::pair<int, int>, int> edgeCount;
  for (int f = 0; f < r.mesh.numTris(); ++f)
    for (int k = 0; k < 3; ++k) {
      auto e = std::minmax(r.mesh.F(f, k), r.mesh.F(f, (k + 1) % 3));
      ++edgeCount[{e.first, e.second}];
    }
  for (const auto& e : tc.cut_edges) {
    auto k = std::minmax(e[0], e[1]);
    EXPECT_EQ((edgeCount[{k.first, k.second}]), 1) << "cut edge shared by both sides";
  }
  if (complete) {
    int comps = 0;
    elementComponents(r.mesh, &comps);
    EXPECT_GE(comps, 2) << "a complete cut must separate the mesh";
  }
}

// --- baselines -------------------------------------------------------------------------

TEST(Cut2DStandard, SplitsEveryCrossedEdgeAndSeparates) {
  const TriMesh m = gridTriMesh(4, 3, 1.0);
  auto r = cut2d(m, Vector2d(-1, 1.45), Vector2d(5, 1.55), method(CutMethod::Standard));
  ASSERT_TRUE(r.ok()) << r.error();
  checkCut(m, *r, true);
  EXPECT_EQ(r->report.crossed_edges, r->report.subdivided_edges);
  EXPECT_EQ(r->report.displaced_nodes, 0);
  EXPECT_GT(r->mesh.numTris(), m.numTris());
  EXPECT_NEAR(totalArea(r->mesh), totalArea(m), 1e-9 * totalArea(m));
  EXPECT_TRUE(r->change.moved_nodes.empty());
}

TEST(Cut2DDelete, RemovesCrossedElementsOnly) {
  const TriMesh m = gridTriMesh(4, 3, 1.0);
  auto r = cut2d(m, Vector2d(-1, 1.5), Vector2d(5, 1.5), method(CutMethod::Delete));
  ASSERT_TRUE(r.ok()) << r.error();
  checkCut(m, *r, true);
  EXPECT_EQ(r->mesh.numTris(), m.numTris() - 8);  // the middle row of squares
  EXPECT_EQ(r->report.deleted_elements, 8);
  EXPECT_NEAR(totalArea(r->mesh), totalArea(m) - 4.0, 1e-12);
}

TEST(Cut2DSnap, DisplacesInsteadOfSubdividing) {
  const TriMesh m = gridTriMesh(4, 3, 1.0);
  auto r = cut2d(m, Vector2d(-1, 1.4), Vector2d(5, 1.4), method(CutMethod::Snap));
  ASSERT_TRUE(r.ok()) << r.error();
  checkCut(m, *r, true);
  EXPECT_EQ(r->report.subdivided_edges, 0);
  EXPECT_EQ(r->mesh.numTris(), m.numTris());
  EXPECT_EQ(countDistinctPositions(r->mesh), m.numNodes());
}

// --- Fig. 5 cases ----------------------------------------------------------------------

TEST(Cut2DHybrid, Case1BothCrossingsNearNodesOnlyDisplaces) {
  // y = 1.1: every crossed edge is crossed at 0.1 of its length from a node of row 1.
  const TriMesh m = gridTriMesh(4, 3, 1.0);
  auto r = cut2d(m, Vector2d(-1, 1.1), Vector2d(5, 1.1), method(CutMethod::Hybrid, false));
  ASSERT_TRUE(r.ok()) << r.error();
  checkCut(m, *r, true);
  EXPECT_EQ(r->report.subdivided_edges, 0);
  EXPECT_EQ(r->report.displaced_nodes, 5);
  EXPECT_EQ(r->report.border_displacements, 2);  // (0,1) and (4,1) slide along the border
  EXPECT_EQ(r->mesh.numTris(), m.numTris());
  EXPECT_EQ(countDistinctPositions(r->mesh), m.numNodes());
  // Border nodes stayed on their border line.
  const int left = r->change.node_old_to_new[5], right = r->change.node_old_to_new[9];
  EXPECT_DOUBLE_EQ(r->mesh.X(left, 0), 0.0);
  EXPECT_DOUBLE_EQ(r->mesh.X(right, 0), 4.0);
  EXPECT_NEAR(r->mesh.X(left, 1), 1.1, 1e-12);
  EXPECT_NEAR(totalArea(r->mesh), totalArea(m), 1e-12);
}

TEST(Cut2DHybrid, Case2DisplacementPlusOneNewElementPerTriangle) {
  // x = 0.1 crosses the spokes to the top/bottom corners at 0.2 from the centre (displace
  // the centre) and the top and bottom border edges at 0.4 (subdivide): two type-2 cases.
  const TriMesh m = testing::hexagonMesh();
  Cut2DOptions o = method(CutMethod::Hybrid, false);  // the cut stage (the node budget would merge)
  o.corner_region = 0;  // the paper's case: the border crossings are not bent to the corners
  auto r = cut2d(m, Vector2d(0.1, -2), Vector2d(0.1, 2), o);
  ASSERT_TRUE(r.ok()) << r.error();
  checkCut(m, *r, true);
  EXPECT_EQ(r->report.displaced_nodes, 1);
  EXPECT_EQ(r->report.subdivided_edges, 2);
  EXPECT_EQ(r->mesh.numTris(), 8);  // 6 + one per type-2 triangle
  const int c = r->change.node_old_to_new[0];
  EXPECT_NEAR(r->mesh.X(c, 0), 0.1, 1e-12);
  EXPECT_NEAR(totalArea(r->mesh), totalArea(m), 1e-12);
}

TEST(Cut2DHybrid, Case3TwoNewElements) {
  // Both crossings near the middle of an edge; the corners are features and cannot move.
  const TriMesh m = testing::singleTriangle();
  auto r = cut2d(m, Vector2d(-1, 0.4), Vector2d(2, 0.4), method(CutMethod::Hybrid));
  ASSERT_TRUE(r.ok()) << r.error();
  checkCut(m, *r, true);
  EXPECT_EQ(r->report.displaced_nodes, 0);
  EXPECT_EQ(r->report.subdivided_edges, 2);
  EXPECT_EQ(r->mesh.numTris(), 3);
  EXPECT_EQ(r->report.duplicated_nodes, 2);
}

// --- Fig. 4: look-ahead ----------------------------------------------------------------

TEST(Cut2DHybrid, TwoConsecutiveType2CasesBecomeAnEdgeFlip) {
  // The line through (0,0), (2,1), (4,2) meets nodes and crosses one vertical edge at its
  // middle between them: vertex -> edge -> vertex, twice.
  const TriMesh m = gridTriMesh(4, 2, 1.0);
  Cut2DOptions o = method(CutMethod::Hybrid, false);
  auto r = cut2d(m, Vector2d(-1, -0.5), Vector2d(5, 2.5), o);
  ASSERT_TRUE(r.ok()) << r.error();
  checkCut(m, *r, true);
  EXPECT_EQ(r->report.edge_flips, 2);
  EXPECT_EQ(r->report.subdivided_edges, 0);
  EXPECT_EQ(r->mesh.numTris(), m.numTris());
  EXPECT_EQ(r->change.removed_elements.size(), 4u);
  EXPECT_EQ(r->change.added_elements.size(), 4u);
}

TEST(Cut2DHybrid, RefusedFlipAddsTwoElements) {
  const TriMesh m = gridTriMesh(4, 2, 1.0);
  Cut2DOptions o = method(CutMethod::Hybrid, false);
  o.min_quality = 0.2;  // the flipped triangles (q = 0.136) are not good enough
  auto r = cut2d(m, Vector2d(-1, -0.5), Vector2d(5, 2.5), o);
  ASSERT_TRUE(r.ok()) << r.error();
  checkCut(m, *r, true);
  EXPECT_EQ(r->report.edge_flips, 0);
  EXPECT_EQ(r->report.subdivided_edges, 2);
  EXPECT_EQ(r->mesh.numTris(), m.numTris() + 4);  // two new elements per refused flip
}

TEST(Cut2DHybrid, DisplacementThatWouldFoldFallsBackToSubdivision) {
  // Node 1 of the sliver fan cannot be projected onto the cut without folding; the crossing
  // is subdivided instead.
  const TriMesh m = testing::hexagonMesh();
  Cut2DOptions o = method(CutMethod::Hybrid, false);
  o.min_quality = 0.4999;  // every displacement worsens the equilateral fan: none may happen
  o.corner_region = 0;
  auto r = cut2d(m, Vector2d(0.1, -2), Vector2d(0.1, 2), o);
  ASSERT_TRUE(r.ok()) << r.error();
  checkCut(m, *r, true);
  EXPECT_EQ(r->report.displaced_nodes, 0);
  EXPECT_EQ(r->report.subdivided_edges, 5);  // the three spokes the cut crosses + 2 border edges
  EXPECT_TRUE(r->change.moved_nodes.empty());
}

// --- border and corner nodes -----------------------------------------------------------

TEST(Cut2DHybrid, CornerAndBorderNodesNeverLeaveTheBorder) {
  // y = 0.1 passes near the bottom row: corners are features, the other bottom nodes are
  // border nodes whose crossing is on an interior edge (they may only move along the border).
  const TriMesh m = gridTriMesh(3, 3, 1.0);
  auto r = cut2d(m, Vector2d(-1, 0.1), Vector2d(4, 0.1), method(CutMethod::Hybrid));
  ASSERT_TRUE(r.ok()) << r.error();
  checkCut(m, *r, true);
  for (int i = 0; i <= 3; ++i) {
    const int n = r->change.node_old_to_new[i];
    EXPECT_DOUBLE_EQ(r->mesh.X(n, 1), 0.0) << "bottom node " << i;
  }
  EXPECT_DOUBLE_EQ(r->mesh.X(r->change.node_old_to_new[0], 0), 0.0);
  EXPECT_DOUBLE_EQ(r->mesh.X(r->change.node_old_to_new[3], 0), 3.0);
  EXPECT_NEAR(totalArea(r->mesh), totalArea(m), 1e-9 * totalArea(m));
}

// --- partial and progressive cuts, errors ---------------------------------------------

TEST(Cut2D, CutEndingInsideLeavesOnePiece) {
  const TriMesh m = gridTriMesh(4, 3, 1.0);
  for (CutMethod cm : {CutMethod::Standard, CutMethod::Hybrid, CutMethod::Snap}) {
    auto r = cut2d(m, Vector2d(-1, 1.5), Vector2d(2.3, 1.5), method(cm));
    ASSERT_TRUE(r.ok()) << r.error();
    checkCut(m, *r, false);
    int comps = 0;
    elementComponents(r->mesh, &comps);
    EXPECT_EQ(comps, 1) << cutMethodName(cm);
    EXPECT_NEAR(totalArea(r->mesh), totalArea(m), 1e-9 * totalArea(m));
  }
}

TEST(Cut2D, ProgressiveCutInTwoCallsSeparates) {
  const TriMesh m = gridTriMesh(4, 3, 1.0);
  for (CutMethod cm : {CutMethod::Standard, CutMethod::Hybrid}) {
    auto r1 = cut2d(m, Vector2d(-1, 1.5), Vector2d(2.5, 1.5), method(cm));
    ASSERT_TRUE(r1.ok()) << r1.error();
    // Continue from the crack tip (the last node on the cut).
    double tipX = -1;
    Vector2d tip;
    for (int n : r1->change.cut_nodes)
      if (r1->mesh.X(n, 0) > tipX) {
        tipX = r1->mesh.X(n, 0);
        tip = Vector2d(r1->mesh.X(n, 0), r1->mesh.X(n, 1));
      }
    auto r2 = cut2d(r1->mesh, tip, Vector2d(5, tip.y()), method(cm));
    ASSERT_TRUE(r2.ok()) << r2.error();
    checkCut(r1->mesh, *r2, true);
  }
}

TEST(Cut2D, BadInputIsAnError) {
  const TriMesh m = gridTriMesh(2, 2, 1.0);
  EXPECT_FALSE(cut2d(m, std::vector<Vector2d>{Vector2d(0, 0)}).ok());
  EXPECT_FALSE(cut2d(m, Vector2d(0, 0), Vector2d(NAN, 1)).ok());
  TriMesh bent = m;
  bent.X(4, 2) = 1.0;
  auto r = cut2d(bent, Vector2d(-1, 0.5), Vector2d(3, 0.5));
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("planar"), std::string::npos);
  CutMethod cm;
  EXPECT_FALSE(parseCutMethod("laser", &cm));
  EXPECT_TRUE(parseCutMethod("snap", &cm));
  EXPECT_EQ(cm, CutMethod::Snap);
}

TEST(Cut2D, MissingTheMeshChangesNothing) {
  const TriMesh m = gridTriMesh(2, 2, 1.0);
  auto r = cut2d(m, Vector2d(5, 5), Vector2d(6, 7));
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->mesh.numTris(), m.numTris());
  EXPECT_TRUE(r->change.added_elements.empty());
  EXPECT_EQ(r->mesh.X, m.X);
}

TEST(Cut2DHybrid, Fig4SpecialCaseDisplacesTheNodeAlongItsOwnEdge) {
  // A fan around node 0 = (0, 0.2); the cut y = 0 crosses the spoke 0-1 at 0.2 of its length
  // from node 0 (snap region). Projecting node 0 onto the cut, to (0, 0), would fold the
  // elements (0, 3, 4) and (0, 5, 3): the edge 3-4 crosses y = 0 at x = 0.025. The node is displaced onto
  // the cut at the crossing point on its own edge, (0.2, 0), instead (Fig. 4 special case).
  TriMesh m;
  m.X.setZero(6, 3);
  m.X.row(0) << 0.0, 0.2, 0;
  m.X.row(1) << 1.0, -0.8, 0;
  m.X.row(2) << 1.2, 0.9, 0;
  m.X.row(3) << -0.05, 0.15, 0;
  m.X.row(4) << 0.15, -0.25, 0;
  m.X.row(5) << -0.6, 0.6, 0;  // node 3 is a border corner (24 degrees): it stays
  m.F.resize(5, 3);
  m.F << 0, 1, 2, 0, 2, 5, 0, 5, 3, 0, 3, 4, 0, 4, 1;
  m.material.setOnes(5);
  ASSERT_TRUE(validate(m).ok()) << validate(m).error();
  Cut2DOptions o = method(CutMethod::Hybrid, false);
  o.min_quality = 0.001;  // isolate the fold test from the quality threshold
  o.corner_region = 0;
  auto r = cut2d(m, Vector2d(-2, 0), Vector2d(2, 0), o);
  ASSERT_TRUE(r.ok()) << r.error();
  checkCut(m, *r, true);
  const int n0 = r->change.node_old_to_new[0];
  EXPECT_NEAR(r->mesh.X(n0, 0), 0.2, 1e-12);
  EXPECT_NEAR(r->mesh.X(n0, 1), 0.0, 1e-12);
  EXPECT_GE(r->report.displaced_nodes, 1);
  EXPECT_NEAR(totalArea(r->mesh), totalArea(m), 1e-12);
}

TEST(Cut2DHybrid, CutNearACornerIsBentThroughTheCorner) {
  // The cut enters the bottom border 0.2 from the corner (0, 0), a feature that cannot move:
  // it is bent to start at the corner instead of cutting off a sliver of it.
  const TriMesh m = gridTriMesh(4, 4, 1.0);
  const Vector2d a(0.2, 0), dir = Vector2d(1, 1.2).normalized();
  auto r = cut2d(m, a - 0.5 * dir, a + 10 * dir, method(CutMethod::Hybrid));
  ASSERT_TRUE(r.ok()) << r.error();
  checkCut(m, *r, true);
  const int corner = r->change.node_old_to_new[0];
  EXPECT_EQ(r->mesh.X(corner, 0), 0.0);
  EXPECT_EQ(r->mesh.X(corner, 1), 0.0);
  bool cornerOnCut = false;
  for (int n : r->change.cut_nodes) cornerOnCut = cornerOnCut || (r->mesh.X(n, 0) == 0.0 && r->mesh.X(n, 1) == 0.0);
  EXPECT_TRUE(cornerOnCut);
  const auto s = computeStats(r->mesh);
  EXPECT_GE(s.q_min, 0.27);
  EXPECT_LE(s.elements, m.numTris());
  // Without the bend the corner keeps a sliver.
  Cut2DOptions plain = method(CutMethod::Hybrid);
  plain.corner_region = 0;
  auto r2 = cut2d(m, a - 0.5 * dir, a + 10 * dir, plain);
  ASSERT_TRUE(r2.ok()) << r2.error();
  EXPECT_LT(computeStats(r2->mesh).q_min, s.q_min);
}

TEST(Cut2DHybrid, OptimisationFlipsAndMovesCutNodesToRepairQuality) {
  const auto m = readTriMesh(std::string(HYSIM_TEST_DATA_DIR) + "/cutting/table1_mesh2.msh");
  ASSERT_TRUE(m.ok()) << m.error();
  Cut2DOptions o = method(CutMethod::Hybrid);
  Cut2DOptions noRepair = o;
  noRepair.optimize.repair_rounds = 0;
  const Vector2d a(-25, -6), b(25, 3);
  auto r = cut2d(*m, a, b, o);
  auto r0 = cut2d(*m, a, b, noRepair);
  ASSERT_TRUE(r.ok() && r0.ok());
  checkCut(*m, *r, true);
  EXPECT_GT(r->report.repair_moves, 0);
  EXPECT_GT(computeStats(r->mesh).q_min, computeStats(r0->mesh).q_min);
  // Cut nodes stay on the cut line.
  const Vector2d d = (b - a).normalized();
  for (int n : r->change.cut_nodes) {
    const Vector2d p(r->mesh.X(n, 0), r->mesh.X(n, 1));
    EXPECT_NEAR(std::abs(d.x() * (p - a).y() - d.y() * (p - a).x()), 0.0, 1e-9);
  }
}

// --- randomized complete cuts ------------------------------------------------------------

struct RandomCase {
  std::string name;
  TriMesh mesh;
  bool straightBorder;
};

// DistMesh meshes: the two Table-1 meshes (`hysim tables --table 1 --meshes DIR`), a
// rectangle with h0 = 9 (four corners) and an ellipse (semi-axes 1 and 0.6, h0 = 0.12,
// curvature varying along the border), all made with tools/distmesh.cpp.
std::vector<RandomCase> randomMeshes() {
  std::vector<RandomCase> out;
  for (const char* name : {"table1_mesh1.msh", "table1_mesh2.msh", "distmesh_rect_h9.msh", "distmesh_ellipse.msh"}) {
    auto m = readTriMesh(std::string(HYSIM_TEST_DATA_DIR) + "/cutting/" + name);
    EXPECT_TRUE(m.ok()) << m.error();
    const std::string n(name);
    if (m.ok()) out.push_back({n, *m, n == "table1_mesh1.msh" || n == "distmesh_rect_h9.msh"});
  }
  return out;
}

// Smallest angle (degrees) between the line p0-p1 and the border edges it crosses. A cut
// meeting the border at an angle alpha leaves a wedge whose element has an angle <= alpha,
// so q <= 4 sin(alpha/2) sin^2(45deg + alpha/4)... below 0.27 for alpha < ~19 degrees: no
// triangulation of the cut mesh can meet the quality bound there.
double borderCrossingAngleDeg(const TriMesh& m, const Vector2d& p0, const Vector2d& p1) {
  std::map<std::pair<int, int>, int> count;
  for (int f = 0; f < m.numTris(); ++f)
    for (int k = 0; k < 3; ++k) {
      auto e = std::minmax(m.F(f, k), m.F(f, (k + 1) % 3));
      ++count[{e.first, e.second}];
    }
  const Vector2d d = (p1 - p0).normalized();
  auto side = [&](const Vector2d& q) { return d.x() * (q - p0).y() - d.y() * (q - p0).x(); };
  double best = 90;
  for (const auto& [e, c] : count) {
    if (c != 1) continue;
    const Vector2d a(m.X(e.first, 0), m.X(e.first, 1)), b(m.X(e.second, 0), m.X(e.second, 1));
    if ((side(a) > 0) == (side(b) > 0)) continue;
    best = std::min(best, std::acos(std::min(1.0, std::abs((b - a).normalized().dot(d)))) * 180 / M_PI);
  }
  return best;
}

// The acceptance of the hybrid method on complete straight cuts: element count and distinct
// node positions within +5%, q_min >= 0.27 and >= 0.7x the initial q_min, valid, sides
// separated, area kept. Cuts meeting the border at less than 25 degrees are skipped (see
// borderCrossingAngleDeg: the bound is geometrically impossible below ~19 degrees).
TEST(Cut2DRandom, CompleteStraightCutsMeetTheAcceptance) {
  std::mt19937 rng(12345);
  int cases = 0, hybridCases = 0;
  for (const auto& rc : randomMeshes()) {
    const TriMesh& m = rc.mesh;
    const auto s0 = computeStats(m);
    const int d0 = countDistinctPositions(m);
    const double A0 = totalArea(m);
    const Vector2d lo(m.X.col(0).minCoeff(), m.X.col(1).minCoeff()), hi(m.X.col(0).maxCoeff(), m.X.col(1).maxCoeff());
    const Vector2d c = 0.5 * (lo + hi);
    const double R = (hi - lo).norm();
    std::uniform_real_distribution<double> ang(0, M_PI), off(-0.3, 0.3);
    double worstRatio = 1e9, worstQ = 1, worstGrowth = 0, worstNodes = 0;
    int tried = 0;
    for (int k = 0; k < 60; ++k) {
      const double a = ang(rng);
      const Vector2d dir(std::cos(a), std::sin(a)), nrm(-dir.y(), dir.x());
      const Vector2d mid = c + off(rng) * (hi - lo).minCoeff() * nrm;
      const Vector2d p0 = mid - R * dir, p1 = mid + R * dir;
      if (borderCrossingAngleDeg(m, p0, p1) < 25) continue;
      ++tried;
      for (CutMethod cm : {CutMethod::Standard, CutMethod::Hybrid, CutMethod::Snap}) {
        SCOPED_TRACE(rc.name + " " + cutMethodName(cm) + " cut " + std::to_string(k));
        auto r = cut2d(m, p0, p1, method(cm));
        ASSERT_TRUE(r.ok()) << r.error();
        checkCut(m, *r, true);
        const double dA = std::abs(totalArea(r->mesh) - A0) / A0;
        if (cm == CutMethod::Standard || rc.straightBorder) EXPECT_LT(dA, 1e-9);
        else EXPECT_LT(dA, 1e-3);
        if (cm == CutMethod::Hybrid) {
          const auto s = computeStats(r->mesh);
          const int d = countDistinctPositions(r->mesh);
          worstRatio = std::min(worstRatio, s.q_min / s0.q_min);
          worstQ = std::min(worstQ, s.q_min);
          worstGrowth = std::max(worstGrowth, static_cast<double>(s.elements) / s0.elements);
          worstNodes = std::max(worstNodes, static_cast<double>(d) / d0);
          EXPECT_GE(s.q_min, 0.27);
          EXPECT_GE(s.q_min, 0.7 * s0.q_min);
          EXPECT_LE(s.elements, 1.05 * s0.elements);
          EXPECT_LE(d, 1.05 * d0);
          ++hybridCases;
        }
        ++cases;
      }
    }
    EXPECT_GE(tried, 40) << rc.name;
    std::printf("%s: %d hybrid cuts, worst q_min %.3f (%.3f x initial), worst growth: elements %.3f, positions %.3f\n",
                rc.name.c_str(), tried, worstQ, worstRatio, worstGrowth, worstNodes);
  }
  EXPECT_GE(hybridCases, 160);
  EXPECT_GE(cases, 480);
}

}  // namespace
}  // namespace hysim::cutting
