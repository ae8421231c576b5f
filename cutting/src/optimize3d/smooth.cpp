// Smoothing: nodes of poor tets near the cut move, within their constraint (constraints.cpp).
// Candidate moves (ascent along the gradient of the worst incident element's q*, a damped
// spring step toward the local mean edge length, a push away from the face opposite the node
// in its worst element; each tried at decreasing lengths) are kept only if no incident tet
// inverts and the worst incident q* rises: the local minimum quality never drops. Iterated
// over the nodes around the ones that moved until the moves get small.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

#include "cut_optimizer.hpp"
#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::cutting::opt3d {
namespace {

Vec3 project(const Constraint& c, Vec3 d) {
  if (c.kind != Freedom::Free && c.kind != Freedom::Ridge) d -= d.dot(c.normal) * c.normal;
  return d;
}

// Unit direction of the allowed part of d (zero when d is (nearly) all normal: the remainder
// would be rounding noise).
Vec3 unitIn(const Constraint& c, const Vec3& d) {
  const Vec3 p = project(c, d);
  const double len = p.norm();
  return len > 1e-6 * d.norm() && len > 0 ? Vec3(project(c, p / len)) : Vec3::Zero();
}

}  // namespace

void CutOptimizer::smooth() {
  int it = 0;
  bfStart.assign(N, -1);  // constraintOf keeps the boundary faces per node (see there)
  bfLen.assign(N, 0);
  cons.bfPool.clear();
  for (; it < options.max_iterations && !work.empty(); ++it) {
    mv.largest = mv.scale = 0;
    movedNow.clear();
    timed(&OptimizeCounts::move_ms, [&] { moveRun(work); });
    const double largest = mv.largest, scale = mv.scale;
    work.clear();
    for (int n : movedNow) addBadAround(n, it + 1);
    if (largest <= options.stop_fraction * scale) {
      ++it;
      break;
    }
  }
  bfStart.clear();
  if (counts) counts->iterations = it;
}

// One node's move: it reads the positions of n and its neighbours and writes n's; appends n
// to movedNow where it moved.
void CutOptimizer::moveNode(int n) {
  MoveTry mt;
  mt.n = n;
  double before = 0;
  if (!prepareMove(mt, &before)) return;
  const Vec3 x = mt.x;
  const Constraint& c = mt.c;
  double best = before, bestDv = 0;
  Vec3 bestX = x;
  mt.farFromCut = curved && !onCut[n] ? -1 : 0;  // -1: not asked yet
  mv.starVolume.clear();
  for (const Vec3& d : mt.dirs) {
    if (d.squaredNorm() == 0) continue;
    double step = 1.0;
    for (int tries = 0; tries < 5; ++tries, step *= 0.5) {
      Vec3 y = x + step * d;
      if (!placeCandidate(mt, y)) continue;
      // The checks below must all pass and have no side effects on the outcome (their
      // caches and starAbove's lastBelow only skip or order work), so any order gives the
      // same moves: the cheapest first (the worst tet, which starAbove tries first anyway),
      // then the volume check (it fails often), the surface queries after it.
      const double qFirst = wtQAt(mt, y);
      if (!(qFirst > best)) continue;
      // Moves on a curved surface change the volume a little (the faces are chords): within the budget.
      double dv = 0;
      if (curved && (c.kind == Freedom::Surface || c.kind == Freedom::Fan || c.kind == Freedom::Ridge) &&
          !moveVolumeOk(mt, y, &dv))
        continue;
      if (!sideOk(mt, y)) continue;
      double q = 0;
      if (starAbove(n, y, mt.wt, qFirst, best, &q)) {
        best = q;
        bestX = y;
        bestDv = dv;
        break;
      }
    }
  }
  if (best > before) {
    mv.largest = std::max(mv.largest, (bestX - x).norm());
    if (mv.split) {
      mv.net += bestDv;
      mv.churn += std::abs(bestDv);
    } else {
      moveBudget.spend(bestDv);
    }
    ed.setPosition(n, bestX);
    didMove[n] = 1;
    movedNow.push_back(n);
  }
}

