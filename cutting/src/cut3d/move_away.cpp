// Stage 2a (hybrid, plane): a node not on the cut whose crossed edges are still cut within
// away_fraction * |e| of it would leave tiny edges and slivers after the split. It moves away
// from the plane instead (interior: along the normal; flat boundary: within its tangent
// plane; ridge: along a ridge edge), just far enough that every crossing on its edges lies at
// >= away_fraction of the edge; if the guard refuses, at a fraction of that. The cut stays
// exactly the plane: only the crossings move along their edges.
#include <algorithm>
#include <cmath>
#include <limits>

#include "cut3d_stages.hpp"

namespace hysim::cutting::cut3d_detail {

void Cut3D::moveAway() {
  if (!(options.method == CutMethod::Hybrid && plane && options.away_fraction > 0 && !crossed.empty())) return;
  const double f = std::min(options.away_fraction, 0.45);
  const Vec3 pn = surface.planeNormal().normalized();
  struct Near {
    double frac;
    std::int32_t node;
  };
  std::vector<Near> near;
  for (const auto& c : crossed) {
    if (!c.alive) continue;
    if (c.t < f) near.push_back({c.t, c.a});
    if (1.0 - c.t < f) near.push_back({1.0 - c.t, c.b});
  }
  std::stable_sort(near.begin(), near.end(), [](const Near& x, const Near& y) { return x.frac < y.frac; });
  std::vector<std::uint8_t> tried(N0, 0);
  for (const auto& nr : near) {
    const int n = nr.node;
    if (on[n] || tried[n]) continue;
    tried[n] = 1;
    // |phi| that puts every crossing on n's edges at >= f of the edge.
    double need = 0;
    for (int x = crossOff[n]; x < crossOff[n + 1]; ++x) {
      const CrossedEdge& ce = crossed[crossAt[x]];
      if (ce.alive) need = std::max(need, f / (1.0 - f) * std::abs(phi[ce.a == n ? ce.b : ce.a]));
    }
    const double sgn = phi[n] > 0 ? 1.0 : -1.0;
    if (!(need > std::abs(phi[n]))) continue;
    Vec3 dir;
    double rate, maxStep = std::numeric_limits<double>::infinity();
    if (awayDirection(n, sgn, pn, &dir, &rate, &maxStep)) moveAwayBy(n, need, dir, rate, maxStep);
  }
}

// Direction (unit) in which n moves away, the rate at which |phi| grows along it and the
// longest step allowed; false where no direction raises |phi| fast enough.
bool Cut3D::awayDirection(int n, double sgn, const Vec3& pn, Vec3* dir, double* rate, double* maxStep) {
  boundaryFacesOf(n, candBf);
  const std::vector<BFace>& bf = candBf;
  if (bf.empty()) {
    *dir = sgn * pn;
    *rate = 1.0;
    return true;
  }
  bool feature = false;
  Vec3 m = Vec3::Zero();
  for (const auto& b : bf) {
    if (b.normal.dot(bf[0].normal) < cosFeature) feature = true;
    m += b.normal;
  }
  if (!feature) {
    m.normalize();
    const Vec3 d = pn - pn.dot(m) * m;  // steepest direction within the tangent plane
    *rate = d.norm();
    if (!(*rate > 0.25)) return false;  // plane nearly parallel to the boundary there
    *dir = sgn * d / *rate;
    return true;
  }
  // Along the ridge edge on which |phi| grows fastest, at most half of it.
  *rate = 0;
  const auto fe = featureEdgesOf(n);
  for (int r : fe.to) {
    const Vec3 e = w.x(r) - w.x(n);
    const double len = e.norm();
    const double g = sgn * (phi[r] - phi[n]) / len;
    if (on[r] || !(g > *rate)) continue;
    *rate = g;
    *dir = e / len;
    *maxStep = (fe.straight ? 0.5 : fe.polyhedral ? 0.0 : options.feature_slide_fraction) * len;
  }
  return *rate > 0.25;
}

// The longest of the steps toward |phi| = need the guard allows, if any.
void Cut3D::moveAwayBy(int n, double need, const Vec3& dir, double rate, double maxStep) {
  const Vec3 pn = surface.planeNormal().normalized(), pp = surface.planePoint();
  const double have = std::abs(phi[n]);
  for (const double level : {1.0, 0.75, 0.5, 0.35, 0.25}) {
    const double want = level * need;
    if (!(want > have)) break;
    const double step = (want - have) / rate;
    if (step > maxStep) continue;
    const Vec3 target = w.x(n) + step * dir;
    if (!guardOk(n, target)) continue;
    w.setX(n, target);
    phi[n] = pn.dot(target - pp);
    for (int x = crossOff[n]; x < crossOff[n + 1]; ++x) {
      CrossedEdge& ce = crossed[crossAt[x]];
      ce.t = phi[ce.a] / (phi[ce.a] - phi[ce.b]);
    }
    moved.push_back(n);
    ++result.report.away_moves;
    return;
  }
}

}  // namespace hysim::cutting::cut3d_detail
