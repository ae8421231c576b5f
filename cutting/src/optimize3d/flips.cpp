// Flips: a poor tet (q* below flip_quality) with all its nodes held in place is repaired by
// retriangulating it with its neighbours: 2-3 (the tet and its neighbour across a face become
// three tets around the edge between their far nodes), 3-2 (the three tets around an interior
// edge become two across the triangle of their other nodes) and edge removal (the 4 to 6 tets
// around an interior edge become 2(n - 2)). Only interior faces and edges change, within one
// material: the boundary, the cut and the volume stay exactly. Kept when the worst q* of the
// tets involved rises; the best flip of a tet is taken. New tets reuse the slots of removed
// ones (none free: no 2-3). Curved cuts only.
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
constexpr int kEdgeOf[4][4] = {{-1, 0, 1, 2}, {0, -1, 3, 4}, {1, 3, -1, 5}, {2, 4, 5, -1}};
#ifdef HYSIM_CHECK_EXACT
int hitsOf(unsigned m, unsigned S) {
  return int((m & S) != 0) + int(((m >> 4) & S) != 0) + int(((m >> 8) & S) != 0) + int(((m >> 12) & S) != 0);
}
void checkHits(const NearTet& nt, unsigned S, int need) {
  if ((hitsOf(nt.m, S) == need) != ((nt.c & S) == S)) std::abort();
}
#endif
}  // namespace

// A candidate that found no flip in a round is not tried again in the next round of the same
// call while nothing it reads changed: it reads the stars of its nodes, the tets in them (and
// the stars of their nodes, for the existence checks) and how many free slots there are (as
// min(count, 2): one for a 2-3, up to two for an edge removal). Each flip's rebuilt stars mark
// (flipMark, with the flip's number) their nodes and the nodes of the tets around them.
void CutOptimizer::flips() {
  if (!curved || !(options.flip_quality > 0)) return;
  freeSlots.assign(ed.killed().begin(), ed.killed().end());
  std::sort(freeSlots.begin(), freeSlots.end());
  freeSlots.erase(std::unique(freeSlots.begin(), freeSlots.end()), freeSlots.end());
  availNow = -1;
  failedPrev.clear();
  failedNow.clear();
  std::vector<std::int32_t> cands;
  flipChanged.clear();
  for (int round = 0; round < 3; ++round) {
    flipCandidates(round, cands);
    int done = 0;
    size_t fp = 0;
    for (int t : cands) {
      if (dead[t]) continue;
      const double qt = ed.quality(t);
      if (!(qt < options.flip_quality)) continue;
      while (fp < failedPrev.size() && failedPrev[fp].t < t) ++fp;
      if (fp < failedPrev.size() && failedPrev[fp].t == t) {
        const FlipFailed& prev = failedPrev[fp];
        bool same = std::min(availSlots(), 2) == prev.avail;
        for (int k = 0; k < 4 && same && !flipMark.empty(); ++k) same = flipMark[mesh.T(t, k)] <= prev.clock;
        if (same) {
          failedNow.push_back(prev);
          continue;
        }
      }
      // Nothing changes until the best flip is applied.
      FlipChoice ch;
      ch.best = qt;
      int nearOff[4];
      gatherNear(t, nearOff);
      FlipNeighbourhood nb;
      neighbourhoodOf(t, nearOff, nb);
      bestFlip23(t, qt, nb, ch);
      bestFlip32(t, nb, ch);
      if (options.edge_removal) bestEdgeRemoval(t, nb, ch);
      if (ch.kind < 0) {
        failedNow.push_back({t, flipClock, std::min(availSlots(), 2)});
        continue;
      }
      applyFlip(t, ch);
      ++done;
      if (counts) ++counts->flips;
      afterFlip();
    }
    failedPrev.swap(failedNow);
    failedNow.clear();
    if (done == 0) break;
  }
}

// The dead tets in freeSlots (the slots free for reuse), counted when first needed after each
// change. Only min(count, 2) is read (the checks of failed candidates; an edge removal takes
// at most two): the count stops at 2.
int CutOptimizer::availSlots() {
  if (availNow < 0) {
    availNow = 0;
    for (size_t k = 0; k < freeSlots.size() && availNow < 2; ++k) availNow += dead[freeSlots[k]] ? 1 : 0;
  }
  return availNow;
}