// The node's worst tet, constraint and candidate directions; false where it does not move
// (its star is good enough, or it is fixed). *before: the worst q* around it.
bool CutOptimizer::prepareMove(MoveTry& mt, double* before) {
  const int n = mt.n;
  // (The cached quality test before the constraint, which looks at the whole star.)
  int wt = -1;
  *before = ed.worstAround(n, &wt);
  if (*before < 0 || *before >= options.quality_target || wt < 0) return false;
  const Constraint c = constraintOf(n);
  if (c.kind == Freedom::Fixed) return false;
  const Vec3 x = ed.position(n);
  mt.wt = wt;
  mt.c = c;
  mt.x = x;
  double sum = 0;
  int deg = 0;
  Vec3 force = Vec3::Zero();
  for (const std::int32_t *s = ed.starBegin(n), *sEnd = ed.starEnd(n); s < sEnd; ++s) {
    if (dead[(*s)]) continue;
    for (int k = 0; k < 4; ++k) {
      const int m = mesh.T((*s), k);
      if (m == n) continue;
      sum += (ed.position(m) - x).norm();
      ++deg;
    }
  }
  if (deg == 0) return false;
  const double h = sum / deg;
  mv.scale = std::max(mv.scale, h);
  for (const std::int32_t *s = ed.starBegin(n), *sEnd = ed.starEnd(n); s < sEnd; ++s) {
    if (dead[(*s)]) continue;
    for (int k = 0; k < 4; ++k) {
      const int m = mesh.T((*s), k);
      if (m == n) continue;
      const Vec3 d = ed.position(m) - x;
      const double len = d.norm();
      if (len > 0) force += (len - h) * d / len;
    }
  }
  // The worst tet's corners, n's at wtK (for ed.qualityWith(wt, n, y) below: the same values).
  Vec3* wtP = mt.wtP;
  int& wtK = mt.wtK;
  wtK = -1;
  for (int k = 0; k < 4; ++k) {
    const int v = mesh.T(wt, k);
    wtP[k] = ed.position(v);
    if (v == n) wtK = k;
  }
  // Gradient of the worst element's q* (central differences).
  Vec3 grad = Vec3::Zero();
  const double fd = 1e-4 * h;
  for (int a = 0; a < 3; ++a) {
    Vec3 e = Vec3::Zero();
    e[a] = fd;
    grad[a] = (wtQAt(mt, x + e) - wtQAt(mt, x - e)) / (2 * fd);
  }
  grad = unitIn(c, grad);
  // Push: away from the face opposite n in its worst tet.
  Vec3 face[3];
  int f = 0;
  for (int k = 0; k < 4; ++k)
    if (mesh.T(wt, k) != n) face[f++] = ed.position(mesh.T(wt, k));
  Vec3 push = (face[1] - face[0]).cross(face[2] - face[0]);
  if (push.norm() > 0) push.normalize();
  if (push.dot(x - face[0]) < 0) push = -push;
  push = unitIn(c, push);
  const Vec3 spring = options.step_gain * 2.0 * force / deg;
  mt.dirs[0] = 0.25 * h * grad;
  mt.dirs[1] = spring.norm() * unitIn(c, spring);
  mt.dirs[2] = 0.3 * h * push;
  keepMaterials(mt);
  return true;
}

