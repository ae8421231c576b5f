// Edge collapse on the cut: an edge with an end on the cut that is short (below
// collapse_fraction of its tet's mean edge) or belongs to a poor tet (q* below quality_target)
// is collapsed into its end on the cut, which keeps its place (so the cut stays where it is):
// the tets around the edge go, the other tets of the collapsed node take the kept one. Kept
// only if no tet inverts, the worst q* there rises (short edges: does not fall), the volume
// changes by at most collapse_volume_fraction of the star and within the budget, no two tets
// coincide and the mesh stays manifold. The stars are stale for the two ends until the next
// batch, so within a batch they take part in no other collapse. Curved cuts, last (after flap
// peeling): only edges of tets below flap_quality, and a node already non-manifold may stay
// so.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <limits>
#include <vector>

#include "cut_optimizer.hpp"
#include "hysim/cutting/mesh_stats.hpp"
#include "../flap_peel.hpp"

namespace hysim::cutting::opt3d {
namespace {

// Sorted by length (then ends); an edge comes once per poor tet around it: one candidate per
// (u, v), short if any of its copies is (a short edge's test accepts what the other accepts,
// and copies would be tried one after the other on the same mesh).
bool byKey(const CollapseCand& p, const CollapseCand& q) {  // (the lengths are finite)
  if (p.len < q.len) return true;
  if (q.len < p.len) return false;
  return p.u != q.u ? p.u < q.u : p.v < q.v;
}

// (c sorted by byKey: copies of a candidate are neighbours, in any order; the first copy's
// fields are kept, the same for every copy but the tet, which the collapse does not read.)
void mergeCopies(const std::vector<CollapseCand>& c, std::vector<CollapseCand>& out) {
  out.resize(c.size());
  size_t kept = 0;
  for (size_t i = 0; i < c.size(); ++i) {
    if (kept > 0 && out[kept - 1].len == c[i].len && out[kept - 1].u == c[i].u && out[kept - 1].v == c[i].v) {
      out[kept - 1].shortEdge = out[kept - 1].shortEdge || c[i].shortEdge;
      continue;
    }
    out[kept++] = c[i];
  }
  out.resize(kept);
}

#ifdef HYSIM_CHECK_EXACT
void sortMerge(std::vector<CollapseCand>& c) {
  std::sort(c.begin(), c.end(), byKey);
  const std::vector<CollapseCand> all = c;
  mergeCopies(all, c);
}
#endif

}  // namespace

void CutOptimizer::collapseEdges() {
  if (!(options.collapse_fraction > 0)) return;
  col.locked.assign(N, 0);
  // Candidates refused by a check that looks only at the stars of u and v (positions do not
  // change here): refused again while neither star changes (starStamp[n] takes a new number
  // whenever a tet with n dies or changes), whatever else happened. A later batch skips them
  // (the budget check, which depends on the other collapses, never records a refusal).
  // Per u, a list of (v, shortEdge, offCut, the two stamps) in `refusedPool`.
  // (The arrays live across calls, allocated by the first: the stamps keep counting, the
  // lists are emptied at the end of each call.)
  if (starStamp.empty()) {
    starStamp.assign(N, 0);
    refusedHead.assign(N, -1);
  }
  col.offCutToo = curved && options.collapse_off_cut;
  if (isSeed.empty()) {
    isSeed.assign(N, 0);
    for (int n : seeds) isSeed[n] = 1;
  }
  if (tetChanged.empty()) tetChanged.assign(M, 0);
  col.raw.clear();
  col.cands.clear();
  col.changedTets.clear();
  for (int batch = 0; batch < 3; ++batch) {
    collapseCandidates(batch);
    int done = 0;
    for (const CollapseCand& c : col.cands) {
      if (col.locked[c.u] || col.locked[c.v] || refusedBefore(c)) continue;
      if (tryCollapse(c)) ++done;
    }
    if (done == 0) break;
    ed.refreshStars();
    std::fill(col.locked.begin(), col.locked.end(), 0);
  }
  for (int u : refusedUs) refusedHead[u] = -1;
  refusedUs.clear();
  refusedPool.clear();
}

// The candidates of all region tets (`raw`, with copies), kept sorted by byKey: the first
// batch sorts them; a later batch changed only the tets of its collapses (removed, or a node
// replaced: `changedTets`) and nothing else a candidate depends on (positions, the cut flags),
// so it drops the candidates of the changed tets, takes those of the changed ones anew (where
// they are still region tets: with a seed node), sorts them and merges the two runs. The list
// (copies merged, into `cands`) is the same as from scratch.
void CutOptimizer::collapseCandidates(int batch) {
  if (batch == 0) {
    std::vector<std::int32_t> seen;
    regionTets(seen);
    col.raw.clear();
    for (int t : seen) candidatesOf(t, col.raw);
    std::sort(col.raw.begin(), col.raw.end(), byKey);
  } else {
    for (int t : col.changedTets) tetChanged[t] = 1;
    col.raw.erase(std::remove_if(col.raw.begin(), col.raw.end(),
                             [&](const CollapseCand& c) { return dead[c.tet] || tetChanged[c.tet]; }),
              col.raw.end());
    const size_t kept = col.raw.size();
    for (int t : col.changedTets) {
      if (!tetChanged[t]) continue;  // (a tet changed twice: once)
      tetChanged[t] = 0;
      bool inRegion = false;
      for (int k = 0; k < 4; ++k) inRegion = inRegion || isSeed[mesh.T(t, k)];
      if (inRegion) candidatesOf(t, col.raw);
    }
    col.changedTets.clear();
    const auto mid = col.raw.begin() + static_cast<std::ptrdiff_t>(kept);
    std::sort(mid, col.raw.end(), byKey);
    col.cands.clear();
    std::merge(col.raw.begin(), mid, mid, col.raw.end(), std::back_inserter(col.cands), byKey);
    col.raw.swap(col.cands);
  }
  mergeCopies(col.raw, col.cands);
#ifdef HYSIM_CHECK_EXACT
  {  // the same list as from scratch
    std::vector<std::int32_t> seen;
    std::vector<CollapseCand> ref;
    regionTets(seen);
    for (int t : seen) candidatesOf(t, ref);
    sortMerge(ref);
    bool same = ref.size() == col.cands.size();
    for (size_t i = 0; i < ref.size() && same; ++i)
      same = std::memcmp(&ref[i].len, &col.cands[i].len, sizeof(double)) == 0 && ref[i].u == col.cands[i].u &&
             ref[i].v == col.cands[i].v && ref[i].shortEdge == col.cands[i].shortEdge && ref[i].offCut == col.cands[i].offCut;
    if (!same) std::abort();
  }
#endif
}

// Does node n have a boundary face?
bool CutOptimizer::onBoundary(int n) {
  ed.liveStar(n, col.vstar, nullptr);
  discAround(n, col.vstar, true);
  return !link.empty();
}

// The candidates of tet t (edges of a poor tet, short edges), appended to `out`.
void CutOptimizer::candidatesOf(int t, std::vector<CollapseCand>& out) {
  if (dead[t]) return;
  {
    const double q = ed.quality(t);
    if (lastResort && !(q < options.flap_quality)) return;
    // Edge lengths as Eigen's norm() of p[a] - p[b]: the square root of ((x x + y y) + z z),
    // in scalars over the coordinate columns.
    double sq[6], lens[6];
    {
      const double* cx = mesh.X.col(0).data();
      const double* cy = mesh.X.col(1).data();
      const double* cz = mesh.X.col(2).data();
      const int i[4] = {mesh.T(t, 0), mesh.T(t, 1), mesh.T(t, 2), mesh.T(t, 3)};
      for (int a = 0, e = 0; a < 4; ++a)
        for (int b = a + 1; b < 4; ++b, ++e) {
          const double dx = cx[i[a]] - cx[i[b]], dy = cy[i[a]] - cy[i[b]], dz = cz[i[a]] - cz[i[b]];
          sq[e] = (dx * dx + dy * dy) + dz * dz;
        }
    }
    // A tet at or above quality_target has only its short edges: none where the shortest
    // is not below collapse_fraction x the longest (a bound on the mean: the six rounded
    // sixths add up to at most hi (1 + 6 eps) < hi (1 + 1e-9)) or the local edge.
    // (sqrt is correctly rounded, so monotone: the shortest and longest lengths are the
    // roots of the smallest and largest squares; the other four are taken only past here.)
    if (q >= options.quality_target) {
      double lo2 = sq[0], hi2 = sq[0];
      for (int e = 1; e < 6; ++e) {
        lo2 = std::min(lo2, sq[e]);
        hi2 = std::max(hi2, sq[e]);
      }
      const double lo = std::sqrt(lo2), hi = std::sqrt(hi2);
      if (lo >= options.collapse_fraction * std::max(hi * (1 + 1e-9), region.edge_length)) return;
    }
    double mean = 0;
    for (int e = 0; e < 6; ++e) {
      lens[e] = std::sqrt(sq[e]);
      mean += lens[e] / 6.0;
    }
#ifdef HYSIM_CHECK_EXACT
    const Vec3 p[4] = {ed.position(mesh.T(t, 0)), ed.position(mesh.T(t, 1)), ed.position(mesh.T(t, 2)), ed.position(mesh.T(t, 3))};
    for (int a = 0, e = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b, ++e) {
        const double ref = (p[a] - p[b]).norm();
        if (std::memcmp(&ref, &lens[e], sizeof ref) != 0) std::abort();
      }
#endif
    for (int a = 0, e = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b, ++e) {
        const int x = mesh.T(t, a), y = mesh.T(t, b);
        const double len = lens[e];
        const bool shortEdge = len < options.collapse_fraction * std::max(mean, region.edge_length);
        if (!shortEdge && q >= options.quality_target) continue;
        if (onCut[y]) out.push_back({len, x, y, shortEdge, false, t});
        if (onCut[x]) out.push_back({len, y, x, shortEdge, false, t});
        if (col.offCutToo && !onCut[x] && !onCut[y]) {
          out.push_back({len, x, y, shortEdge, true, t});
          out.push_back({len, y, x, shortEdge, true, t});
        }
      }
  }
}

// Candidates refused by a check that looks only at the stars of u and v (positions do not
// change here) are refused again while neither star changes (starStamp[n] takes a new number
// whenever a tet with n dies or changes). The budget check, which depends on the other
// collapses, never records a refusal.
bool CutOptimizer::refusedBefore(const CollapseCand& c) const {
  const int u = c.u, v = c.v;
  bool again = false;
  for (std::int32_t r = refusedHead[u]; r >= 0 && !again; r = refusedPool[r].next) {
    const Refused& e = refusedPool[r];
    again = e.v == v && e.shortEdge == c.shortEdge && e.offCut == c.offCut && e.stampU == starStamp[u] &&
            e.stampV == starStamp[v];
  }
  return again;
}

void CutOptimizer::refuse(const CollapseCand& c) {
  const int u = c.u, v = c.v;
  if (refusedHead[u] < 0) refusedUs.push_back(u);
  refusedPool.push_back({v, refusedHead[u], starStamp[u], starStamp[v], c.shortEdge, c.offCut});
  refusedHead[u] = static_cast<std::int32_t>(refusedPool.size()) - 1;
}

bool CutOptimizer::tryCollapse(const CollapseCand& c) {
  if (!gatherCollapse(c)) {
    refuse(c);
    return false;
  }
  double dv = 0;
  const int volume = collapseVolume(&dv);
  if (volume == 1) {
    refuse(c);
    return false;
  }
  if (volume == 2) return false;  // over the budget: not recorded
  if (!collapseQualityOk(c) || collapseCoincides(c) || (c.offCut && onBoundary(c.u) && !onBoundary(c.v))) {
    // (Off the cut: a boundary node only into a boundary node; an interior node's star keeps its volume.)
    refuse(c);
    return false;
  }
  if (!applyCollapse(c)) return false;
  const int u = c.u, v = c.v;
  col.locked[u] = col.locked[v] = 1;
  // The stars that changed: of every node of the removed and changed tets (v among them), and u.
  starStamp[u] = ++stampClock;
  for (int t : col.dying)
    for (int k = 0; k < 4; ++k) starStamp[mesh.T(t, k)] = ++stampClock;
  for (int t : col.changing)
    for (int k = 0; k < 4; ++k) starStamp[mesh.T(t, k)] = ++stampClock;
  col.changedTets.insert(col.changedTets.end(), col.changing.begin(), col.changing.end());
  budget.spend(dv);
  if (counts) ++counts->collapsed;
  return true;
}

// One pass over u's live tets: those with v die, the others change (u becomes v). Checks in
// order of cost, without side effects: off the cut, one material (every live tet of u has the
// label of the first); no changed tet inverts or goes flat (its determinant with v for u, in
// tetVolumeHere's scalar arithmetic, kept for the volume check); the edge is still an edge (a
// tet dies).
bool CutOptimizer::gatherCollapse(const CollapseCand& c) {
  const int u = c.u, v = c.v;
  col.dying.clear();
  col.changing.clear();
  col.detAfter.clear();
  bool ok = true;
  {
    const double* cx = mesh.X.col(0).data();
    const double* cy = mesh.X.col(1).data();
    const double* cz = mesh.X.col(2).data();
    const double vx = cx[v], vy = cy[v], vz = cz[v];
    std::int32_t mat0 = 0;
    bool first = true;
    for (const std::int32_t *s = ed.starBegin(u), *sEnd = ed.starEnd(u); s < sEnd; ++s) {
      const int t = (*s);
      if (dead[t]) continue;
      if (c.offCut) {
        const std::int32_t m = mesh.material(t);
        if (first) {
          mat0 = m;
          first = false;
        } else if (m != mat0) {
          ok = false;
          break;
        }
      }
      const int i0 = mesh.T(t, 0), i1 = mesh.T(t, 1), i2 = mesh.T(t, 2), i3 = mesh.T(t, 3);
      if ((i0 == v) | (i1 == v) | (i2 == v) | (i3 == v)) {
        col.dying.push_back(t);
        continue;
      }
      const double x0 = i0 == u ? vx : cx[i0], y0 = i0 == u ? vy : cy[i0], z0 = i0 == u ? vz : cz[i0];
      const double x1 = i1 == u ? vx : cx[i1], y1 = i1 == u ? vy : cy[i1], z1 = i1 == u ? vz : cz[i1];
      const double x2 = i2 == u ? vx : cx[i2], y2 = i2 == u ? vy : cy[i2], z2 = i2 == u ? vz : cz[i2];
      const double x3 = i3 == u ? vx : cx[i3], y3 = i3 == u ? vy : cy[i3], z3 = i3 == u ? vz : cz[i3];
      const double ax = x1 - x0, ay = y1 - y0, az = z1 - z0;
      const double bx = x2 - x0, by = y2 - y0, bz = z2 - z0;
      const double ex = x3 - x0, ey = y3 - y0, ez = z3 - z0;
      const double nx = by * ez - bz * ey, ny = bz * ex - bx * ez, nz = bx * ey - by * ex;
      const double det = (ax * nx + ay * ny) + az * nz;
#ifdef HYSIM_CHECK_EXACT
      {
        Vec3 p[4];
        for (int k = 0; k < 4; ++k) p[k] = mesh.T(t, k) == u ? ed.position(v) : ed.position(mesh.T(t, k));
        const double ref = (p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0]));
        if (std::memcmp(&ref, &det, sizeof det) != 0) std::abort();
      }
#endif
      if (!(det > 0)) {
        ok = false;
        break;
      }
      col.changing.push_back(t);
      col.detAfter.push_back(det);
    }
  }
  return ok && !col.dying.empty();
}

