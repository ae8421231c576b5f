// 2D cutting: hybrid (snap / subdivide / flip), standard subdivision, snapping only and
// element deletion, one pipeline:
//   1. intersect the cut with the mesh: events (the cut passes through a node, or crosses
//      an edge at a fraction t), ordered along the cut, grouped into chains of events that
//      share an element (the part of the cut inside the mesh);
//   2. hybrid / snap: displace nodes onto the cut where the cut crosses an edge near them
//      (Fig. 5 regions), border nodes only along the border and not at features, never
//      folding or flattening an element; then re-intersect;
//   3. hybrid: an edge flip where two type-2 cases follow each other (Fig. 4);
//   4. subdivide the remaining crossings: a crossed element gets 1 (type 2) or 2 (type 3)
//      new elements;
//   5. hybrid: optimisation (optimize2d.cpp);
//   6. duplicate the nodes on the cut so that the two sides share no edge;
//   7. compact into a TriMesh and a TopologyChange.
#include "hysim/cutting/cut2d.hpp"

#include <algorithm>
#include <chrono>
#include <map>
#include <cmath>
#include <numeric>
#include <string>
#include <unordered_map>

#include "cut2d_internal.hpp"

namespace hysim::cutting {

using detail::Chains;
using detail::orient;
using detail::triQuality;
using detail::Vec2;
using detail::Work;

const char* cutMethodName(CutMethod method) {
  switch (method) {
    case CutMethod::Hybrid: return "hybrid";
    case CutMethod::Standard: return "standard";
    case CutMethod::Snap: return "snap";
    case CutMethod::Delete: return "delete";
  }
  return "?";
}

bool parseCutMethod(const std::string& name, CutMethod* method) {
  for (CutMethod m : {CutMethod::Hybrid, CutMethod::Standard, CutMethod::Snap, CutMethod::Delete})
    if (name == cutMethodName(m)) {
      *method = m;
      return true;
    }
  return false;
}

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

struct Event {
  bool vertex = false;
  int node = -1;        // vertex event
  int a = -1, b = -1;   // edge event: edge (a, b), crossing at (1-t) a + t b
  double t = 0;
  double s = 0;         // position along the polyline: segment index + fraction
  Vec2 p;
};

struct Polyline {
  std::vector<Vec2> pts;
  // Closest point on the polyline to q.
  Vec2 closest(const Vec2& q) const {
    Vec2 best = pts[0];
    double bd = 1e300;
    for (std::size_t i = 0; i + 1 < pts.size(); ++i) {
      const Vec2 d = pts[i + 1] - pts[i];
      const double l2 = d.squaredNorm();
      double u = l2 > 0 ? (q - pts[i]).dot(d) / l2 : 0.0;
      u = std::clamp(u, 0.0, 1.0);
      const Vec2 c = pts[i] + u * d;
      const double dd = (c - q).squaredNorm();
      if (dd < bd) {
        bd = dd;
        best = c;
      }
    }
    return best;
  }
};

std::uint64_t edgeKey(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

// All unique alive edges.
std::vector<std::array<int, 2>> allEdges(const Work& w) {
  std::vector<std::array<int, 2>> edges;
  for (const auto& t : w.tris) {
    if (!t.alive) continue;
    for (int k = 0; k < 3; ++k) {
      const int a = t.v[k], b = t.v[(k + 1) % 3];
      // Each interior edge appears twice (once per direction); keep a < b, and keep border
      // edges (which appear once) whatever their direction.
      int tt[2];
      const int n = w.edgeTris(a, b, tt);
      if (a < b || n == 1) edges.push_back({a, b});
    }
  }
  return edges;
}

// Intersects the cut with the mesh. Nodes within `eps` of the cut are vertex events; edges
// with neither end a vertex event that properly cross the cut are edge events (one per
// edge, the first along the cut). Sorted along the cut.
std::vector<Event> computeEvents(const Work& w, const Polyline& pl, double eps) {
  std::vector<Event> events;
  std::vector<char> isVertex(w.nodes.size(), 0);
  const int nseg = static_cast<int>(pl.pts.size()) - 1;
  for (int n = 0; n < static_cast<int>(w.nodes.size()); ++n) {
    if (!w.nodes[n].alive || w.nodeTris[n].empty()) continue;
    const Vec2& q = w.nodes[n].p;
    for (int i = 0; i < nseg; ++i) {
      const Vec2 d = pl.pts[i + 1] - pl.pts[i];
      const double l2 = d.squaredNorm();
      if (l2 <= 0) continue;
      const double u = (q - pl.pts[i]).dot(d) / l2;
      if (u < -eps / std::sqrt(l2) || u > 1 + eps / std::sqrt(l2)) continue;
      const double dist = std::abs(detail::cross2(d, q - pl.pts[i])) / std::sqrt(l2);
      if (dist <= eps) {
        Event e;
        e.vertex = true;
        e.node = n;
        e.s = i + std::clamp(u, 0.0, 1.0);
        e.p = q;
        events.push_back(e);
        isVertex[n] = 1;
        break;
      }
    }
  }
  std::unordered_map<std::uint64_t, int> edgeEvent;
  for (const auto& e : allEdges(w)) {
    const int a = e[0], b = e[1];
    if (isVertex[a] || isVertex[b]) continue;
    const Vec2& pa = w.nodes[a].p;
    const Vec2& pb = w.nodes[b].p;
    for (int i = 0; i < nseg; ++i) {
      const Vec2& p0 = pl.pts[i];
      const Vec2& p1 = pl.pts[i + 1];
      const double oa = orient(p0, p1, pa), ob = orient(p0, p1, pb);
      if (!((oa > 0 && ob < 0) || (oa < 0 && ob > 0))) continue;
      const double o0 = orient(pa, pb, p0), o1 = orient(pa, pb, p1);
      if ((o0 > 0 && o1 > 0) || (o0 < 0 && o1 < 0)) continue;
      const double t = oa / (oa - ob);
      const double u = (o0 == o1) ? 0.0 : o0 / (o0 - o1);
      Event ev;
      ev.a = a;
      ev.b = b;
      ev.t = t;
      ev.p = (1 - t) * pa + t * pb;
      ev.s = i + std::clamp(u, 0.0, 1.0);
      auto it = edgeEvent.find(edgeKey(a, b));
      if (it == edgeEvent.end()) {
        edgeEvent.emplace(edgeKey(a, b), static_cast<int>(events.size()));
        events.push_back(ev);
      } else if (ev.s < events[it->second].s) {
        events[it->second] = ev;
      }
      break;
    }
  }
  std::sort(events.begin(), events.end(), [](const Event& x, const Event& y) { return x.s < y.s; });
  return events;
}

// Triangles an event touches.
void eventTris(const Work& w, const Event& e, std::vector<int>& out) {
  out.clear();
  if (e.vertex) {
    out = w.nodeTris[e.node];
  } else {
    int t[2];
    const int n = w.edgeTris(e.a, e.b, t);
    for (int i = 0; i < std::min(n, 2); ++i) out.push_back(t[i]);
  }
}

// Groups consecutive events sharing a triangle into chains (the pieces of the cut inside
// the mesh); chains of a single event are dropped (the cut only touches the mesh there).
std::vector<std::vector<Event>> eventChains(const Work& w, const std::vector<Event>& events) {
  std::vector<std::vector<Event>> chains;
  std::vector<int> ta, tb;
  std::vector<Event> cur;
  for (std::size_t i = 0; i < events.size(); ++i) {
    bool connected = false;
    if (!cur.empty()) {
      eventTris(w, cur.back(), ta);
      eventTris(w, events[i], tb);
      for (int x : ta)
        for (int y : tb) connected = connected || x == y;
    }
    if (!connected) {
      if (cur.size() >= 2) chains.push_back(cur);
      cur.clear();
    }
    cur.push_back(events[i]);
  }
  if (cur.size() >= 2) chains.push_back(cur);
  return chains;
}

struct BorderInfo {
  std::vector<std::vector<int>> borderNbrs;  // border neighbours of each node
  std::vector<char> corner;                  // feature node: must not move
};

BorderInfo borderInfo(const Work& w, double featureAngleDeg) {
  BorderInfo bi;
  bi.borderNbrs.assign(w.nodes.size(), {});
  bi.corner.assign(w.nodes.size(), 0);
  for (const auto& t : w.tris) {
    if (!t.alive) continue;
    for (int k = 0; k < 3; ++k) {
      const int a = t.v[k], b = t.v[(k + 1) % 3];
      if (w.isBorderEdge(a, b)) {
        bi.borderNbrs[a].push_back(b);
        bi.borderNbrs[b].push_back(a);
      }
    }
  }
  const double cosMax = std::cos(featureAngleDeg * 3.14159265358979323846 / 180.0);
  for (int n = 0; n < static_cast<int>(w.nodes.size()); ++n) {
    const auto& nb = bi.borderNbrs[n];
    if (nb.empty()) continue;
    if (nb.size() != 2) {
      bi.corner[n] = 1;  // pinched border: treat as a feature
      continue;
    }
    const Vec2 d0 = (w.nodes[n].p - w.nodes[nb[0]].p).normalized();
    const Vec2 d1 = (w.nodes[nb[1]].p - w.nodes[n].p).normalized();
    // The angle between the two edges' normals equals the angle between their directions
    // when both are walked the same way round the border.
    if (d0.dot(d1) < cosMax) bi.corner[n] = 1;
  }
  return bi;
}

// Hybrid / snapping-only: displaces nodes onto the cut (step 2).
void displaceNodes(Work& w, const Polyline& pl, const std::vector<std::vector<Event>>& chains, double region,
                   double minQuality, const BorderInfo& bi, Cut2DReport& report) {
  struct Candidate {
    int node;
    double frac;      // distance along the edge from the node, as a fraction of the edge
    Vec2 edgePoint;   // crossing point on that edge
    bool borderEdge;
  };
  std::vector<Candidate> cands;
  for (const auto& chain : chains)
    for (const auto& e : chain) {
      if (e.vertex) continue;
      const bool nearA = e.t < 0.5;
      const double frac = nearA ? e.t : 1 - e.t;
      const bool borderEdge = w.isBorderEdge(e.a, e.b);
      // On a border edge the nearer node may slide along the border up to the middle (a
      // border subdivision would add a node that the optimisation cannot move away).
      if (frac >= (borderEdge ? std::max(region, 0.5001) : region)) continue;
      cands.push_back({nearA ? e.a : e.b, frac, e.p, borderEdge});
    }
  std::stable_sort(cands.begin(), cands.end(), [](const Candidate& x, const Candidate& y) { return x.frac < y.frac; });
  std::vector<char> done(w.nodes.size(), 0);
  for (const auto& c : cands) {
    if (done[c.node]) continue;
    const int n = c.node;
    const bool border = !bi.borderNbrs[n].empty();
    std::vector<Vec2> targets;
    if (border) {
      // Only along the border, never at a feature: the target must be the cut's crossing
      // with one of the node's own border edges.
      if (bi.corner[n] || !c.borderEdge) continue;
      targets.push_back(c.edgePoint);
    } else {
      targets.push_back(pl.closest(w.nodes[n].p));
      // Fig. 4 special treatment: when the projection onto the cut would fold or flatten a
      // neighbour, displace the node to the cut point on its own edge instead.
      targets.push_back(c.edgePoint);
    }
    for (const Vec2& p : targets) {
      if (w.minQualityIfMoved(n, p) >= minQuality) {
        w.nodes[n].p = p;
        done[n] = 1;
        ++report.displaced_nodes;
        if (border) ++report.border_displacements;
        break;
      }
    }
  }
}

// Hybrid: where the cut enters or leaves the mesh through a border edge close to a feature
// node (a corner, which must not move), the cut is bent to pass through that node: within
// the first element it runs from the corner to the original line instead of cutting off a
// sliver of the corner that no element of the mesh's size could represent well. Returns
// true when the polyline changed.
bool bendToCorners(const Work& w, Polyline& pl, const std::vector<std::vector<Event>>& chains, const BorderInfo& bi,
                   double region, double h) {
  if (chains.empty() || region <= 0) return false;
  const int nseg = static_cast<int>(pl.pts.size()) - 1;
  auto corner = [&](const Event& e) {
    if (e.vertex || !w.isBorderEdge(e.a, e.b)) return -1;
    const int n = e.t < 0.5 ? e.a : e.b;
    return bi.corner[n] && std::min(e.t, 1 - e.t) < region ? n : -1;
  };
  const Event first = chains.front().front(), last = chains.back().back();
  const int c0 = corner(first), c1 = corner(last);
  if (c0 < 0 && c1 < 0) return false;
  std::vector<Vec2> pts = pl.pts;
  if (c1 >= 0) {
    const int i = std::clamp(static_cast<int>(std::floor(last.s)), 0, nseg - 1);
    const Vec2 d = (pts[i + 1] - pts[i]).normalized();
    const Vec2 y = last.p - std::min(h, 0.5 * (last.p - pts[i]).norm()) * d;
    pts.resize(i + 1);
    pts.push_back(y);
    pts.push_back(w.nodes[c1].p);
  }
  if (c0 >= 0) {
    const int i = std::clamp(static_cast<int>(std::floor(first.s)), 0, nseg - 1);
    const Vec2 d = (pts[i + 1] - pts[i]).normalized();
    const Vec2 y = first.p + std::min(h, 0.5 * (pts[i + 1] - first.p).norm()) * d;
    std::vector<Vec2> head{w.nodes[c0].p, y};
    pts.erase(pts.begin(), pts.begin() + i + 1);
    pts.insert(pts.begin(), head.begin(), head.end());
  }
  pl.pts = pts;
  return true;
}

// Hybrid look-ahead (step 3): vertex a -> edge (x, y) -> vertex d, i.e. two type-2 cases
// in a row, becomes one edge flip (x, y) -> (a, d) when both new elements are good enough.
// Otherwise the two triangles are subdivided later (two new elements).
int flipConsecutiveType2(Work& w, const Polyline& pl, double eps, double minQuality) {
  int flips = 0;
  std::vector<std::uint64_t> tried;
  for (int guard = 0; guard < 10000; ++guard) {
    const auto chains = eventChains(w, computeEvents(w, pl, eps));
    bool flipped = false;
    for (const auto& ch : chains) {
      for (std::size_t i = 0; i + 2 < ch.size() && !flipped; ++i) {
        if (!ch[i].vertex || ch[i + 1].vertex || !ch[i + 2].vertex) continue;
        const int a = ch[i].node, d = ch[i + 2].node;
        const int x0 = ch[i + 1].a, y0 = ch[i + 1].b;
        const std::uint64_t key = edgeKey(x0, y0);
        if (std::find(tried.begin(), tried.end(), key) != tried.end()) continue;
        tried.push_back(key);
        int tt[2];
        if (w.edgeTris(x0, y0, tt) != 2) continue;
        // t1 = (a, x, y) counter-clockwise, t2 = (d, y, x).
        int t1 = -1, t2 = -1;
        for (int k = 0; k < 2; ++k) {
          const auto& v = w.tris[tt[k]].v;
          if (v[0] == a || v[1] == a || v[2] == a) t1 = tt[k];
          if (v[0] == d || v[1] == d || v[2] == d) t2 = tt[k];
        }
        if (t1 < 0 || t2 < 0 || t1 == t2) continue;
        auto v = w.tris[t1].v;
        while (v[0] != a) std::rotate(v.begin(), v.begin() + 1, v.end());
        const int x = v[1], y = v[2];
        const Vec2 &pa = w.nodes[a].p, &px = w.nodes[x].p, &py = w.nodes[y].p, &pd = w.nodes[d].p;
        if (std::min(triQuality(pa, px, pd), triQuality(pa, pd, py)) < minQuality) continue;
        const int mat1 = w.tris[t1].material, mat2 = w.tris[t2].material;
        w.killTri(t1);
        w.killTri(t2);
        w.addTri(a, x, d, mat1);
        w.addTri(a, d, y, mat2);
        ++flips;
        flipped = true;
      }
      if (flipped) break;
    }
    if (!flipped) break;
  }
  return flips;
}

// Step 4: subdivides every crossed edge of the chains; returns the chains as node lists.
Chains subdivide(Work& w, const std::vector<std::vector<Event>>& chains, Cut2DReport& report) {
  std::unordered_map<std::uint64_t, int> splitNode;  // edge -> new node
  Chains out;
  for (const auto& ch : chains) {
    std::vector<int> nodes;
    for (const auto& e : ch) {
      if (e.vertex) {
        nodes.push_back(e.node);
        continue;
      }
      const std::uint64_t key = edgeKey(e.a, e.b);
      auto it = splitNode.find(key);
      int id;
      if (it != splitNode.end()) {
        id = it->second;
      } else {
        id = w.addNode(e.p);
        auto& nn = w.nodes[id];
        // Parents as old indices where the parents are old nodes (always the case: the
        // edges split here join nodes that existed before this cut).
        nn.num_parents = 2;
        nn.parents = {w.nodes[e.a].old, w.nodes[e.b].old, -1};
        nn.weights = {1 - e.t, e.t, 0};
        splitNode.emplace(key, id);
        ++report.subdivided_edges;
      }
      nodes.push_back(id);
    }
    out.push_back(nodes);
  }
  if (splitNode.empty()) return out;
  // Re-triangulate every triangle with split edges.
  const int ntris = static_cast<int>(w.tris.size());
  for (int t = 0; t < ntris; ++t) {
    if (!w.tris[t].alive) continue;
    const auto v = w.tris[t].v;
    int p[3];  // split node on the edge opposite v[k], or -1
    int count = 0;
    for (int k = 0; k < 3; ++k) {
      auto it = splitNode.find(edgeKey(v[(k + 1) % 3], v[(k + 2) % 3]));
      p[k] = it == splitNode.end() ? -1 : it->second;
      count += p[k] >= 0;
    }
    if (count == 0) continue;
    const int mat = w.tris[t].material;
    w.killTri(t);
    auto P = [&](int n) -> const Vec2& { return w.nodes[n].p; };
    if (count == 1) {
      int k = 0;
      while (p[k] < 0) ++k;
      const int o = v[k], u = v[(k + 1) % 3], x = v[(k + 2) % 3];
      w.addTri(o, u, p[k], mat);
      w.addTri(o, p[k], x, mat);
    } else if (count == 2) {
      int i = 0;
      while (p[i] >= 0) ++i;  // the unsplit edge is opposite v[i]
      const int a = v[i], b = v[(i + 1) % 3], c = v[(i + 2) % 3];
      const int pc = p[(i + 1) % 3];  // on edge (c, a)
      const int pb = p[(i + 2) % 3];  // on edge (a, b)
      w.addTri(a, pb, pc, mat);
      // Quad (pb, b, c, pc): the diagonal giving the better worst element.
      const double q1 = std::min(triQuality(P(pb), P(b), P(c)), triQuality(P(pb), P(c), P(pc)));
      const double q2 = std::min(triQuality(P(pb), P(b), P(pc)), triQuality(P(b), P(c), P(pc)));
      if (q1 >= q2) {
        w.addTri(pb, b, c, mat);
        w.addTri(pb, c, pc, mat);
      } else {
        w.addTri(pb, b, pc, mat);
        w.addTri(b, c, pc, mat);
      }
    } else {
      const int a = v[0], b = v[1], c = v[2];
      w.addTri(a, p[2], p[1], mat);
      w.addTri(b, p[0], p[2], mat);
      w.addTri(c, p[1], p[0], mat);
      w.addTri(p[0], p[1], p[2], mat);
    }
  }
  return out;
}

// Step 6: duplicates the nodes of the cut so the sides share no edge. Around each node on
// the cut, triangles joined across non-cut edges form fans; every fan but the first gets
// its own copy of the node.
void separate(Work& w, const Chains& chains, Cut2DReport& report) {
  std::unordered_map<std::uint64_t, char> cutEdge;
  std::vector<int> cutNodes;
  for (const auto& ch : chains)
    for (std::size_t i = 0; i + 1 < ch.size(); ++i) {
      int tt[2];
      if (w.edgeTris(ch[i], ch[i + 1], tt) == 0) continue;  // not an edge: cannot separate here
      cutEdge[edgeKey(ch[i], ch[i + 1])] = 1;
      cutNodes.push_back(ch[i]);
      cutNodes.push_back(ch[i + 1]);
    }
  std::sort(cutNodes.begin(), cutNodes.end());
  cutNodes.erase(std::unique(cutNodes.begin(), cutNodes.end()), cutNodes.end());
  for (int n : cutNodes) {
    const std::vector<int> fan = w.nodeTris[n];
    const int m = static_cast<int>(fan.size());
    std::vector<int> comp(m);
    std::iota(comp.begin(), comp.end(), 0);
    auto find = [&](int i) {
      while (comp[i] != i) i = comp[i] = comp[comp[i]];
      return i;
    };
    for (int i = 0; i < m; ++i)
      for (int j = i + 1; j < m; ++j) {
        // shared edge (n, x) not on the cut?
        for (int k = 0; k < 3; ++k) {
          const int x = w.tris[fan[i]].v[k];
          if (x == n) continue;
          const auto& vj = w.tris[fan[j]].v;
          if ((vj[0] == x || vj[1] == x || vj[2] == x) && !cutEdge.count(edgeKey(n, x))) comp[find(i)] = find(j);
        }
      }
    std::vector<int> roots;
    for (int i = 0; i < m; ++i) {
      const int r = find(i);
      if (std::find(roots.begin(), roots.end(), r) == roots.end()) roots.push_back(r);
    }
    for (std::size_t r = 1; r < roots.size(); ++r) {
      const int copy = w.addNode(w.nodes[n].p);
      auto& cn = w.nodes[copy];
      const auto& src = w.nodes[n];
      if (src.old >= 0) {
        cn.num_parents = 1;
        cn.parents = {src.old, -1, -1};
        cn.weights = {1, 0, 0};
      } else {
        cn.num_parents = src.num_parents;
        cn.parents = src.parents;
        cn.weights = src.weights;
      }
      cn.duplicate = true;
      ++report.duplicated_nodes;
      for (int i = 0; i < m; ++i) {
        if (find(i) != roots[r]) continue;
        const int t = fan[i];
        for (int k = 0; k < 3; ++k)
          if (w.tris[t].v[k] == n) w.tris[t].v[k] = copy;
        // The element keeps its identity: only a node reference changed.
        auto& l = w.nodeTris[n];
        l.erase(std::find(l.begin(), l.end(), t));
        w.nodeTris[copy].push_back(t);
      }
    }
  }
}

// Step "delete": removes every element the cut passes through.
void deleteCrossed(Work& w, const std::vector<std::vector<Event>>& chains, Cut2DReport& report) {
  std::vector<int> ta, tb, victims;
  for (const auto& ch : chains)
    for (std::size_t i = 0; i + 1 < ch.size(); ++i) {
      eventTris(w, ch[i], ta);
      eventTris(w, ch[i + 1], tb);
      if (ch[i].vertex && ch[i + 1].vertex) continue;  // along an existing edge: nothing crossed
      for (int x : ta)
        for (int y : tb)
          if (x == y) victims.push_back(x);
    }
  std::sort(victims.begin(), victims.end());
  victims.erase(std::unique(victims.begin(), victims.end()), victims.end());
  for (int t : victims) w.killTri(t);
  report.deleted_elements = static_cast<int>(victims.size());
}

Result<Cut2DResult> finish(const TriMesh& in, Work& w, const Chains& chains) {
  Cut2DResult out;
  TopologyChange& tc = out.change;
  tc.old_num_nodes = in.numNodes();
  tc.old_num_elements = in.numTris();
  // Nodes: alive and used (or unused old nodes of the input, which stay).
  std::vector<int> nodeNew(w.nodes.size(), -1);
  int nn = 0;
  for (int i = 0; i < static_cast<int>(w.nodes.size()); ++i) {
    if (w.nodes[i].alive && !w.nodeTris[i].empty()) nodeNew[i] = nn++;
  }
  // Keep input nodes that were unused in the input too (they are not ours to drop).
  std::vector<char> usedIn(in.numNodes(), 0);
  for (int f = 0; f < in.numTris(); ++f)
    for (int k = 0; k < 3; ++k) usedIn[in.F(f, k)] = 1;
  for (int i = 0; i < in.numNodes(); ++i)
    if (!usedIn[i] && nodeNew[i] < 0 && w.nodes[i].alive) nodeNew[i] = nn++;
  out.mesh.X.setZero(nn, 3);
  for (int i = 0; i < static_cast<int>(w.nodes.size()); ++i)
    if (nodeNew[i] >= 0) {
      out.mesh.X(nodeNew[i], 0) = w.nodes[i].p.x();
      out.mesh.X(nodeNew[i], 1) = w.nodes[i].p.y();
    }
  tc.node_old_to_new.assign(in.numNodes(), -1);
  for (int i = 0; i < in.numNodes(); ++i) {
    int j = i;
    while (j >= 0 && !w.nodes[j].alive) j = w.nodes[j].merged_into;
    tc.node_old_to_new[i] = j >= 0 ? nodeNew[j] : -1;
    if (nodeNew[i] >= 0 && (w.nodes[i].p.x() != in.X(i, 0) || w.nodes[i].p.y() != in.X(i, 1)))
      tc.moved_nodes.push_back(nodeNew[i]);
  }
  for (int i = in.numNodes(); i < static_cast<int>(w.nodes.size()); ++i) {
    if (nodeNew[i] < 0) continue;
    NewNode n;
    n.id = nodeNew[i];
    n.num_parents = w.nodes[i].num_parents;
    n.parents = w.nodes[i].parents;
    n.weights = w.nodes[i].weights;
    n.duplicate = w.nodes[i].duplicate;
    tc.new_nodes.push_back(n);
  }
  std::sort(tc.new_nodes.begin(), tc.new_nodes.end(), [](const NewNode& a, const NewNode& b) { return a.id < b.id; });
  std::sort(tc.moved_nodes.begin(), tc.moved_nodes.end());
  // Elements: survivors of the input first (in input order), then new ones.
  int nf = 0;
  for (const auto& t : w.tris) nf += t.alive;
  out.mesh.F.resize(nf, 3);
  out.mesh.material.resize(nf);
  tc.element_old_to_new.assign(in.numTris(), -1);
  int f = 0;
  for (const auto& t : w.tris) {
    if (!t.alive) continue;
    for (int k = 0; k < 3; ++k) out.mesh.F(f, k) = nodeNew[t.v[k]];
    out.mesh.material(f) = t.material;
    if (t.old >= 0) tc.element_old_to_new[t.old] = f;
    else tc.added_elements.push_back(f);
    ++f;
  }
  for (int i = 0; i < in.numTris(); ++i)
    if (tc.element_old_to_new[i] < 0) tc.removed_elements.push_back(i);
  {
    // Cut nodes and edges, each side: after separation an edge of the cut exists once per
    // side with different copies of its nodes; copies share their source's position, so
    // each node is mapped back to its chain node by exact position.
    std::unordered_map<std::uint64_t, char> chainEdge;
    std::map<std::pair<double, double>, int> byPos;
    auto posKey = [](const Vec2& p) { return std::pair<double, double>(p.x(), p.y()); };
    for (const auto& ch : chains)
      for (int n : ch) byPos[posKey(w.nodes[n].p)] = n;
    for (const auto& ch : chains)
      for (std::size_t i = 0; i + 1 < ch.size(); ++i) chainEdge[edgeKey(ch[i], ch[i + 1])] = 1;
    auto source = [&](int n) {
      auto it = byPos.find(posKey(w.nodes[n].p));
      return it == byPos.end() ? -1 : it->second;
    };
    std::vector<char> isCut(nn, 0);
    for (const auto& t : w.tris) {
      if (!t.alive) continue;
      for (int k = 0; k < 3; ++k) {
        const int a = t.v[k], b = t.v[(k + 1) % 3];
        const int sa = source(a), sb = source(b);
        if (sa < 0 || sb < 0 || !chainEdge.count(edgeKey(sa, sb))) continue;
        tc.cut_edges.push_back({nodeNew[a], nodeNew[b]});
        isCut[nodeNew[a]] = isCut[nodeNew[b]] = 1;
      }
    }
    for (int i = 0; i < nn; ++i)
      if (isCut[i]) tc.cut_nodes.push_back(i);
  }
  tc.new_num_nodes = nn;
  tc.new_num_elements = nf;
  return out;
}

}  // namespace

Result<Cut2DResult> cut2d(const TriMesh& mesh, const std::vector<Eigen::Vector2d>& polyline,
                          const Cut2DOptions& options) {
  const auto t0 = Clock::now();
  if (polyline.size() < 2) return Error{"cut2d: the cut needs at least two points"};
  for (const auto& p : polyline)
    if (!p.allFinite()) return Error{"cut2d: non-finite cut point"};
  if (!mesh.isPlanar()) return Error{"cut2d: the mesh is not planar (z != 0)"};
  if (Status st = validate(mesh); !st.ok()) return Error{"cut2d: invalid input mesh: " + st.error()};

  Work w;
  w.nodes.resize(mesh.numNodes());
  for (int i = 0; i < mesh.numNodes(); ++i) {
    w.nodes[i].p = Vec2(mesh.X(i, 0), mesh.X(i, 1));
    w.nodes[i].old = i;
  }
  w.tris.resize(mesh.numTris());
  for (int f = 0; f < mesh.numTris(); ++f) {
    w.tris[f].v = {mesh.F(f, 0), mesh.F(f, 1), mesh.F(f, 2)};
    w.tris[f].old = f;
    w.tris[f].material = mesh.material.size() == mesh.F.rows() ? mesh.material(f) : 0;
  }
  w.rebuildNodeTris();

  // Mean edge length sets the tolerances.
  double meanEdge = 0;
  {
    const auto edges = allEdges(w);
    for (const auto& e : edges) meanEdge += (w.nodes[e[0]].p - w.nodes[e[1]].p).norm();
    meanEdge = edges.empty() ? 1.0 : meanEdge / static_cast<double>(edges.size());
  }
  const double eps = 1e-9 * meanEdge;
  Polyline pl{polyline};
  int usedNodes = 0;  // the node budget of the optimisation
  for (const auto& l : w.nodeTris) usedNodes += !l.empty();

  Cut2DResult result;
  Cut2DReport& rep = result.report;
  auto chains = eventChains(w, computeEvents(w, pl, eps));
  for (const auto& ch : chains)
    for (const auto& e : ch) rep.crossed_edges += !e.vertex;

  Chains nodeChains;
  if (options.method == CutMethod::Delete) {
    deleteCrossed(w, chains, rep);
  } else {
    if (options.method == CutMethod::Hybrid || options.method == CutMethod::Snap) {
      const bool hybrid = options.method == CutMethod::Hybrid;
      const BorderInfo bi = borderInfo(w, options.feature_angle_deg);
      if (hybrid && bendToCorners(w, pl, chains, bi, options.corner_region, meanEdge))
        chains = eventChains(w, computeEvents(w, pl, eps));
      // Snapping only: every crossing displaces its nearer node; only folding or
      // flattening (q < 0.01) refuses.
      displaceNodes(w, pl, chains, hybrid ? options.snap_region : 0.5001, hybrid ? options.min_quality : 0.01, bi,
                    rep);
      if (hybrid && options.edge_flips) rep.edge_flips = flipConsecutiveType2(w, pl, eps, options.min_quality);
      chains = eventChains(w, computeEvents(w, pl, eps));
    }
    nodeChains = subdivide(w, chains, rep);
    rep.cut_ms = msSince(t0);
    if (options.method == CutMethod::Hybrid && options.optimize.enabled) {
      const auto t1 = Clock::now();
      detail::optimizeAfterCut(w, nodeChains, meanEdge, options.optimize.keep_node_count ? usedNodes : -1, options, rep);
      rep.optimize_ms = msSince(t1);
    }
    if (options.separate) separate(w, nodeChains, rep);
  }
  if (options.method == CutMethod::Delete) rep.cut_ms = msSince(t0);
  auto out = finish(mesh, w, nodeChains);
  if (!out.ok()) return out;
  out->report = rep;
  return out;
}

Result<Cut2DResult> cut2d(const TriMesh& mesh, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                          const Cut2DOptions& options) {
  return cut2d(mesh, std::vector<Eigen::Vector2d>{a, b}, options);
}

int countDistinctPositions(const TriMesh& mesh) {
  std::vector<char> used(mesh.numNodes(), 0);
  for (int f = 0; f < mesh.numTris(); ++f)
    for (int k = 0; k < 3; ++k) used[mesh.F(f, k)] = 1;
  std::vector<std::array<double, 3>> pos;
  for (int i = 0; i < mesh.numNodes(); ++i)
    if (used[i]) pos.push_back({mesh.X(i, 0), mesh.X(i, 1), mesh.X(i, 2)});
  std::sort(pos.begin(), pos.end());
  return static_cast<int>(std::unique(pos.begin(), pos.end()) - pos.begin());
}

Eigen::VectorXi elementComponents(const TriMesh& mesh, int* count) {
  const int nf = mesh.numTris();
  std::vector<int> parent(nf);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  std::unordered_map<std::uint64_t, int> firstTri;
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const auto key = edgeKey(mesh.F(f, k), mesh.F(f, (k + 1) % 3));
      auto [it, inserted] = firstTri.emplace(key, f);
      if (!inserted) parent[find(f)] = find(it->second);
    }
  Eigen::VectorXi label(nf);
  std::unordered_map<int, int> ids;
  for (int f = 0; f < nf; ++f) {
    const int r = find(f);
    auto [it, inserted] = ids.emplace(r, static_cast<int>(ids.size()));
    label(f) = it->second;
  }
  if (count) *count = static_cast<int>(ids.size());
  return label;
}

double totalArea(const TriMesh& mesh) {
  double a = 0;
  for (int f = 0; f < mesh.numTris(); ++f) a += triArea(mesh, f);
  return a;
}

}  // namespace hysim::cutting