double CutOptimizer::vol6(int a, int b, int c, int d) const {
  const Vec3 p0 = ed.position(a);
  return (ed.position(b) - p0).dot((ed.position(c) - p0).cross(ed.position(d) - p0));
}

// -1 unless vol6(a, b, c, d) > 0, else q*.
double CutOptimizer::q4(int a, int b, int c, int d) const {
  return radiusRatioOriented(ed.position(a), ed.position(b), ed.position(c), ed.position(d));
}

void CutOptimizer::flipSetTet(int t, int a, int b, int c, int d) {
  flipChanged.push_back(t);
  ed.setTetNodes(t, a, b, c, d);
}

// The round's candidates: the region's poor tets (round 0); later, the last round's
// candidates and the tets changed since, live, with a seed among their nodes (a tet no flip
// changed kept its nodes, its place in the region and its q*).
void CutOptimizer::flipCandidates(int round, std::vector<std::int32_t>& cands) {
  if (round == 0) {
    regionTets(cands);
  } else {
    // The region's tets now (every star rebuilt after the last flip): a tet no flip
    // changed kept its nodes, its place in the region (a seed among its nodes) and its q*;
    // the others were changed by setTet. So: the last round's candidates and the changed
    // tets, live, with a seed among their nodes.
    if (flipSeeds.empty()) {
      flipSeeds.assign(seeds.begin(), seeds.end());
      std::sort(flipSeeds.begin(), flipSeeds.end());
    }
    // (cands is sorted and without repeats: the changed tets sorted and merged in, as a
    // sort + unique of the whole.)
#ifdef HYSIM_CHECK_EXACT
    std::vector<std::int32_t> ref(cands);
    ref.insert(ref.end(), flipChanged.begin(), flipChanged.end());
    std::sort(ref.begin(), ref.end());
    ref.erase(std::unique(ref.begin(), ref.end()), ref.end());
    if (std::adjacent_find(cands.begin(), cands.end(), std::greater_equal<std::int32_t>()) != cands.end())
      std::abort();
#endif
    const size_t mid = cands.size();
    cands.insert(cands.end(), flipChanged.begin(), flipChanged.end());
    std::sort(cands.begin() + static_cast<std::ptrdiff_t>(mid), cands.end());
    mergeSortedRuns(cands, mid, candsMerged);
#ifdef HYSIM_CHECK_EXACT
    if (ref != cands) std::abort();
#endif
    cands.erase(std::remove_if(cands.begin(), cands.end(),
                               [&](int t) {
                                 if (dead[t]) return true;
                                 bool in = false;
                                 for (int k = 0; k < 4 && !in; ++k)
                                   in = std::binary_search(flipSeeds.begin(), flipSeeds.end(), mesh.T(t, k));
                                 return !in;
                               }),
                cands.end());
    flipChanged.clear();
  }
  cands.erase(std::remove_if(cands.begin(), cands.end(), [&](int t) { return !(ed.quality(t) < options.flip_quality); }),
              cands.end());
}