// A node between materials moves perpendicular to each material's volume gradient (the sum
// over its tets of that material): the volume is linear in one node's position, so every
// material keeps its volume exactly and the interface does not drift. Constraints that put
// the candidate onto a surface afterwards (Surface, Fan, Ridge) are left to the budgets.
void CutOptimizer::keepMaterials(MoveTry& mt) {
  if (mt.c.kind != Freedom::Free && mt.c.kind != Freedom::Plane) return;
  std::int32_t labels[4];
  Vec3 grads[4];
  int numLabels = 0;
  const int n = mt.n;
  for (const std::int32_t *s = ed.starBegin(n), *sEnd = ed.starEnd(n); s < sEnd; ++s) {
    if (dead[*s]) continue;
    const std::int32_t label = labelOf(mesh, *s);
    int i = 0;
    while (i < numLabels && labels[i] != label) ++i;
    if (i == numLabels) {
      if (numLabels == 4) return;
      labels[numLabels] = label;
      grads[numLabels++] = Vec3::Zero();
    }
    int k = 0;
    while (mesh.T(*s, k) != n) ++k;
    grads[i] += tetVolumeGradient(mesh, *s, k);
  }
  if (numLabels < 2) return;
  Vec3 basis[3];
  int nb = 0;
  if (mt.c.kind == Freedom::Plane) basis[nb++] = mt.c.normal.normalized();
  for (int i = 0; i < numLabels && nb < 3; ++i) {
    Vec3 g = grads[i];
    const double scale = g.norm();
    for (int b = 0; b < nb; ++b) g -= g.dot(basis[b]) * basis[b];
    if (g.norm() > 1e-9 * scale) basis[nb++] = g.normalized();
  }
  for (Vec3& d : mt.dirs) {
    if (nb == 3) d.setZero();
    for (int b = 0; b < nb && nb < 3; ++b) d -= d.dot(basis[b]) * basis[b];
  }
}

// q* of the node's worst tet with the node at y (its corners as gathered: the same values as
// qualityWith).
double CutOptimizer::wtQAt(const MoveTry& mt, const Vec3& y) const {
  const Vec3* wtP = mt.wtP;
  switch (mt.wtK) {
    case 0: return radiusRatioOriented(y, wtP[1], wtP[2], wtP[3]);
    case 1: return radiusRatioOriented(wtP[0], y, wtP[2], wtP[3]);
    case 2: return radiusRatioOriented(wtP[0], wtP[1], y, wtP[3]);
    case 3: return radiusRatioOriented(wtP[0], wtP[1], wtP[2], y);
    default: return radiusRatioOriented(wtP[0], wtP[1], wtP[2], wtP[3]);  // (n not a corner: not expected)
  }
}

// Puts candidate y where the constraint allows (onto the cut surface, along the ridge, onto
// the boundary fan); false where the ridge offers no move.
bool CutOptimizer::placeCandidate(const MoveTry& mt, Vec3& y) {
  const Constraint& c = mt.c;
  const Vec3& x = mt.x;
  const int n = mt.n;
  if (c.kind == Freedom::Surface) onCutAgain(mt, y);
  if (c.kind == Freedom::Ridge) {  // along the ridge edge nearest the move, at most 0.45 of it
    const Vec3 d = y - x;
    double bestAlong = 0;
    Vec3 to = x;
    for (const Vec3& r : c.ridge) {
      const Vec3 e = r - x;
      const double len = e.norm();
      if (!(len > 0)) continue;
      const double along = std::min(d.dot(e) / len, 0.45 * len);
      if (along > bestAlong) {
        bestAlong = along;
        to = x + (along / len) * e;
      }
    }
    if (!(bestAlong > 0)) return false;
    y = to;
    if (onCut[n]) onCutAgain(mt, y);
  }
  if (c.kind == Freedom::Fan) {
    Vec3 best = y;
    double bestD = std::numeric_limits<double>::infinity();
    for (const auto& tri : cons.fan) {
      const Vec3 z = closestPointOnTriangle(y, tri[0], tri[1], tri[2]);
      const double dz = (z - y).squaredNorm();
      if (dz < bestD) {
        bestD = dz;
        best = z;
      }
    }
    y = best;
  }
  return true;
}

// y := its nearest point of the cut, which lies within |y - x| + dist(x) of y: the search
// looks no farther (the same point as a full search).
void CutOptimizer::onCutAgain(const MoveTry& mt, Vec3& y) {
  const int n = mt.n;
  const double r = (y - mt.x).norm() + nodeDistance(n, nullptr, onCut[n] ? region.eps : std::numeric_limits<double>::infinity());
  region.surface->signedDistanceNear(Vec3(y), r, &y);
}

