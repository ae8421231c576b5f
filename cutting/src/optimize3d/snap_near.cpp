// Late snapping: a node off the cut but within collapse_fraction of the local edge length of
// it, with tets whose other three nodes lie on the cut (slivers and short edges no single edge
// collapse can remove: collapsing into one cut node flattens the others), moves onto the cut
// (its nearest point), and the tets that become flat (all four nodes on the cut) are removed.
// Same acceptance as a collapse: nothing inverts, the worst q* around does not fall, volume
// within the limits, no non-manifold node.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

#include "cut_optimizer.hpp"
#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::cutting::opt3d {

// Distances of nodes to the cut surface, kept with the position they were measured at (both
// snapNear calls ask about the same nodes; most have not moved in between). within(x, r) is
// |signedDistance(x)| <= r with the same per-triangle distances, so the answers are the ones
// the surface queries give. (At most one entry per node, in the order first asked.)
DistEntry& CutOptimizer::distEntry(int n) {
  if (distSlot.empty()) {
    distSlot.assign(N, -1);
    distPool.resize(N);
  }
  std::int32_t& slot = distSlot[n];
  if (slot < 0) {
    slot = distNext++;
    distPool[slot].kind = 0;
  }
  DistEntry& e = distPool[slot];
  if (e.kind != 0 && e.x != ed.position(n)) e.kind = 0;
  return e;
}

// |signed distance| of node n to the cut, and its nearest point. `within`: a distance n is
// known to be within (within() said so, or n is on the cut and `within` the on-surface
// tolerance), for the bounded search, which gives signedDistance's value and point.
double CutOptimizer::nodeDistance(int n, Vec3* closest, double within) {
  DistEntry& e = distEntry(n);
  if (e.kind != 1) {
    e.x = ed.position(n);
    e.d = std::abs(region.surface->signedDistanceNear(e.x, within, &e.closest));
    e.kind = 1;
  }
  if (closest) *closest = e.closest;
  return e.d;
}

// region.surface->within(position(n), r).
bool CutOptimizer::nodeWithin(int n, double r) {
  DistEntry& e = distEntry(n);
  if (e.kind == 1) return e.d <= r;
  if (e.kind == 2 && r <= e.d) return false;
  const bool in = region.surface->within(ed.position(n), r);
  if (!in) {
    e.x = ed.position(n);
    e.d = r;
    e.kind = 2;
  }
  return in;
}

void CutOptimizer::snapNear() {
  if (!(options.collapse_fraction > 0) || region.surface == nullptr) return;
  std::vector<std::pair<double, std::int32_t>> cands;
  std::vector<std::int32_t> around0;
  regionTets(around0);
  std::vector<std::uint8_t> tried(N, 0);
  for (int t : around0)
    for (int k = 0; k < 4; ++k) {
      const int u = mesh.T(t, k);
      if (onCut[u] || tried[u]) continue;
      tried[u] = 1;
      const double limit = options.collapse_fraction * region.edge_length;
      if (!nodeWithin(u, limit)) continue;  // far: no nearest-point search
      const double d = nodeDistance(u, nullptr, limit);
      if (d < limit) cands.emplace_back(d, u);
    }
  std::sort(cands.begin(), cands.end());
  sn.near = options.collapse_fraction * region.edge_length;
  sn.groupAt.assign(N, 0);
  sn.prevGroup = 0;
  for (const auto& [dist, u] : cands) {
    if (onCut[u]) continue;
    snapTargets(u);
    for (const Vec3& y : sn.targets) {
      if ((y - ed.position(u)).norm() > options.collapse_fraction * region.edge_length) continue;
      // The moving set: u, plus (up to two) near nodes next to it that must come along (a
      // tet that would go flat or get worse because another of its nodes is also near the
      // cut): they move to their nearest points of the cut.
      sn.group.assign({u});
      sn.groupTo.assign({y});
      sn.prevGroup = 0;
      bool done = false;
      while (!done) {
        int partner = -1;
        const bool ok = trySnap(&partner);
        if (ok) {
          done = true;
          break;
        }
        if (partner < 0 || sn.group.size() >= 3) break;
        Vec3 z;
        nodeDistance(partner, &z);
        sn.group.push_back(partner);
        sn.groupTo.push_back(z);
      }
      if (done) break;
    }
  }
}