// The live tets around t's nodes 0, 1 and 2 (star order; t among them), each with the mask c
// of t's nodes it contains (bit k: t's node k is one of its nodes): the face and edge
// searches read them instead of scanning the stars again. A live tet's four nodes are
// distinct and so are t's, so "the tet holds the nodes S" is (c & S) == S (checked under
// HYSIM_CHECK_EXACT against a count per position).
void CutOptimizer::gatherNear(int t, int nearOff[4]) {
  nearTets.clear();
  {
    const int t0 = mesh.T(t, 0), t1 = mesh.T(t, 1), t2 = mesh.T(t, 2), t3 = mesh.T(t, 3);
    // A tet's mask: the OR of its nodes' bits (t's nodes carry bits 0 to 3 while it is
    // tried; every other node 0).
    if (flipNodeBit.empty()) flipNodeBit.assign(N, 0);
    std::uint8_t* const nodeBit = flipNodeBit.data();
    nodeBit[t0] = 1;
    nodeBit[t1] = 2;
    nodeBit[t2] = 4;
    nodeBit[t3] = 8;
    for (int i = 0; i < 3; ++i) {
      nearOff[i] = static_cast<int>(nearTets.size());
      for (const std::int32_t *s = ed.starBegin(mesh.T(t, i)), *sEnd = ed.starEnd(mesh.T(t, i)); s < sEnd; ++s) {
        if (dead[*s]) continue;
        const int w0 = mesh.T(*s, 0), w1 = mesh.T(*s, 1), w2 = mesh.T(*s, 2), w3 = mesh.T(*s, 3);
        const unsigned c = unsigned(nodeBit[w0] | nodeBit[w1] | nodeBit[w2] | nodeBit[w3]);
#ifdef HYSIM_CHECK_EXACT
        unsigned m = 0;
        const int wl[4] = {w0, w1, w2, w3};
        for (int l = 0; l < 4; ++l)
          m |= (unsigned(wl[l] == t0) | unsigned(wl[l] == t1) << 1 | unsigned(wl[l] == t2) << 2 |
                unsigned(wl[l] == t3) << 3)
               << (4 * l);
        if (c != ((m | m >> 4 | m >> 8 | m >> 12) & 0xFu)) std::abort();
        nearTets.push_back({*s, c, m});
#else
        nearTets.push_back({*s, c});
#endif
      }
    }
    nodeBit[t0] = nodeBit[t1] = nodeBit[t2] = nodeBit[t3] = 0;
    nearOff[3] = static_cast<int>(nearTets.size());
  }
}

// The tets around each edge (i, j) of t, i < j (from the list of node i, in its order; bit j of
// a tet's mask around node i): their count and the first six, all that the 3-2 flip (three)
// and the edge removal (four to six) read. And the neighbour across each face f: the first
// other tet around the face's first node (node 1 for face 0, node 0 for the others) holding
// the face's three nodes.
void CutOptimizer::neighbourhoodOf(int t, const int nearOff[4], FlipNeighbourhood& nb) {
  {
    const int matT = mesh.material(t);
    for (int i = 0; i < 3; ++i)
      for (int k = nearOff[i]; k < nearOff[i + 1]; ++k) {
        const unsigned c = nearTets[k].c;
        const std::int32_t s = nearTets[k].s;
#ifdef HYSIM_CHECK_EXACT
        for (int j = i + 1; j < 4; ++j) checkHits(nearTets[k], (1u << i) | (1u << j), 2);
        for (int f = 0; f < 4; ++f)
          if (kFace[f][0] == i) checkHits(nearTets[k], 0xFu & ~(1u << f), 3);
#endif
        if ((c >> (i + 1)) == 0) continue;  // (no other node of t after node i)
        for (int j = i + 1; j < 4; ++j)
          if (c & (1u << j)) {
            const int e = kEdgeOf[i][j];
            if (nb.edgeN[e] < 6) nb.edgeTetsOf[e][nb.edgeN[e]] = s;
            ++nb.edgeN[e];
            nb.edgeSameMat[e] = nb.edgeSameMat[e] && mesh.material(s) == matT;
          }
        if (s == t || i > 1) continue;
        if (i == 1) {
          if (nb.faceU[0] < 0 && (c & 0xEu) == 0xEu) nb.faceU[0] = s;
        } else {
          for (int f = 1; f < 4; ++f) {
            const unsigned S = 0xFu & ~(1u << f);
            if (nb.faceU[f] < 0 && (c & S) == S) nb.faceU[f] = s;
          }
        }
      }
  }
}