// Every candidate lies within 2 x the longest direction of x (a fan's nearest point is no
// farther from y than x is). When the cut surface is farther than that from x (with a margin
// of a few eps), no candidate can cross it or come within eps of it: sideKept holds for all
// of them, and its surface queries are skipped (one query, asked when the first candidate
// gets that far, instead).
bool CutOptimizer::sideOk(MoveTry& mt, const Vec3& y) {
  if (mt.farFromCut < 0) {
    double reach = 0;
    for (const Vec3& d : mt.dirs) reach = std::max(reach, d.norm());
    mt.farFromCut = nodeWithin(mt.n, 2.0 * reach + 4.0 * region.eps) ? 0 : 1;
  }
  return mt.farFromCut == 1 || sideKept(mt.n, mt.x, y);
}

// The volume change *dv of moving the node to y, within the move budget and
// move_volume_fraction of a regular tet of the local edge. The star's volumes where the node
// is, and per live star tet the parts of its volume expression that do not depend on the
// node's position, are gathered once per node (the same operations on the same values).
bool CutOptimizer::moveVolumeOk(const MoveTry& mt, const Vec3& y, double* dvOut) {
  const int n = mt.n;
  double dv = 0;
  if (mv.starVolume.empty()) {  // the star's volumes where n is (the same for every candidate)
    // With them, per live star tet the parts of its volume expression that do not
    // depend on n's position (the corners, the differences and the cross product of
    // the fixed corners: the same operations on the same values as below).
    const double* cx = mesh.X.col(0).data();
    const double* cy = mesh.X.col(1).data();
    const double* cz = mesh.X.col(2).data();
    mv.starVol.clear();
    for (const std::int32_t *s = ed.starBegin(n), *sEnd = ed.starEnd(n); s < sEnd; ++s) {
      mv.starVolume.push_back(dead[*s] ? 0.0 : tetVolumeHere(mesh, *s));
      if (dead[*s]) continue;
      StarVolTet sv;
      double px[4], py[4], pz[4];
      sv.kn = -1;
      for (int k = 0; k < 4; ++k) {
        const int v = mesh.T(*s, k);
        if (v == n && sv.kn < 0) sv.kn = k;
        px[k] = cx[v];
        py[k] = cy[v];
        pz[k] = cz[v];
      }
      sv.old = mv.starVolume.back();
      for (int k = 0; k < 4; ++k) {
        sv.p[0][k] = px[k];
        sv.p[1][k] = py[k];
        sv.p[2][k] = pz[k];
      }
      if (sv.kn != 0) {
        sv.a[0] = px[1] - px[0], sv.a[1] = py[1] - py[0], sv.a[2] = pz[1] - pz[0];
        sv.b[0] = px[2] - px[0], sv.b[1] = py[2] - py[0], sv.b[2] = pz[2] - pz[0];
        sv.e[0] = px[3] - px[0], sv.e[1] = py[3] - py[0], sv.e[2] = pz[3] - pz[0];
        const double bx = sv.b[0], by = sv.b[1], bz = sv.b[2];
        const double ex = sv.e[0], ey = sv.e[1], ez = sv.e[2];
        sv.nrm[0] = by * ez - bz * ey, sv.nrm[1] = bz * ex - bx * ez, sv.nrm[2] = bx * ey - by * ex;
      }
      mv.starVol.push_back(sv);
    }
  }
  // (The volume of each tet with n at y in scalars, as tetVolumeHere: the same value
  // as the vector expression (p1 - p0).dot((p2 - p0).cross(p3 - p0)).)
  for (const StarVolTet& sv : mv.starVol) {
    double ax, ay, az, bx, by, bz, ex, ey, ez, vol6;
    if (sv.kn == 0) {
      ax = sv.p[0][1] - y[0], ay = sv.p[1][1] - y[1], az = sv.p[2][1] - y[2];
      bx = sv.p[0][2] - y[0], by = sv.p[1][2] - y[1], bz = sv.p[2][2] - y[2];
      ex = sv.p[0][3] - y[0], ey = sv.p[1][3] - y[1], ez = sv.p[2][3] - y[2];
    } else {
      ax = sv.a[0], ay = sv.a[1], az = sv.a[2];
      bx = sv.b[0], by = sv.b[1], bz = sv.b[2];
      ex = sv.e[0], ey = sv.e[1], ez = sv.e[2];
      const double dx = y[0] - sv.p[0][0], dy = y[1] - sv.p[1][0], dz = y[2] - sv.p[2][0];
      if (sv.kn == 1) ax = dx, ay = dy, az = dz;
      else if (sv.kn == 2) bx = dx, by = dy, bz = dz;
      else if (sv.kn == 3) ex = dx, ey = dy, ez = dz;
    }
    if (sv.kn == 1 || sv.kn < 0) {  // (kn < 0: n not a corner, not expected)
      vol6 = (ax * sv.nrm[0] + ay * sv.nrm[1]) + az * sv.nrm[2];
    } else {
      const double nx = by * ez - bz * ey, ny = bz * ex - bx * ez, nz = bx * ey - by * ex;
      vol6 = (ax * nx + ay * ny) + az * nz;
    }
#ifdef HYSIM_CHECK_EXACT
    {
      Vec3 p[4];
      for (int k = 0; k < 4; ++k)
        p[k] = k == sv.kn ? y : Vec3(sv.p[0][k], sv.p[1][k], sv.p[2][k]);
      const double ref = (p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0]));
      if (std::memcmp(&ref, &vol6, sizeof vol6) != 0) std::abort();
    }
