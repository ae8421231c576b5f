// Where a node may move (cut_optimizer.hpp's list): free, in a plane, on the curved cut, on
// its boundary faces (fan), along a ridge, or not at all; and the side of the cut it keeps.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

#include "cut_optimizer.hpp"
#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::cutting::opt3d {

// n's boundary faces (used by one live tet), as (tet, face) in the order first seen, into
// cons.bfPool: the faces around n by the pair of their nodes other than n, counted in a table
// over n's neighbours. While bfStart is not empty (the move loop, which changes positions
// only), each node's faces are kept and found again.
void CutOptimizer::gatherBoundaryFaces(int n) {
  ConsScratch& S = cons;
  const bool keep = !bfStart.empty();
  if (!keep || bfStart[n] < 0) {
    if (!keep) S.bfPool.clear();
    S.consFaces.clear();
    // Faces by the pair of their nodes other than n (local numbers over n's neighbours).
    S.nbrs.clear();
    const std::int32_t *sBegin = ed.starBegin(n), *sEnd = ed.starEnd(n);
    const size_t recs = 5 * static_cast<size_t>(sEnd - sBegin);
    if (S.consLocal.size() < recs) S.consLocal.resize(recs);
    std::int32_t* cl = S.consLocal.data();
    for (const std::int32_t* s = sBegin; s < sEnd; ++s)
      if (!dead[*s]) {
        *cl++ = *s;
        for (int k = 0; k < 4; ++k) {
          const int w = mesh.T(*s, k);
          if (w == n) {
            *cl++ = -1;
            continue;
          }
          if (S.localId[w] < 0) {
            S.localId[w] = static_cast<std::int32_t>(S.nbrs.size());
            S.nbrs.push_back(w);
          }
          *cl++ = S.localId[w];
        }
      }
    const std::int32_t* clEnd = cl;
    const size_t L = S.nbrs.size();
    if (S.pairCount.size() < L * L) S.pairCount.assign(L * L, -1);  // index into S.consFaces
    for (const std::int32_t* rec = S.consLocal.data(); rec < clEnd; rec += 5) {
      const std::int32_t* lt = rec + 1;
      int ln = 0;
      while (lt[ln] >= 0) ++ln;
      // The positions other than n's, p[0] < p[1] < p[2]; face f = p[r] (in f order) is the
      // pair of the other two.
      int p[3], np = 0;
      for (int k = 0; k < 4; ++k)
        if (k != ln) p[np++] = k;
      for (int r = 0; r < 3; ++r) {
        const std::int32_t x = lt[p[r == 0 ? 1 : 0]], y = lt[p[r == 2 ? 1 : 2]];
        const std::int32_t key = std::min(x, y) * static_cast<std::int32_t>(L) + std::max(x, y);
        std::int32_t& at = S.pairCount[key];
        if (at >= 0) {
          ++S.consFaces[at].count;
        } else {
          at = static_cast<std::int32_t>(S.consFaces.size());
          S.consFaces.push_back({rec[0], p[r], 1, key});
        }
      }
    }
    for (int w : S.nbrs) S.localId[w] = -1;
    if (keep) bfStart[n] = static_cast<std::int32_t>(S.bfPool.size());
    for (const FaceUse& fu : S.consFaces) {
      S.pairCount[fu.key] = -1;
      if (fu.count != 1) continue;
      S.bfPool.push_back({fu.t, fu.f});
    }
    if (keep) bfLen[n] = static_cast<std::int32_t>(S.bfPool.size()) - bfStart[n];
  }
}