// 2-3 across each face whose neighbour has t's material, where a slot is free.
void CutOptimizer::bestFlip23(int t, double qt, const FlipNeighbourhood& nb, FlipChoice& ch) {
  const bool slot = [&]() {
    while (!freeSlots.empty() && !dead[freeSlots.back()]) freeSlots.pop_back();
    return !freeSlots.empty();
  }();
  for (int f = 0; f < 4 && slot; ++f) {
    const int a = mesh.T(t, kFace[f][0]), b = mesh.T(t, kFace[f][1]), c = mesh.T(t, kFace[f][2]),
              d = mesh.T(t, f);
    const int u = nb.faceU[f];
    if (u < 0 || mesh.material(u) != mesh.material(t)) continue;
    int e = -1;
    for (int k = 0; k < 4; ++k)
      if (mesh.T(u, k) != a && mesh.T(u, k) != b && mesh.T(u, k) != c) e = mesh.T(u, k);
    const double old = std::min(qt, ed.quality(u));
    // The new edge (d, e) is no shorter than the shortest edge of the two tets.
    double shortest = std::numeric_limits<double>::infinity();
    for (int tt : {t, u})
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j)
          shortest = std::min(shortest, (ed.position(mesh.T(tt, i)) - ed.position(mesh.T(tt, j))).squaredNorm());
    if ((ed.position(d) - ed.position(e)).squaredNorm() < shortest) continue;
    // (d, e) must not be an edge already (where the mesh folds, it could be).
    bool exists = false;
    for (const std::int32_t *s = ed.starBegin(d), *sEnd = ed.starEnd(d); s < sEnd && !exists; ++s)
      if (!dead[*s])
        for (int k = 0; k < 4; ++k) exists = exists || mesh.T(*s, k) == e;
    if (exists) continue;
    // (d, a, b, c) with kFace's order is positive when the face is (a, b, c) seen from
    // outside, i.e. vol(a, b, c, d) < 0 in this convention: use the tet's own order.
    // New tets: t with one face node replaced by e.
    int v[4];
    for (int k = 0; k < 4; ++k) v[k] = mesh.T(t, k);
    double qn = 1.0;
    for (int r = 0; r < 3 && qn > ch.best; ++r) {
      const int fk = kFace[f][r];
      int w[4] = {v[0], v[1], v[2], v[3]};
      w[fk] = e;
      qn = std::min(qn, q4(w[0], w[1], w[2], w[3]));
    }
    if (qn > ch.best && qn > old) {
      ch.best = qn;
      ch.kind = 0;
      ch.f = f;
      ch.u = u;
      ch.i = e;
    }
  }
}

// 3-2 about each edge of t with exactly three tets of one material in a closed ring.
void CutOptimizer::bestFlip32(int t, const FlipNeighbourhood& nb, FlipChoice& ch) {
  for (int i = 0, ei = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j, ++ei) {
      const int a = mesh.T(t, i), b = mesh.T(t, j);
      const std::int32_t* edgeTets = nb.edgeTetsOf[ei];
      if (nb.edgeN[ei] != 3) continue;
      if (!nb.edgeSameMat[ei]) continue;
      // The other two nodes of each tet; a closed ring uses each of three nodes twice.
      std::int32_t others[6], m = 0;
      for (int r = 0; r < 3; ++r)
        for (int k = 0, u = edgeTets[r]; k < 4; ++k)
          if (mesh.T(u, k) != a && mesh.T(u, k) != b) others[m++] = mesh.T(u, k);
      if (m != 6) continue;
      std::int32_t p[3], np = 0;
      bool closed = true;
      for (int k = 0; k < 6 && closed; ++k) {
        int uses = 0;
        for (int l = 0; l < 6; ++l) uses += others[l] == others[k];
        closed = uses == 2;
        bool seen = false;
        for (int l = 0; l < np; ++l) seen = seen || p[l] == others[k];
        if (!seen && np < 3) p[np++] = others[k];
      }
      if (!closed || np != 3) continue;
      // The triangle (p0, p1, p2) must not be a face already (where the mesh folds).
      bool exists = false;
      for (const std::int32_t *s = ed.starBegin(p[0]), *sEnd = ed.starEnd(p[0]); s < sEnd && !exists; ++s) {
        if (dead[*s]) continue;
        int hits = 0;
        for (int k = 0; k < 4; ++k) hits += mesh.T(*s, k) == p[1] || mesh.T(*s, k) == p[2];
        exists = hits == 2;
      }
      if (exists) continue;
      double old = 1.0;
      for (int r = 0; r < 3; ++r) old = std::min(old, ed.quality(edgeTets[r]));
      const double va = vol6(p[0], p[1], p[2], a);
      const int top = va > 0 ? a : b, bottom = va > 0 ? b : a;
      const double qn = std::min(q4(p[0], p[1], p[2], top), q4(p[0], p[2], p[1], bottom));
      if (qn > ch.best && qn > old) {
        ch.best = qn;
        ch.kind = 1;
        ch.i = top;
        ch.j = bottom;
        for (int k = 0; k < 3; ++k) {
          ch.ring[k] = p[k];
          ch.ringTets[k] = edgeTets[k];
        }
      }
    }
}