#endif
    dv += vol6 / 6.0 - sv.old;
  }
  *dvOut = dv;
  return !(!moveFits(dv) || std::abs(dv) > options.move_volume_fraction * edgeTet);
}

// Does a move's volume change dv fit the move budget? A part of a split has half the room
// left at the split's start: |net + 2 (its net + dv)| <= limit and the same for the churn, so
// whatever both parts spend, the sum fits (the halves' mean does).
bool CutOptimizer::moveFits(double dv) const {
  if (!mv.split) return moveBudget.fits(dv);
  return std::abs(moveBudget.net + 2.0 * (mv.net + dv)) <= moveBudget.limit &&
         moveBudget.churn + 2.0 * (mv.churn + std::abs(dv)) <= moveBudget.churn_factor * moveBudget.limit;
}

// Is the worst q* around n with n at y above `floor`? Tet `first` (the likely worst) is
// tried first and the scan stops at the first tet at or below the floor; when it passes,
// *q receives the worst q* (as worstAround).
// (firstQ: ed.qualityWith(first, n, y), which the caller has already computed.)
// The answer does not depend on the order of the tets (any at or below the floor: false;
// else the minimum): the tet that failed n's last such test (lastBelow[n], where it is
// still a live tet of n) is tried second, as it is likely to fail again.
bool CutOptimizer::starAbove(int n, const Vec3& y, int first, double firstQ, double floor, double* q) {
  double worst = firstQ;
  if (!(worst > floor)) return false;
  int second = lastBelow[n];
  if (second == first || second < 0 || dead[second]) {
    second = -1;
  } else {
    bool has = false;
    for (int k = 0; k < 4; ++k) has = has || mesh.T(second, k) == n;
    if (!has) second = -1;
  }
  if (second >= 0) {
    const double qt = ed.qualityWith(second, n, y);
    if (!(qt > floor)) return false;
    worst = std::min(worst, qt);
  }
  for (const std::int32_t *s = ed.starBegin(n), *sEnd = ed.starEnd(n); s < sEnd; ++s) {
    if ((*s) == first || (*s) == second || dead[(*s)]) continue;
    const double qt = ed.qualityWith((*s), n, y);
    if (!(qt > floor)) {
      lastBelow[n] = *s;
      return false;
    }
    worst = std::min(worst, qt);
  }
  *q = std::min(1.0, worst);
  return true;
}