Constraint CutOptimizer::constraintOf(int n) {
  ConsScratch& S = cons;
  Constraint c;
  S.faces.clear();
  gatherBoundaryFaces(n);
  const bool keep = !bfStart.empty();
  Vec3 sum = Vec3::Zero();
  bool boundary = false, allCut = true;
  const std::int32_t bfFrom = keep ? bfStart[n] : 0;
  const auto& bfPool = S.bfPool;
  const std::int32_t bfTo = keep ? bfStart[n] + bfLen[n] : static_cast<std::int32_t>(bfPool.size());
  for (std::int32_t bi = bfFrom; bi < bfTo; ++bi) {
    const int t = bfPool[bi][0], f = bfPool[bi][1];
    const int i0 = mesh.T(t, kFace[f][0]), i1 = mesh.T(t, kFace[f][1]), i2 = mesh.T(t, kFace[f][2]);
    std::int32_t o[2], m = 0;
    for (int v : {i0, i1, i2})
      if (v != n) o[m++] = v;
    if (o[0] > o[1]) std::swap(o[0], o[1]);
    const Vec3 area = (ed.position(i1) - ed.position(i0)).cross(ed.position(i2) - ed.position(i0));
    S.faces.push_back({o[0], o[1], area, area.normalized()});
    boundary = true;
    sum += area;
    allCut = allCut && onCut[o[0]] && onCut[o[1]];
  }
  const bool nodeOnCut = onCut[n] != 0;
  if (nodeOnCut) {
    if (!options.move_cut_nodes) return c;
    if (boundary && !allCut) {  // rim node
      ridgeOf(c, nodeOnCut);
      return c;
    }
    if (plane) {
      c.kind = Freedom::Plane;
      c.normal = region.surface->planeNormal();
      return c;
    }
    if (!boundary || sum.norm() == 0) return c;
    c.normal = sum.normalized();
    // A curved cut surface: slide in the tangent plane, then back onto the surface (the
    // volume changes by second-order amounts), where the cut faces around are smooth.
    c.kind = Freedom::Surface;
    for (const auto& bf : S.faces)
      if (bf.unit.dot(c.normal) < cosCurved) c.kind = Freedom::Fixed;
    return c;
  }
  if (!boundary) {
    c.kind = Freedom::Free;
    return c;
  }
  if (!options.move_boundary_nodes || sum.norm() == 0) return c;
  c.normal = sum.normalized();
  c.kind = Freedom::Plane;
  for (const auto& bf : S.faces) {
    const double cosine = bf.unit.dot(c.normal);
    if (cosine < cosCurved) {
      c.kind = Freedom::Fixed;
      ridgeOf(c, nodeOnCut);
      return c;
    }
    if (cosine < cosFlat) c.kind = Freedom::Fan;
  }
  if (c.kind == Freedom::Fan) {  // the node stays on its boundary faces as they are now
    S.fan.clear();
    for (const auto& bf : S.faces) S.fan.push_back({ed.position(n), ed.position(bf.u), ed.position(bf.v)});
  }
  return c;
}

// A node on a ridge (the rim, where the cut meets the boundary, or a crease of the boundary)
// slides along it: exactly two of its boundary edges are ridge edges (between a cut and a
// non-cut face, or faces more than ridge_deg apart). Reads cons.faces (constraintOf's).
bool CutOptimizer::ridgeOf(Constraint& c, bool nodeOnCut) {
  const ConsScratch& S = cons;
  if (!curved || !(options.ridge_deg > 0)) return false;
  int found = 0;
  for (size_t i = 0; i < S.faces.size(); ++i) {
    for (int w : {S.faces[i].u, S.faces[i].v})
      for (size_t j = i + 1; j < S.faces.size(); ++j) {
        if (S.faces[j].u != w && S.faces[j].v != w) continue;
        const bool cutI = onCut[S.faces[i].u] && onCut[S.faces[i].v] && nodeOnCut;
        const bool cutJ = onCut[S.faces[j].u] && onCut[S.faces[j].v] && nodeOnCut;
        // (On the cut only the rim counts: the node is put back onto the cut surface.)
        const bool edge = nodeOnCut ? cutI != cutJ
                                    : S.faces[i].unit.dot(S.faces[j].unit) < cosRidge;
        if (!edge) continue;
        if (found == 2) return false;
        c.ridge[found++] = ed.position(w);
      }
  }
  if (found != 2) return false;
  c.kind = Freedom::Ridge;
  c.normal = Vec3::Zero();
  return true;
}

// A node off the cut stays strictly on its side of the surface.
bool CutOptimizer::sideKept(int n, const Vec3& x, const Vec3& y) const {
  if (onCut[n] || region.surface == nullptr) return true;
  if (plane) {
    const Vec3 pn = region.surface->planeNormal(), pp = region.surface->planePoint();
    const double a = pn.dot(x - pp), b = pn.dot(y - pp);
    return a * b > 0 && std::abs(b) > region.eps;
  }
  CutSurface::Hit hit;
  return !region.surface->intersectSegment(x, y, region.eps, &hit) &&
         !region.surface->within(y, region.eps);
}

}  // namespace hysim::cutting::opt3d