// Edge removal: the n (4 to 6) tets around an interior edge (a, b), all of t's material,
// become 2(n - 2): the ring of their other nodes is triangulated as a fan from one ring node
// and each triangle joined to a and to b. Valid when a and b lie on opposite sides of every
// triangle (all new tets positive); n > 4 takes free slots.
void CutOptimizer::bestEdgeRemoval(int t, const FlipNeighbourhood& nb, FlipChoice& ch) {
  int avail = -1;  // the free slots, counted when first needed
  for (int i = 0, ei = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j, ++ei) {
      const int a = mesh.T(t, i), b = mesh.T(t, j);
      const std::int32_t* edgeTets = nb.edgeTetsOf[ei];
      const bool sameMat = nb.edgeSameMat[ei] != 0;
      const int n = nb.edgeN[ei];
      if (n > 4 && n <= 6 && avail < 0) avail = availSlots();
      if (n < 4 || n > 6 || (n > 4 && n - 4 > avail) || !sameMat) continue;
      // The ring: each tet's other two nodes, chained into one cycle.
      std::int32_t pr[6][2], cyc[6], cycT[6];
      bool used[6] = {false, false, false, false, false, false};
      for (int e = 0; e < n; ++e) {
        int m = 0;
        for (int k = 0; k < 4; ++k)
          if (mesh.T(edgeTets[e], k) != a && mesh.T(edgeTets[e], k) != b && m < 2) pr[e][m++] = mesh.T(edgeTets[e], k);
      }
      cyc[0] = pr[0][0];
      cyc[1] = pr[0][1];
      cycT[0] = edgeTets[0];
      used[0] = true;
      bool closed = true;
      for (int m = 2; m <= n && closed; ++m) {
        const int from = cyc[m - 1];
        int found = -1;
        for (int e = 0; e < n && found < 0; ++e)
          if (!used[e] && (pr[e][0] == from || pr[e][1] == from)) found = e;
        if (found < 0) {
          closed = false;
          break;
        }
        used[found] = true;
        cycT[m - 1] = edgeTets[found];
        const int to = pr[found][0] == from ? pr[found][1] : pr[found][0];
        if (m < n) {
          for (int l = 0; l < m; ++l) closed = closed && cyc[l] != to;
          cyc[m] = to;
        } else {
          closed = to == cyc[0];
        }
      }
      if (!closed) continue;
      double old = 1.0;
      for (int r = 0; r < n; ++r) old = std::min(old, ed.quality(edgeTets[r]));
      for (int apex = 0; apex < n; ++apex) {
        double qn = 1.0;
        int sign = 0;
        for (int m = 1; m + 1 < n && qn > ch.best; ++m) {
          const int p0 = cyc[apex], p1 = cyc[(apex + m) % n], p2 = cyc[(apex + m + 1) % n];
          const double va = vol6(p0, p1, p2, a), vb = vol6(p0, p1, p2, b);
          const int sg = va > 0 ? 1 : -1;
          if (!(va * vb < 0) || (sign != 0 && sg != sign)) {
            qn = -1;
            break;
          }
          sign = sg;
          qn = std::min(qn, sg > 0 ? std::min(q4(p0, p1, p2, a), q4(p0, p2, p1, b))
                                   : std::min(q4(p0, p2, p1, a), q4(p0, p1, p2, b)));
        }
        if (!(qn > ch.best && qn > old)) continue;
        // The fan's diagonals must not be edges already (where the mesh folds).
        bool exists = false;
        for (int m = 2; m + 1 < n && !exists; ++m) {
          const int d0 = cyc[apex], d1 = cyc[(apex + m) % n];
          for (const std::int32_t *s = ed.starBegin(d0), *sEnd = ed.starEnd(d0); s < sEnd && !exists; ++s)
            if (!dead[*s])
              for (int k = 0; k < 4; ++k) exists = exists || mesh.T(*s, k) == d1;
        }
        if (exists) continue;
        ch.best = qn;
        ch.kind = 2;
        ch.i = a;
        ch.j = b;
        ch.erN = n;
        ch.erApex = apex;
        for (int e = 0; e < n; ++e) {
          ch.erRing[e] = cyc[e];
          ch.erTets[e] = cycT[e];
        }
      }
    }
}