// The move loop's nodes in parts: after splitWork(list), partA and partB (each in list
// order) have no two nodes that are neighbours (share a tet), so neither part's moves read
// a position the other's write, and partS holds the rest. A sort along an axis by position
// puts the nodes ranked below k on the left; partA is those whose neighbours in the list
// are all on the left too, partB the right, partS the left ones with a neighbour on the
// right. k makes max(|A|, |B|) + |S| smallest.
// False where the list is too short to be worth it or no split leaves both parts nodes.
bool CutOptimizer::splitWork(const std::vector<std::int32_t>& list) {
  const int W = static_cast<int>(list.size());
  if (W < std::max(2, options.parallel_min_nodes)) return false;
  for (int i = 0; i < W; ++i) workAt[list[i]] = i;
  adjOff.assign(W + 1, 0);
  adj.clear();
  for (int i = 0; i < W; ++i) {
    const int n = list[i];
    if (ringStart[n] < 0) {  // n's neighbours (live tets), kept: the loop changes no tet
      ringStart[n] = static_cast<std::int32_t>(ringPool.size());
      for (const std::int32_t *s = ed.starBegin(n), *sEnd = ed.starEnd(n); s < sEnd; ++s) {
        if (dead[*s]) continue;
        for (int k = 0; k < 4; ++k) {
          const int m = mesh.T(*s, k);
          if (m == n || ringMark[m] == n) continue;
          ringMark[m] = n;
          ringPool.push_back(m);
        }
      }
      ringLen[n] = static_cast<std::int32_t>(ringPool.size()) - ringStart[n];
    }
    for (const std::int32_t *m = &ringPool[ringStart[n]], *mEnd = m + ringLen[n]; m < mEnd; ++m)
      if (workAt[*m] >= 0) adj.push_back(workAt[*m]);
    adjOff[i + 1] = static_cast<std::int32_t>(adj.size());
  }
  for (int n : list) workAt[n] = -1;
  // The axis: the longest side of the nodes' bounding box.
  Vec3 lo = ed.position(list[0]), hi = lo;
  for (int n : list) {
    lo = lo.cwiseMin(ed.position(n));
    hi = hi.cwiseMax(ed.position(n));
  }
  int axis = 0;
  (hi - lo).maxCoeff(&axis);
  keyed.resize(W);
  for (int i = 0; i < W; ++i) keyed[i] = {mesh.X(list[i], axis), i};
  std::sort(keyed.begin(), keyed.end());
  rankOf.resize(W);
  reach.resize(W);
  for (int r = 0; r < W; ++r) rankOf[keyed[r].second] = r;
  for (int i = 0; i < W; ++i) {  // the highest rank of a node and its neighbours
    reach[i] = rankOf[i];
    for (int j = adjOff[i]; j < adjOff[i + 1]; ++j) reach[i] = std::max(reach[i], rankOf[adj[j]]);
  }
  below.assign(W + 1, 0);  // below[k]: nodes with reach < k (partA's size at k)
  for (int i = 0; i < W; ++i) ++below[reach[i] + 1];
  for (int k = 0; k < W; ++k) below[k + 1] += below[k];
  int bestK = -1, bestCost = W;
  for (int k = 1; k < W; ++k) {
    const int sizeA = below[k], sizeB = W - k, sizeS = k - sizeA;
    const int cost = std::max(sizeA, sizeB) + sizeS;
    if (sizeA > 0 && cost < bestCost) {
      bestCost = cost;
      bestK = k;
    }
  }
  if (bestK < 0) return false;
  partA.clear();
  partB.clear();
  partS.clear();
  for (int i = 0; i < W; ++i) {
    if (rankOf[i] >= bestK) {
      partB.push_back(list[i]);
    } else if (reach[i] < bestK) {
      partA.push_back(list[i]);
    } else {
      partS.push_back(list[i]);
    }
  }
  return true;
}

// Moves the nodes of `list` (no repeats), appending the moved ones to movedNow: part A,
// then part B, each with half of the move budget left at the split's start (moveFits; both
// spend it only after B), then the rest the same way, and the last part (too short to
// split) one node after another.
void CutOptimizer::moveRun(const std::vector<std::int32_t>& list) {
  moveRest = list;
  while (splitWork(moveRest)) {
    double net[2], churn[2];
    mv.split = true;
    for (int k = 0; k < 2; ++k) {
      mv.net = mv.churn = 0;
      for (int n : k == 0 ? partA : partB) moveNode(n);
      net[k] = mv.net;
      churn[k] = mv.churn;
    }
    mv.split = false;
    for (int k = 0; k < 2; ++k) {
      moveBudget.net += net[k];
      moveBudget.churn += churn[k];
    }
    moveRest.swap(partS);
  }
  for (int n : moveRest) moveNode(n);
}

}  // namespace hysim::cutting::opt3d