// Targets for u: the nearest point of the cut, then the nearest points of the edges between
// two cut nodes around u (for a node on the outer boundary, the rim: it stays on the
// boundary's polygonal surface).
void CutOptimizer::snapTargets(int u) {
  sn.targets.clear();
  sn.targetEdges.clear();
  sn.targets.emplace_back();
  nodeDistance(u, &sn.targets.back());
  for (const std::int32_t *s = ed.starBegin(u), *sEnd = ed.starEnd(u); s < sEnd; ++s) {
    const int t = (*s);
    if (dead[t]) continue;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        const int a = mesh.T(t, i), b = mesh.T(t, j);
        if (a == u || b == u || !onCut[a] || !onCut[b]) continue;
        // The same link edge seen from its other tet, possibly as (b, a): its point differs
        // from the first one's in rounding only, and is not tried again.
        const std::uint64_t edge = std::uint64_t(std::uint32_t(std::min(a, b))) << 32 | std::uint32_t(std::max(a, b));
        if (std::find(sn.targetEdges.begin(), sn.targetEdges.end(), edge) != sn.targetEdges.end()) continue;
        sn.targetEdges.push_back(edge);
        const Vec3 pa = ed.position(a), ab = ed.position(b) - pa;
        const double l2 = ab.squaredNorm();
        if (!(l2 > 0)) continue;
        // A target equal (bit for bit) to an earlier one fails the same way: trySnap leaves
        // everything as it was when it fails (the link edge (a, b) of u is in two tets).
        const Vec3 y = pa + std::clamp((ed.position(u) - pa).dot(ab) / l2, 0.1, 0.9) * ab;
        bool seen = false;
        for (size_t k = 0; k < sn.targets.size() && !seen; ++k)
          seen = std::memcmp(sn.targets[k].data(), y.data(), sizeof(double) * 3) == 0;
        if (!seen) sn.targets.push_back(y);
      }
  }
}

// The partner: a near node of the worst tet off the cut and not in the group (the last).
void CutOptimizer::namePartner(int worstTet, int* partner) {
  for (int k = 0; k < 4; ++k) {
    const int v = mesh.T(worstTet, k);
    if (!onCut[v] && sn.groupAt[v] == 0 && nodeWithin(v, sn.near) && nodeDistance(v, nullptr, sn.near) < sn.near)
      *partner = v;
  }
}

// Moves the group onto the cut and removes the tets that go flat, if that passes the checks;
// otherwise leaves everything as it was and names a near node (not on the cut, not in the
// group) of the tet that failed, if there is one.
bool CutOptimizer::trySnap(int* partner) {
  for (size_t g = 0; g < sn.group.size(); ++g) sn.groupAt[sn.group[g]] = static_cast<std::int8_t>(g + 1);
  const bool ok = trySnapMarked(partner);
  for (int g : sn.group) sn.groupAt[g] = 0;
  return ok;
}

bool CutOptimizer::trySnapMarked(int* partner) {
  double before = 0, after = 0;
  if (!evaluateSnap(partner, &before, &after)) return false;
  return applySnap(before, after);
}