// The volume change (*dv) against u's star: 0 fits, 1 refused (star or material limit), 2
// over the budget.
int CutOptimizer::collapseVolume(double* dv) {
  double before = 0, after = 0;
  matVol.clear();
  for (int t : col.dying) {
    const double vt = tetVolumeHere(mesh, t);
    before += vt;
    matAdd(t, vt, 0.0);
  }
  for (size_t i = 0; i < col.changing.size(); ++i) {
    const int t = col.changing[i];
    const double vt = tetVolumeHere(mesh, t);
    before += vt;
    const double vol = col.detAfter[i] / 6.0;
    after += vol;
    matAdd(t, vt, vol);
  }
  const double change = std::abs(after - before);
  if (change > options.collapse_volume_fraction * std::max(before, refVolume) || !matFits(before)) return 1;
  *dv = after - before;
  return budget.fits(after - before) ? 0 : 2;
}

// The worst q* after rises (short edges: does not fall); stops as soon as it fails.
bool CutOptimizer::collapseQualityOk(const CollapseCand& c) {
  const int u = c.u;
  const Vec3 xv = ed.position(c.v);
  bool ok = true;
  double oldMin = 1.0;
  for (int t : col.dying) oldMin = std::min(oldMin, ed.quality(t));
  for (int t : col.changing) oldMin = std::min(oldMin, ed.quality(t));
  // newMin = the worst q* after; stop as soon as it fails against oldMin.
  double newMin = 1.0;
  for (int t : col.changing) {
    newMin = std::min(newMin, ed.qualityWith(t, u, xv));
    if (c.shortEdge ? newMin < oldMin : !(newMin > oldMin)) {
      ok = false;
      break;
    }
  }
  return ok && !(c.shortEdge ? newMin < oldMin : !(newMin > oldMin));
}