void CutOptimizer::applyFlip(int t, const FlipChoice& ch) {
  if (ch.kind == 0) {
    int v[4];
    for (int k = 0; k < 4; ++k) v[k] = mesh.T(t, k);
    const int e = ch.i, u = ch.u;
    const int extra = freeSlots.back();
    freeSlots.pop_back();
    const int slots[3] = {t, u, extra};
    dead[extra] = 0;
    mesh.material(extra) = mesh.material(t);
    for (int r = 0; r < 3; ++r) {
      int w[4] = {v[0], v[1], v[2], v[3]};
      w[kFace[ch.f][r]] = e;
      flipSetTet(slots[r], w[0], w[1], w[2], w[3]);
    }
    if (!dead[u]) ed.touch(mesh.T(u, 0));
  } else if (ch.kind == 1) {
    flipSetTet(ch.ringTets[0], ch.ring[0], ch.ring[1], ch.ring[2], ch.i);
    flipSetTet(ch.ringTets[1], ch.ring[0], ch.ring[2], ch.ring[1], ch.j);
    ed.markDead(ch.ringTets[2]);
    freeSlots.push_back(ch.ringTets[2]);
  } else if (ch.kind == 2) {
    const int a = ch.i, b = ch.j, n = ch.erN;
    std::int32_t slots[8];
    for (int e = 0; e < n; ++e) slots[e] = ch.erTets[e];
    for (int e = n; e < 2 * (n - 2); ++e) {
      while (!freeSlots.empty() && !dead[freeSlots.back()]) freeSlots.pop_back();
      slots[e] = freeSlots.back();  // (there are: counted when the removal was chosen)
      freeSlots.pop_back();
      dead[slots[e]] = 0;
      mesh.material(slots[e]) = mesh.material(t);
    }
    int next = 0;
    for (int m = 1; m + 1 < n; ++m) {
      const int p0 = ch.erRing[ch.erApex], p1 = ch.erRing[(ch.erApex + m) % n], p2 = ch.erRing[(ch.erApex + m + 1) % n];
      if (vol6(p0, p1, p2, a) > 0) {
        flipSetTet(slots[next++], p0, p1, p2, a);
        flipSetTet(slots[next++], p0, p2, p1, b);
      } else {
        flipSetTet(slots[next++], p0, p2, p1, a);
        flipSetTet(slots[next++], p0, p1, p2, b);
      }
    }
    ed.touch(a);
    ed.touch(b);
  }
}

// After a flip: the stars of the touched nodes rebuilt and marked with the flip's number.
void CutOptimizer::afterFlip() {
  ++flipClock;
  availNow = -1;
  flipRebuilt.assign(ed.pendingNodes().begin(), ed.pendingNodes().end());
  ed.refreshStars();
  if (flipMark.empty()) flipMark.assign(N, -1);
  for (int y : flipRebuilt) {
    flipMark[y] = flipClock;
    for (const std::int32_t *s = ed.starBegin(y), *sEnd = ed.starEnd(y); s < sEnd; ++s)
      if (!dead[*s])
        for (int k = 0; k < 4; ++k) flipMark[mesh.T(*s, k)] = flipClock;
  }
}

}  // namespace hysim::cutting::opt3d