// The group's new positions: the tets that die and change, their volume and q*, against the
// checks. A retry (the group grown by a partner, nothing else changed: a failed try leaves
// everything as it was) takes the volume and q* of each changing tet without the new member
// from the attempt before (prevGroup: its group size, 0 after a new group).
bool CutOptimizer::evaluateSnap(int* partner, double* beforeOut, double* afterOut) {
  // The live tets of the group's stars, sorted, each once: each star is sorted, so a
  // merge of the runs (one node: its star as it is) gives what sort + unique gave.
  sn.tets.clear();
  for (size_t gi = 0; gi < sn.group.size(); ++gi) {
    const size_t mid = sn.tets.size();
    for (const std::int32_t *s = ed.starBegin(sn.group[gi]), *sEnd = ed.starEnd(sn.group[gi]); s < sEnd; ++s)
      if (!dead[(*s)]) sn.tets.push_back((*s));
    if (gi > 0) mergeSortedRuns(sn.tets, mid, sn.tetsMerged);
  }
#ifdef HYSIM_CHECK_EXACT
  {
    std::vector<std::int32_t> ref;
    for (int g : sn.group)
      for (const std::int32_t *s = ed.starBegin(g), *sEnd = ed.starEnd(g); s < sEnd; ++s)
        if (!dead[(*s)]) ref.push_back((*s));
    std::sort(ref.begin(), ref.end());
    ref.erase(std::unique(ref.begin(), ref.end()), ref.end());
    if (ref != sn.tets) std::abort();
  }
#endif
  sn.dying.clear();
  sn.changing.clear();
  double oldMin = 1.0, newMin = 1.0, before = 0, after = 0;
  int worstTet = -1;
  matVol.clear();
  const bool reuse = sn.prevGroup > 0 && sn.prevGroup + 1 == sn.group.size();
  const int added = reuse ? sn.group.back() : -1;
  size_t pi = 0;
  // The last try of a chain (three nodes): the caller takes no partner from it, so it may
  // stop at the first changing tet below the old minimum (then newMin < oldMin).
  const bool last = sn.group.size() >= 3;
  if (last)
    for (int t : sn.tets) oldMin = std::min(oldMin, ed.quality(t));
  sn.curVol.assign(sn.tets.size(), 0.0);
  sn.curQ.assign(sn.tets.size(), 0.0);
  for (size_t ti = 0; ti < sn.tets.size(); ++ti) {
    const int t = sn.tets[ti];
    int onAfter = 0;
    bool hasAdded = false;
    for (int k = 0; k < 4; ++k) {
      const int v = mesh.T(t, k);
      onAfter += onCut[v] || sn.groupAt[v] != 0;
      hasAdded = hasAdded || v == added;
    }
    oldMin = std::min(oldMin, ed.quality(t));
    const double vt = tetVolumeHere(mesh, t);
    before += vt;
    if (onAfter == 4) {
      sn.dying.push_back(t);
      matAdd(t, vt, 0.0);
      continue;
    }
    sn.changing.push_back(t);
    double vol, q;
    while (reuse && pi < sn.prevTets.size() && sn.prevTets[pi] < t) ++pi;
    if (reuse && !hasAdded && pi < sn.prevTets.size() && sn.prevTets[pi] == t) {
      vol = sn.prevVol[pi];
      q = sn.prevQ[pi];
    } else {
      Vec3 p[4];
      for (int k = 0; k < 4; ++k) {
        const int v = mesh.T(t, k);
        p[k] = ed.position(v);
        if (sn.groupAt[v] != 0) p[k] = sn.groupTo[sn.groupAt[v] - 1];
      }
      vol = (p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0])) / 6.0;
      q = vol > 0 ? radiusRatio(p[0], p[1], p[2], p[3]) : -1.0;
    }
    sn.curVol[ti] = vol;
    sn.curQ[ti] = q;
    matAdd(t, vt, vol);
    if (q < newMin) {
      newMin = q;
      worstTet = t;
      // An inverted tet (q* -1, below every q* >= 0): the try fails and this is the worst
      // tet whatever follows (a later one must be strictly worse). Without a partner from
      // it, the caller ends the chain (nothing below is used: stop here).
      if (q < 0 && !last) {
        int p = -1;
        namePartner(worstTet, &p);
        if (p < 0) return false;
      }
    }
    after += vol;
    if (last && newMin < oldMin) return false;
  }
  sn.prevGroup = sn.group.size();
  sn.prevTets.assign(sn.tets.begin(), sn.tets.end());
  sn.prevVol.swap(sn.curVol);
  sn.prevQ.swap(sn.curQ);
  const double change = std::abs(after - before);
  if (newMin < oldMin && worstTet >= 0) namePartner(worstTet, partner);
  if (sn.dying.empty() || sn.changing.empty() || newMin < oldMin ||
      change > options.collapse_volume_fraction * std::max(before, refVolume) || !budget.fits(after - before) ||
      !matFits(before)) {
    return false;
  }
  *beforeOut = before;
  *afterOut = after;
  return true;
}

bool CutOptimizer::applySnap(double before, double after) {
  sn.groupFrom.clear();
  sn.groupVer.clear();
  for (size_t g = 0; g < sn.group.size(); ++g) {
    sn.groupFrom.push_back(ed.position(sn.group[g]));
    sn.groupVer.push_back(ed.version(sn.group[g]));
    ed.setPosition(sn.group[g], sn.groupTo[g]);
  }
  for (int t : sn.dying) ed.markDead(t);
  bool ok = true;
  for (size_t g = 0; g < sn.group.size() && ok; ++g) {
    ed.liveStar(sn.group[g], around, nullptr);
    ok = discAround(sn.group[g], around);
  }
  for (size_t i = 0; i < sn.dying.size() && ok; ++i)
    for (int k = 0; k < 4 && ok; ++k) {
      const int w = mesh.T(sn.dying[i], k);
      if (sn.groupAt[w] != 0) continue;
      ed.liveStar(w, around, nullptr);
      ok = discAround(w, around);
    }
  if (!ok) {
    for (int t : sn.dying) dead[t] = 0;
    for (size_t g = 0; g < sn.group.size(); ++g) ed.restorePosition(sn.group[g], sn.groupFrom[g], sn.groupVer[g]);
    return false;
  }
  for (int g : sn.group) {
    onCut[g] = 1;
    lateSnapped.push_back(g);
    if (counts) ++counts->late_snaps;
  }
  budget.spend(after - before);
  return true;
}

}  // namespace hysim::cutting::opt3d
