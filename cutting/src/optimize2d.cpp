// Mesh optimisation after a 2D cut (Fig. 1 of the paper), run before the two sides are
// separated (the cut nodes are fixed in the regularisation, so the order does not change
// the result, and collapses need to be done only once for both sides):
//   (a) edge collapse of short edges on the cut, and down to about length / mean edge
//       segments, so the node count stays constant;
//   (b) equal node distribution along the cut;
//   (c) local regularisation: nodes one or two edge steps from the cut move under a combined
//       mass-spring / particle system (constant masses, heavy damping), everything else
//       (cut and border nodes included) fixed, until the largest move is below 2% of the
//       mean edge length. A move that would fold or flatten an element is not taken.
#include <algorithm>
#include <cmath>

#include "cut2d_internal.hpp"

namespace hysim::cutting::detail {
namespace {

bool contains(const std::array<int, 3>& v, int x) { return v[0] == x || v[1] == x || v[2] == x; }

// Collapses r into s (s keeps its position). Returns false, changing nothing, when the
// link condition fails or an element would get quality < minQuality.
bool tryCollapse(Work& w, int r, int s, double minQuality) {
  // Link condition: the common neighbours of r and s are exactly the third nodes of the
  // triangles on edge (r, s).
  std::vector<int> nr, ns, third;
  w.neighbours(r, nr);
  w.neighbours(s, ns);
  for (int t : w.nodeTris[r])
    if (contains(w.tris[t].v, s))
      for (int k = 0; k < 3; ++k)
        if (w.tris[t].v[k] != r && w.tris[t].v[k] != s) third.push_back(w.tris[t].v[k]);
  if (third.empty()) return false;
  for (int x : nr)
    if (x != s && std::find(ns.begin(), ns.end(), x) != ns.end() && std::find(third.begin(), third.end(), x) == third.end())
      return false;
  // Geometry of the triangles that keep r (renamed s).
  const Vec2 ps = w.nodes[s].p;
  for (int t : w.nodeTris[r]) {
    const auto& v = w.tris[t].v;
    if (contains(v, s)) continue;
    Vec2 c[3];
    for (int k = 0; k < 3; ++k) c[k] = v[k] == r ? ps : w.nodes[v[k]].p;
    if (triQuality(c[0], c[1], c[2]) < minQuality) return false;
  }
  const std::vector<int> around = w.nodeTris[r];
  for (int t : around) {
    if (contains(w.tris[t].v, s)) {
      w.killTri(t);
      continue;
    }
    auto v = w.tris[t].v;
    for (int k = 0; k < 3; ++k)
      if (v[k] == r) v[k] = s;
    const int mat = w.tris[t].material;
    w.killTri(t);
    w.addTri(v[0], v[1], v[2], mat);
  }
  w.nodes[r].alive = false;
  w.nodes[r].merged_into = s;
  return true;
}

double chainLength(const Work& w, const std::vector<int>& ch) {
  double L = 0;
  for (std::size_t i = 0; i + 1 < ch.size(); ++i) L += (w.nodes[ch[i + 1]].p - w.nodes[ch[i]].p).norm();
  return L;
}

void collapseOnCut(Work& w, std::vector<int>& ch, double h, const Cut2DOptions& o, Cut2DReport& rep) {
  if (ch.size() < 3) return;
  const int target = std::max(1, static_cast<int>(std::lround(chainLength(w, ch) / h)));
  for (int guard = 0; guard < 1000; ++guard) {
    const int segs = static_cast<int>(ch.size()) - 1;
    if (segs <= 1) return;
    // Segments by length, shortest first.
    std::vector<std::pair<double, int>> order;
    for (int i = 0; i < segs; ++i) order.push_back({(w.nodes[ch[i + 1]].p - w.nodes[ch[i]].p).norm(), i});
    std::sort(order.begin(), order.end());
    bool done = false;
    for (const auto& [len, i] : order) {
      if (segs <= target && len >= o.optimize.collapse_ratio * h) return;
      // Candidates to remove: not an end of the chain, not on the border; new nodes first.
      int cand[2] = {ch[i + 1], ch[i]};
      int pos[2] = {i + 1, i};
      if (w.nodes[cand[1]].old < 0 && w.nodes[cand[0]].old >= 0) {
        std::swap(cand[0], cand[1]);
        std::swap(pos[0], pos[1]);
      }
      for (int k = 0; k < 2 && !done; ++k) {
        const int r = cand[k], s = cand[1 - k];
        if (pos[k] == 0 || pos[k] == segs || w.isBorderNode(r)) continue;
        if (tryCollapse(w, r, s, o.min_quality)) {
          ch.erase(ch.begin() + pos[k]);
          ++rep.collapsed_edges;
          done = true;
        }
      }
      if (done) break;
    }
    if (!done) return;
  }
}

// Point at arc length `a` along the polyline through `pts`.
Vec2 atArcLength(const std::vector<Vec2>& pts, double a) {
  for (std::size_t i = 0; i + 1 < pts.size(); ++i) {
    const double l = (pts[i + 1] - pts[i]).norm();
    if (a <= l || i + 2 == pts.size()) return l > 0 ? pts[i] + (std::min(a, l) / l) * (pts[i + 1] - pts[i]) : pts[i];
    a -= l;
  }
  return pts.back();
}

void distributeOnCut(Work& w, const std::vector<int>& ch, double minQuality) {
  if (ch.size() < 3) return;
  // Pieces between anchors (the ends and border nodes).
  std::size_t start = 0;
  for (std::size_t end = 1; end < ch.size(); ++end) {
    if (end + 1 != ch.size() && !w.isBorderNode(ch[end])) continue;
    if (end - start >= 2) {
      std::vector<Vec2> pts;
      for (std::size_t i = start; i <= end; ++i) pts.push_back(w.nodes[ch[i]].p);
      double L = 0;
      for (std::size_t i = 0; i + 1 < pts.size(); ++i) L += (pts[i + 1] - pts[i]).norm();
      const double n = static_cast<double>(end - start);
      for (std::size_t i = start + 1; i < end; ++i) {
        const Vec2 target = atArcLength(pts, L * static_cast<double>(i - start) / n);
        const int node = ch[i];
        const double before = w.minQualityAround(node);
        // Full move, or half of it, if that keeps the elements good enough.
        for (double f : {1.0, 0.5}) {
          const Vec2 p = w.nodes[node].p + f * (target - w.nodes[node].p);
          const double after = w.minQualityIfMoved(node, p);
          if (after > 0 && (after >= minQuality || after >= before)) {
            w.nodes[node].p = p;
            break;
          }
        }
      }
    }
    start = end;
  }
}

// The nodes regularise moves, with the tangent a border node slides along (zero inside),
// their neighbour lists (CSR) and the mean local edge length.
struct Springs {
  std::vector<int> movable;
  std::vector<Vec2> tangent;
  std::vector<int> start{0}, adj;
  double L0 = 0;
};

// The nodes one to `rings` edge steps from the cut chains, ring by ring.
std::vector<int> nodesNearCut(const Work& w, const Chains& chains, int rings) {
  const int N = static_cast<int>(w.nodes.size());
  std::vector<int> ring(N, -1);
  std::vector<int> frontier, next, nb;
  for (const auto& ch : chains)
    for (int n : ch)
      if (ring[n] < 0) {
        ring[n] = 0;
        frontier.push_back(n);
      }
  std::vector<int> movable;
  for (int r = 1; r <= rings; ++r) {
    next.clear();
    for (int n : frontier) {
      w.neighbours(n, nb);
      for (int x : nb)
        if (ring[x] < 0) {
          ring[x] = r;
          next.push_back(x);
          movable.push_back(x);
        }
    }
    frontier.swap(next);
  }
  return movable;
}

// Border nodes slide along the border where it is straight (their two border edges
// collinear); elsewhere on the border (curves, corners) they stay.
void keepMovable(const Work& w, Springs& s) {
  std::vector<int> keep, nb;
  for (int n : s.movable) {
    if (!w.isBorderNode(n)) {
      keep.push_back(n);
      s.tangent.push_back(Vec2::Zero());
      continue;
    }
    w.neighbours(n, nb);
    std::vector<int> bn;
    for (int x : nb)
      if (w.isBorderEdge(n, x)) bn.push_back(x);
    if (bn.size() != 2) continue;
    const Vec2 d0 = w.nodes[n].p - w.nodes[bn[0]].p, d1 = w.nodes[bn[1]].p - w.nodes[n].p;
    if (std::abs(cross2(d0, d1)) > 1e-12 * d0.norm() * d1.norm() || d0.dot(d1) <= 0) continue;
    keep.push_back(n);
    s.tangent.push_back(d0.normalized());
  }
  s.movable.swap(keep);
}

// Compact neighbour lists (CSR) and the mean local edge length.
void buildNeighbourLists(const Work& w, Springs& s) {
  std::vector<int> nb;
  int ne = 0;
  for (int n : s.movable) {
    w.neighbours(n, nb);
    for (int x : nb) {
      s.adj.push_back(x);
      s.L0 += (w.nodes[x].p - w.nodes[n].p).norm();
      ++ne;
    }
    s.start.push_back(static_cast<int>(s.adj.size()));
  }
  s.L0 /= std::max(ne, 1);
}

void springForces(const Work& w, const Springs& s, const Optimize2DOptions& oo, std::vector<Vec2>& force) {
  const double L0 = s.L0;
  for (size_t i = 0; i < s.movable.size(); ++i) {
    const Vec2 xi = w.nodes[s.movable[i]].p;
    Vec2 f = Vec2::Zero();
    for (int k = s.start[i]; k < s.start[i + 1]; ++k) {
      const Vec2 d = w.nodes[s.adj[k]].p - xi;
      const double r = d.norm();
      if (r <= 1e-12 * L0) continue;
      // Spring towards the rest length L0 (alpha), particle repulsion inside L0 (beta):
      // magnitude L0^2/r - r, unbounded as r -> 0, capped at L0 for stability.
      double mag = oo.spring_weight * (r - L0);
      if (r < L0) mag -= oo.particle_weight * std::min(L0 * L0 / r - r, L0);
      f += (mag / r) * d;
    }
    force[i] = f;
  }
}

// One damped step of every movable node; returns the largest move taken.
double moveNodes(Work& w, const Springs& s, const Optimize2DOptions& oo, const std::vector<Vec2>& force,
                 std::vector<Vec2>& vel) {
  const double minArea2 = 1e-3 * s.L0 * s.L0;  // never flatten: twice the area stays above this
  const double damping = 0.1;  // fraction of velocity kept per step (heavy damping)
  double maxMove = 0;
  for (size_t i = 0; i < s.movable.size(); ++i) {
    const int n = s.movable[i];
    vel[i] = damping * vel[i] + oo.step_gain * force[i];
    if (s.tangent[i].x() != 0 || s.tangent[i].y() != 0) vel[i] = vel[i].dot(s.tangent[i]) * s.tangent[i];
    const Vec2 p = w.nodes[n].p + vel[i];
    // Never fold or flatten an element, and never push the worst element around the node
    // below min(its current quality, quality_guard).
    bool ok = true;
    double qBefore = 1.0, qAfter = 1.0;
    for (int t : w.nodeTris[n]) {
      const auto& v = w.tris[t].v;
      Vec2 c[3];
      for (int k = 0; k < 3; ++k) c[k] = v[k] == n ? p : w.nodes[v[k]].p;
      if (orient(c[0], c[1], c[2]) <= minArea2) {
        ok = false;
        break;
      }
      qAfter = std::min(qAfter, triQuality(c[0], c[1], c[2]));
      qBefore = std::min(qBefore, triQuality(w.nodes[v[0]].p, w.nodes[v[1]].p, w.nodes[v[2]].p));
    }
    if (ok && qAfter < std::min(qBefore, oo.quality_guard)) ok = false;
    if (!ok) {
      vel[i].setZero();
      continue;
    }
    maxMove = std::max(maxMove, vel[i].norm());
    w.nodes[n].p = p;
  }
  return maxMove;
}

void regularise(Work& w, const Chains& chains, double meanEdge, const Cut2DOptions& o, Cut2DReport& rep) {
  const auto& oo = o.optimize;
  Springs s;
  s.movable = nodesNearCut(w, chains, oo.rings);
  keepMovable(w, s);
  rep.regularised_nodes = static_cast<int>(s.movable.size());
  if (s.movable.empty()) return;
  buildNeighbourLists(w, s);
  const double stop = oo.stop_fraction * meanEdge;
  const int M = static_cast<int>(s.movable.size());
  std::vector<Vec2> vel(M, Vec2::Zero()), force(M);
  int it = 0;
  for (; it < oo.max_iterations; ++it) {
    springForces(w, s, oo, force);
    if (moveNodes(w, s, oo, force, vel) < stop) {
      ++it;
      break;
    }
  }
  rep.regularisation_iterations = it;
}


// ---------------------------------------------------------------------------------------
// Quality repair (beyond the paper's Fig. 1, within its "mesh optimisation"): local
// topology and position operations driven by the worst elements near the cut.
//   - edge flips that raise the smaller quality of the two triangles (never a cut or border
//     edge, never a fold);
//   - node optimisation: a node moves (pattern search) to raise the worst quality of its
//     triangles; interior nodes move freely, cut nodes slide along the cut (before the
//     sides are separated, so both copies move together), border nodes slide along straight
//     border stretches only; chain ends, corners and curved-border nodes stay;
//   - node budget: edge collapses near the cut remove the nodes the cut added, so that the
//     node (and element) count stays that of the input.

struct RepairContext {
  std::vector<char> onCut;        // per node: on a chain
  std::vector<char> chainEnd;     // per node: first or last node of a chain
  std::vector<Vec2> slide;        // per node: unit direction it may move along (0: free)
  std::vector<signed char> kind;  // -1 unknown, 0 fixed, 1 free, 2 slides along `slide`
};

// How node n may move: fixed, free, or along a line.
int nodeKind(Work& w, const Chains& chains, RepairContext& rc, int n) {
  if (rc.kind[n] >= 0) return rc.kind[n];
  int k = 1;
  if (rc.chainEnd[n]) {
    k = 0;
  } else if (rc.onCut[n]) {
    k = 0;
    for (const auto& ch : chains)
      for (std::size_t i = 1; i + 1 < ch.size(); ++i)
        if (ch[i] == n && !w.isBorderNode(n)) {
          const Vec2 d = w.nodes[ch[i + 1]].p - w.nodes[ch[i - 1]].p;
          if (d.norm() > 0) {
            rc.slide[n] = d.normalized();
            k = 2;
          }
        }
  } else if (w.isBorderNode(n)) {
    k = 0;
    std::vector<int> nb, bn;
    w.neighbours(n, nb);
    for (int x : nb)
      if (w.isBorderEdge(n, x)) bn.push_back(x);
    if (bn.size() == 2) {
      const Vec2 d0 = w.nodes[n].p - w.nodes[bn[0]].p, d1 = w.nodes[bn[1]].p - w.nodes[n].p;
      if (std::abs(cross2(d0, d1)) <= 1e-12 * d0.norm() * d1.norm() && d0.dot(d1) > 0) {
        rc.slide[n] = d0.normalized();
        k = 2;
      }
    }
  }
  rc.kind[n] = static_cast<signed char>(k);
  return k;
}

// Pattern search on the worst quality around n. Returns true when n moved.
bool optimiseNode(Work& w, int n, int kind, const Vec2& dir, double h) {
  if (kind == 0 || w.nodeTris[n].empty()) return false;
  static const double c = std::sqrt(0.5);
  static const Vec2 dirs8[8] = {Vec2(1, 0), Vec2(-1, 0), Vec2(0, 1), Vec2(0, -1),
                                Vec2(c, c), Vec2(-c, -c), Vec2(c, -c), Vec2(-c, c)};
  double best = w.minQualityAround(n);
  Vec2 p = w.nodes[n].p;
  const Vec2 start = p;
  // First try the centroid of the neighbours (Laplacian), the usual good guess.
  if (kind == 1) {
    std::vector<int> nb;
    w.neighbours(n, nb);
    Vec2 cen = Vec2::Zero();
    for (int x : nb) cen += w.nodes[x].p;
    cen /= static_cast<double>(nb.size());
    const double q = w.minQualityIfMoved(n, cen);
    if (q > best) {
      best = q;
      p = cen;
    }
  }
  double s = 0.2 * h;
  for (int it = 0; it < 24 && s > 0.004 * h; ++it) {
    Vec2 bp = p;
    double bq = best;
    const int nd = kind == 1 ? 8 : 2;
    for (int k = 0; k < nd; ++k) {
      const Vec2 d = kind == 1 ? dirs8[k] : (k == 0 ? dir : Vec2(-dir));
      const Vec2 cand = p + s * d;
      const double q = w.minQualityIfMoved(n, cand);
      if (q > bq + 1e-9) {
        bq = q;
        bp = cand;
      }
    }
    if (bq > best) {
      best = bq;
      p = bp;
    } else {
      s *= 0.5;
    }
  }
  if (p == start) return false;
  w.nodes[n].p = p;
  return true;
}

// Flips edge (x, y) when that raises the smaller quality of its two triangles.
bool tryFlip(Work& w, const RepairContext& rc, int x, int y) {
  if (rc.onCut[x] && rc.onCut[y]) return false;
  int tt[2];
  if (w.edgeTris(x, y, tt) != 2) return false;
  // t1 = (x, y, a), t2 = (y, x, d), counter-clockwise.
  auto rot = [&](int t, int first) {
    auto v = w.tris[t].v;
    while (v[0] != first) std::rotate(v.begin(), v.begin() + 1, v.end());
    return v;
  };
  auto v1 = rot(tt[0], x);
  int t1 = tt[0], t2 = tt[1];
  if (v1[1] != y) {
    std::swap(t1, t2);
    v1 = rot(t1, x);
  }
  const auto v2 = rot(t2, y);
  if (v1[1] != y || v2[1] != x) return false;
  const int a = v1[2], d = v2[2];
  if (a == d) return false;
  // The new edge must not exist already.
  for (int t : w.nodeTris[a])
    if (contains(w.tris[t].v, d)) return false;
  const Vec2 &px = w.nodes[x].p, &py = w.nodes[y].p, &pa = w.nodes[a].p, &pd = w.nodes[d].p;
  const double before = std::min(triQuality(px, py, pa), triQuality(py, px, pd));
  const double after = std::min(triQuality(px, pd, pa), triQuality(py, pa, pd));
  if (after <= before + 1e-9) return false;
  const int m1 = w.tris[t1].material, m2 = w.tris[t2].material;
  w.killTri(t1);
  w.killTri(t2);
  w.addTri(x, d, a, m1);
  w.addTri(y, a, d, m2);
  return true;
}

void bandNodes(const Work& w, const Chains& chains, int rings, std::vector<int>& out) {
  out.clear();
  std::vector<char> seen(w.nodes.size(), 0);
  std::vector<int> frontier, next, nb;
  for (const auto& ch : chains)
    for (int n : ch)
      if (!seen[n]) {
        seen[n] = 1;
        out.push_back(n);
        frontier.push_back(n);
      }
  for (int r = 1; r <= rings; ++r) {
    next.clear();
    for (int n : frontier) {
      w.neighbours(n, nb);
      for (int x : nb)
        if (!seen[x]) {
          seen[x] = 1;
          out.push_back(x);
          next.push_back(x);
        }
    }
    frontier.swap(next);
  }
}

void repair(Work& w, Chains& chains, double h, const Cut2DOptions& o, Cut2DReport& rep) {
  const double target = o.optimize.repair_quality;
  RepairContext rc;
  const std::size_t N = w.nodes.size();
  rc.onCut.assign(N, 0);
  rc.chainEnd.assign(N, 0);
  rc.slide.assign(N, Vec2::Zero());
  rc.kind.assign(N, -1);
  for (const auto& ch : chains) {
    for (int n : ch) rc.onCut[n] = 1;
    if (!ch.empty()) rc.chainEnd[ch.front()] = rc.chainEnd[ch.back()] = 1;
  }
  std::vector<int> band, tris, nb, bad;
  bandNodes(w, chains, o.optimize.rings + 1, band);
  std::vector<int> triStamp, nodeStamp(N, -1);
  for (int round = 0; round < o.optimize.repair_rounds; ++round) {
    // Triangles of the band below the target quality.
    triStamp.assign(w.tris.size(), 0);
    bad.clear();
    for (int n : band)
      for (int t : w.nodeTris[n]) {
        if (triStamp[t]) continue;
        triStamp[t] = 1;
        const auto& v = w.tris[t].v;
        if (triQuality(w.nodes[v[0]].p, w.nodes[v[1]].p, w.nodes[v[2]].p) < target) bad.push_back(t);
      }
    if (bad.empty()) break;
    bool changed = false;
    for (int t : bad) {
      if (!w.tris[t].alive) continue;
      const auto v = w.tris[t].v;
      for (int k = 0; k < 3 && w.tris[t].alive; ++k)
        if (tryFlip(w, rc, v[k], v[(k + 1) % 3])) {
          ++rep.repair_flips;
          changed = true;
        }
    }
    // Each node of a bad triangle and its neighbours (a triangle whose corners cannot move
    // improves when its neighbours make room), once per round, worst triangles first.
    auto visit = [&](int n) {
      if (nodeStamp[n] == round) return;
      nodeStamp[n] = round;
      if (optimiseNode(w, n, nodeKind(w, chains, rc, n), rc.slide[n], h)) {
        ++rep.repair_moves;
        changed = true;
      }
    };
    for (int t : bad) {
      if (!w.tris[t].alive) continue;
      const auto v = w.tris[t].v;
      for (int k = 0; k < 3; ++k) visit(v[k]);
    }
    for (int t : bad) {
      if (!w.tris[t].alive) continue;
      const auto v = w.tris[t].v;
      if (triQuality(w.nodes[v[0]].p, w.nodes[v[1]].p, w.nodes[v[2]].p) >= target) continue;
      for (int k = 0; k < 3; ++k) {
        w.neighbours(v[k], nb);
        for (int x : nb) visit(x);
      }
    }
    if (!changed) break;
  }
}

// Smallest quality of the triangles around r if r were merged into s (the triangles on edge
// (r, s) disappear); -1 when the link condition fails (the result would not be manifold).
// `nr` holds the neighbours of r.
double collapseQuality(const Work& w, int r, int s, const std::vector<int>& nr, std::vector<int>& ns) {
  w.neighbours(s, ns);
  int third = 0;
  for (int t : w.nodeTris[r]) third += contains(w.tris[t].v, s);
  if (third == 0) return -1;
  int common = 0;
  for (int x : nr)
    if (x != s && std::find(ns.begin(), ns.end(), x) != ns.end()) ++common;
  if (common != third) return -1;
  const Vec2 ps = w.nodes[s].p;
  double q = 1.0;
  for (int t : w.nodeTris[r]) {
    const auto& v = w.tris[t].v;
    if (contains(v, s)) continue;
    Vec2 c[3];
    for (int k = 0; k < 3; ++k) c[k] = v[k] == r ? ps : w.nodes[v[k]].p;
    q = std::min(q, triQuality(c[0], c[1], c[2]));
  }
  return q;
}

// Node budget: while the mesh has more (alive, used) nodes than `target`, merges the node
// near the cut whose removal leaves the best worst element (nodes made by this cut first).
void collapseToBudget(Work& w, Chains& chains, int target, double h, const Cut2DOptions& o, Cut2DReport& rep) {
  int count = 0;
  for (std::size_t i = 0; i < w.nodes.size(); ++i) count += w.nodes[i].alive && !w.nodeTris[i].empty();
  std::vector<int> band, nr, ns;
  std::vector<int> prev(w.nodes.size(), -1), next(w.nodes.size(), -1);
  std::vector<char> chainEnd(w.nodes.size(), 0);
  for (int guard = 0; count > target && guard < 64; ++guard) {
    // Candidates: the cut's nodes and their neighbours.
    bandNodes(w, chains, 1, band);
    std::fill(prev.begin(), prev.end(), -1);
    std::fill(next.begin(), next.end(), -1);
    std::fill(chainEnd.begin(), chainEnd.end(), 0);
    for (const auto& ch : chains) {
      for (std::size_t i = 0; i + 1 < ch.size(); ++i) {
        next[ch[i]] = ch[i + 1];
        prev[ch[i + 1]] = ch[i];
      }
      if (!ch.empty()) chainEnd[ch.front()] = chainEnd[ch.back()] = 1;
    }
    double bestScore = -1e300;
    int br = -1, bs = -1;
    for (int r : band) {
      if (chainEnd[r] || w.isBorderNode(r)) continue;
      const bool cutNode = prev[r] >= 0 || next[r] >= 0;
      w.neighbours(r, nr);
      for (int s : nr) {
        // A cut node merges only into its neighbour along the cut.
        if (cutNode && s != prev[r] && s != next[r]) continue;
        const double q = collapseQuality(w, r, s, nr, ns);
        if (q < o.optimize.collapse_quality) continue;
        const double len = (w.nodes[r].p - w.nodes[s].p).norm();
        // Prefer good results, short edges and nodes this cut made.
        const double score = q - 0.2 * len / h + (w.nodes[r].old < 0 ? 0.1 : 0.0);
        if (score > bestScore) {
          bestScore = score;
          br = r;
          bs = s;
        }
      }
    }
    if (br < 0 || !tryCollapse(w, br, bs, -1.0)) break;
    for (auto& ch : chains) {
      auto it = std::find(ch.begin(), ch.end(), br);
      if (it != ch.end()) ch.erase(it);
    }
    ++rep.collapsed_edges;
    --count;
  }
}

}  // namespace

void optimizeAfterCut(Work& w, Chains& chains, double meanEdge, int targetNodes, const Cut2DOptions& options,
                      Cut2DReport& report) {
  for (auto& ch : chains) collapseOnCut(w, ch, meanEdge, options, report);
  if (options.optimize.distribute)
    for (const auto& ch : chains) distributeOnCut(w, ch, options.min_quality);
  if (targetNodes >= 0) collapseToBudget(w, chains, targetNodes, meanEdge, options, report);
  if (options.optimize.rings > 0) regularise(w, chains, meanEdge, options, report);
  if (options.optimize.repair_rounds > 0) repair(w, chains, meanEdge, options, report);
}

}  // namespace hysim::cutting::detail
