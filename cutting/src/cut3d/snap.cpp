// Stage 2, snapping (hybrid / snap only): nodes near the cut move onto it, others away from
// it (move_away.cpp); the cut is routed through the nodes that could do neither.
#include <algorithm>
#include <cmath>

#include "cut3d_stages.hpp"

namespace hysim::cutting::cut3d_detail {

namespace {

// An end node of a crossed edge whose crossing lies within `limit` (fraction of the edge) of
// it: the snap candidates, and the routing candidates. Nearest first, ties in edge order.
struct EndCandidate {
  double frac;
  std::int32_t node, edge;
};

std::vector<EndCandidate> endCandidates(const std::vector<CrossedEdge>& crossed, double limit, bool alive_only) {
  std::vector<EndCandidate> out;
  for (int e = 0; e < static_cast<int>(crossed.size()); ++e) {
    const CrossedEdge& c = crossed[e];
    if (alive_only && !c.alive) continue;
    if (c.t <= limit) out.push_back({c.t, c.a, e});
    if (1.0 - c.t <= limit) out.push_back({1.0 - c.t, c.b, e});
  }
  std::stable_sort(out.begin(), out.end(), [](const EndCandidate& x, const EndCandidate& y) { return x.frac < y.frac; });
  return out;
}

}  // namespace

void Cut3D::snap() {
  guardSeen.assign(N0, 0);
  bfCache.start.assign(N0, -1);
  bfCache.count.assign(N0, 0);
  bfCache.local.assign(N0, -1);
  snapOntoCut();
  moveAway();
  routeThroughNodes();
  lap(result.report.snap_ms);
}

// A node whose crossing lies within the snap region of it moves onto the cut, if the guard
// lets it; an interior node refused at the nearest point of the cut tries the crossing on its
// edge instead.
void Cut3D::snapOntoCut() {
  const double region = options.method == CutMethod::Hybrid ? options.snap_region
                        : options.method == CutMethod::Snap ? 0.5
                                                            : 0.0;
  if (!(region > 0) || crossed.empty()) return;
  Cut3DReport& report = result.report;
  const std::vector<EndCandidate> candidates = endCandidates(crossed, region, /*alive_only=*/false);
  std::vector<std::uint8_t> refused(N0, 0);
  for (const auto& cand : candidates) {
    const int n = cand.node;
    if (on[n] || !crossed[cand.edge].alive) continue;
    Vec3 target;
    bool boundary = false, ridgeSnap = false;
    if (!snapTarget(n, cand.edge, region, &target, &boundary, &ridgeSnap)) continue;
    bool ok = false;
    for (int attempt = 0; attempt < (boundary ? 1 : 2) && !ok; ++attempt) {
      if (attempt == 1) target = crossingPoint(crossed[cand.edge]);
      ok = guardOk(n, target);
    }
    if (!ok) {
      if (!refused[n]) ++report.refused_snaps;
      refused[n] = 1;
      continue;
    }
    w.setX(n, target);
    on[n] = 1;
    if (plane) phi[n] = 0;
    onNodes.push_back(n);
    moved.push_back(n);
    ++report.snapped_nodes;
    if (boundary) ++report.boundary_snaps;
    if (ridgeSnap) ++report.ridge_snaps;
    for (int x = crossOff[n]; x < crossOff[n + 1]; ++x) crossed[crossAt[x]].alive = false;
  }
}

// Where n would go; false where it may not move (counted as a feature skip).
bool Cut3D::snapTarget(int n, int edge, double region, Vec3* target, bool* boundary, bool* ridgeSnap) {
  boundaryFacesOf(n, candBf);
  *boundary = !candBf.empty();
  if (*boundary) return boundarySnapTarget(n, edge, region, target, ridgeSnap);
  *target = plane ? Vec3(w.x(n) - phi[n] * surface.planeNormal()) : crossed[edge].point;
  return true;
}

// Boundary nodes stay within the boundary: only where it is flat around them (no feature
// edge or corner), sliding along the crossed boundary edge, or else within the boundary's
// tangent plane onto the cut; a ridge node slides along a crossed ridge edge.
bool Cut3D::boundarySnapTarget(int n, int edge, double region, Vec3* target, bool* ridgeSnap) {
  const CrossedEdge& ce = crossed[edge];
  const int other = ce.a == n ? ce.b : ce.a;
  bool feature = false, boundaryEdge = false;
  const Vec3 firstNormal = candBf.front().normal;
  Vec3 normalSum = Vec3::Zero();  // mean boundary normal at n (its tangent plane)
  for (const BFace& bf : candBf) {
    normalSum += bf.normal;
    if (bf.normal.dot(firstNormal) < cosFeature) feature = true;
    if (bf.u == other || bf.v == other) boundaryEdge = true;
  }
  if (feature) {
    *ridgeSnap = options.method == CutMethod::Hybrid && ridgeTarget(n, region, target);
    if (!*ridgeSnap) ++result.report.feature_skips;
    return *ridgeSnap;
  }
  if (boundaryEdge) {
    *target = crossingPoint(ce);
    return true;
  }
  if (tangentTarget(n, edge, normalSum, target)) return true;
  ++result.report.feature_skips;
  return false;
}

// A ridge node's slide along a crossed feature edge onto the cut (it stays on the feature
// line), as far as featureEdgesOf allows.
bool Cut3D::ridgeTarget(int n, double region, Vec3* target) {
  const FeatureEdges fe = featureEdgesOf(n);
  const double reach = fe.straight ? region : fe.polyhedral ? 0.0 : std::min(region, options.feature_slide_fraction);
  for (int r : fe.to) {
    const std::int32_t* it = edgeIndex.find(edgeKey(n, r));
    if (!it) continue;
    const CrossedEdge& re = crossed[*it];
    if (!re.alive || (re.a == n ? re.t : 1.0 - re.t) > reach) continue;
    *target = crossingPoint(re);
    return true;
  }
  return false;
}

// Onto the cut within the tangent plane of a flat boundary; false where the cut is nearly
// parallel to the boundary, or (curved surface) the hit triangle's plane is not the surface.
bool Cut3D::tangentTarget(int n, int edge, const Vec3& normalSum, Vec3* target) const {
  const CrossedEdge& ce = crossed[edge];
  const Vec3 m = normalSum.normalized();
  // Cut plane near n: the plane itself, or the plane of the hit triangle.
  const Vec3 cn = plane ? surface.planeNormal() : crossedNormal[edge];
  const double dist = plane ? phi[n] : cn.dot(w.x(n) - ce.point);
  const Vec3 d = cn - cn.dot(m) * m;  // steepest direction within the tangent plane
  const double slope = cn.dot(d);
  if (!(slope > 0.25)) return false;
  *target = w.x(n) - (dist / slope) * d;
  return plane || surface.within(*target, 10 * eps);
}

// Hybrid: a crossing still within through_node_fraction * |e| of an end node that could not
// be snapped would leave a tiny edge and slivers. The cut passes through that node instead:
// it is treated as lying on the surface and its crossed edges are not split; the cut surface
// is then approximated locally, off by at most through_node_fraction * |e|.
void Cut3D::routeThroughNodes() {
  if (!(options.method == CutMethod::Hybrid && options.through_node_fraction > 0 && !crossed.empty())) return;
  Cut3DReport& report = result.report;
  const std::vector<EndCandidate> near =
      endCandidates(crossed, std::nextafter(options.through_node_fraction, 0.0), /*alive_only=*/true);
  for (const auto& nr : near) {
    const int n = nr.node;
    if (on[n] || !crossed[nr.edge].alive) continue;
    if (approx.empty()) approx.assign(N0, 0);
    approx[n] = 1;
    on[n] = 1;
    onNodes.push_back(n);
    ++report.routed_nodes;
    for (int x = crossOff[n]; x < crossOff[n + 1]; ++x) {
      // Edges crossed nearer n than their other end now end on the cut; the others
      // (crossed nearer the other end, which may itself be routed through) stay split.
      CrossedEdge& ce = crossed[crossAt[x]];
      if ((ce.a == n ? ce.t : 1.0 - ce.t) <= 0.5) ce.alive = false;
    }
  }
  if (approx.empty()) return;
  // Two routed nodes on opposite sides: their edge is split after all (else one tet would
  // hold both), unless the crossing is too near one of them.
  for (auto& ce : crossed)
    if (!ce.alive && approx[ce.a] && approx[ce.b] && ce.t >= options.through_node_fraction &&
        1.0 - ce.t >= options.through_node_fraction)
      ce.alive = true;
  for (int n = 0; n < N0; ++n)
    if (approx[n])
      report.max_route_deviation_mm =
          std::max(report.max_route_deviation_mm, std::abs(plane ? phi[n] : surface.signedDistance(w.x(n))));
}

}  // namespace hysim::cutting::cut3d_detail