// Would a changed tet coincide with a tet already around v?
bool CutOptimizer::collapseCoincides(const CollapseCand& c) {
  const int u = c.u, v = c.v;
  bool ok = true;
  ed.liveStar(v, col.vstar, nullptr);
  col.keysB.clear();
  for (int w : col.vstar) {
    if (std::find(col.dying.begin(), col.dying.end(), w) != col.dying.end()) continue;
    std::array<std::int32_t, 4> k{mesh.T(w, 0), mesh.T(w, 1), mesh.T(w, 2), mesh.T(w, 3)};
    std::sort(k.begin(), k.end());
    col.keysB.push_back(k);
  }
  for (size_t i = 0; i < col.changing.size() && ok; ++i) {
    const int t = col.changing[i];
    std::array<std::int32_t, 4> k{mesh.T(t, 0), mesh.T(t, 1), mesh.T(t, 2), mesh.T(t, 3)};
    std::replace(k.begin(), k.end(), u, v);
    std::sort(k.begin(), k.end());
    for (const auto& kb : col.keysB)
      if (k == kb) ok = false;
  }
  return !ok;
}

// Applies the collapse, then checks manifoldness around v and the other nodes of the removed
// tets, or undoes it (false).
bool CutOptimizer::applyCollapse(const CollapseCand& c) {
  const int u = c.u, v = c.v;
  ed.bumpTopology();
  for (int t : col.dying) ed.markDead(t);
  ed.touch(u);
  ed.touch(v);
  for (int t : col.changing) {
    ed.noteGained(v, t);
    for (int k = 0; k < 4; ++k)
      if (mesh.T(t, k) == u) mesh.T(t, k) = v;
  }
  ed.liveStar(v, around, &col.changing);
  bool ok = discAround(v, around);
  // (Each node once: the nodes around the edge are in two of the removed tets.)
  col.checked.clear();
  for (size_t i = 0; i < col.dying.size() && ok; ++i)
    for (int k = 0; k < 4 && ok; ++k) {
      const int w = mesh.T(col.dying[i], k);
      if (w == u || w == v || std::find(col.checked.begin(), col.checked.end(), w) != col.checked.end()) continue;
      col.checked.push_back(w);
      ed.liveStar(w, around, nullptr);
      ok = discAround(w, around);
      if (!ok && lastResort) {
        // Last resort: a node whose star earlier cuts had already left non-manifold
        // (two sheets of the boundary touching at it) may stay so, if its star has no
        // more pieces and boundary loops than before.
        const StarShape after = starShape(mesh, w, around);
        for (int t : col.dying) dead[t] = 0;
        for (int t : col.changing)
          for (int k = 0; k < 4; ++k)
            if (mesh.T(t, k) == v) mesh.T(t, k) = u;
        ed.liveStar(w, around, nullptr);
        const StarShape before = starShape(mesh, w, around);
        for (int t : col.dying) dead[t] = 1;
        for (int t : col.changing)
          for (int k = 0; k < 4; ++k)
            if (mesh.T(t, k) == u) mesh.T(t, k) = v;
        ok = !before.manifold() && after.noWorseThan(before);
      }
    }
  if (!ok) {
    for (int t : col.dying) dead[t] = 0;
    for (int t : col.changing)
      for (int k = 0; k < 4; ++k)
        if (mesh.T(t, k) == v) mesh.T(t, k) = u;
    return false;
  }
  return true;
}

}  // namespace hysim::cutting::opt3d
