#pragma once
// Working mesh shared by the 2D cut stages (cut2d.cpp) and the mesh optimisation
// (optimize2d.cpp). Not installed; not part of the public interface.
#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "hysim/cutting/cut2d.hpp"

namespace hysim::cutting::detail {

using Vec2 = Eigen::Vector2d;

struct WNode {
  Vec2 p;
  int old = -1;                       // old node index, -1 for a node made by this cut
  int num_parents = 0;                // new nodes: parents (old indices) and weights
  std::array<int, 3> parents{-1, -1, -1};
  std::array<double, 3> weights{0, 0, 0};
  bool duplicate = false;
  bool alive = true;
  int merged_into = -1;               // edge collapse: the node this one was merged into
};

struct WTri {
  std::array<int, 3> v;
  int old = -1;                       // old element index while unchanged, else -1
  int material = 0;
  bool alive = true;
};

inline double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }
inline double orient(const Vec2& a, const Vec2& b, const Vec2& c) { return cross2(b - a, c - a); }

// q = r_in / R_circ = 4 A^2 ... written as 16 A^2 / (s * l0 l1 l2) * ... ; see radiusRatio.
// Here: q = 4 * A * A_ / ... computed from the side lengths; negative when folded.
inline double triQuality(const Vec2& a, const Vec2& b, const Vec2& c) {
  const double area2 = orient(a, b, c);  // twice the signed area
  const double l0 = (b - c).norm(), l1 = (c - a).norm(), l2 = (a - b).norm();
  const double denom = (l0 + l1 + l2) * l0 * l1 * l2;
  if (denom <= 0) return 0.0;
  // r_in = 2A / perimeter, R = l0 l1 l2 / (4A): q = 8 A^2 / (perimeter * l0 l1 l2), A = area2/2
  const double q = 2.0 * area2 * area2 / denom;
  return area2 > 0 ? q : -q;
}

struct Work {
  std::vector<WNode> nodes;
  std::vector<WTri> tris;
  std::vector<std::vector<int>> nodeTris;  // alive triangles around each node

  int addNode(const Vec2& p) {
    WNode n;
    n.p = p;
    nodes.push_back(n);
    nodeTris.emplace_back();
    return static_cast<int>(nodes.size()) - 1;
  }
  int addTri(int a, int b, int c, int material) {
    WTri t;
    t.v = {a, b, c};
    t.material = material;
    tris.push_back(t);
    const int id = static_cast<int>(tris.size()) - 1;
    for (int k = 0; k < 3; ++k) nodeTris[t.v[k]].push_back(id);
    return id;
  }
  void killTri(int t) {
    tris[t].alive = false;
    for (int k = 0; k < 3; ++k) {
      auto& l = nodeTris[tris[t].v[k]];
      for (std::size_t i = 0; i < l.size(); ++i)
        if (l[i] == t) {
          l[i] = l.back();
          l.pop_back();
          break;
        }
    }
  }
  void rebuildNodeTris() {
    nodeTris.assign(nodes.size(), {});
    for (int t = 0; t < static_cast<int>(tris.size()); ++t)
      if (tris[t].alive)
        for (int k = 0; k < 3; ++k) nodeTris[tris[t].v[k]].push_back(t);
  }
  // Alive triangles containing edge (a, b) (at most 2 in a manifold mesh).
  int edgeTris(int a, int b, int out[2]) const {
    int n = 0;
    for (int t : nodeTris[a]) {
      const auto& v = tris[t].v;
      if (v[0] == b || v[1] == b || v[2] == b) {
        if (n < 2) out[n] = t;
        ++n;
      }
    }
    return n;
  }
  bool isBorderEdge(int a, int b) const {
    int t[2];
    return edgeTris(a, b, t) == 1;
  }
  bool isBorderNode(int a) const {
    for (int t : nodeTris[a]) {
      const auto& v = tris[t].v;
      for (int k = 0; k < 3; ++k)
        if (v[k] != a && isBorderEdge(a, v[k])) return true;
    }
    return false;
  }
  // Unique neighbours of a node.
  void neighbours(int a, std::vector<int>& out) const {
    out.clear();
    for (int t : nodeTris[a])
      for (int k = 0; k < 3; ++k) {
        const int w = tris[t].v[k];
        if (w == a) continue;
        bool seen = false;
        for (int x : out) seen = seen || x == w;
        if (!seen) out.push_back(w);
      }
  }
  // Smallest quality of the triangles around `a` if `a` were at `p` (negative: folded).
  double minQualityIfMoved(int a, const Vec2& p) const {
    double qmin = 1.0;
    for (int t : nodeTris[a]) {
      const auto& v = tris[t].v;
      Vec2 c[3];
      for (int k = 0; k < 3; ++k) c[k] = v[k] == a ? p : nodes[v[k]].p;
      qmin = std::min(qmin, triQuality(c[0], c[1], c[2]));
    }
    return qmin;
  }
  double minQualityAround(int a) const { return minQualityIfMoved(a, nodes[a].p); }
};

// The cut as ordered chains of nodes (each consecutive pair joined by a mesh edge).
using Chains = std::vector<std::vector<int>>;

// Mesh optimisation after the cut (optimize2d.cpp): edge collapse on the cut, equal node
// distribution along the cut, local mass-spring / particle regularisation. Chains are
// updated (collapsed nodes removed). `mean_edge` is the initial mesh's mean edge length;
// `target_nodes` the node count to come back to by collapses near the cut (-1: none).
void optimizeAfterCut(Work& w, Chains& chains, double mean_edge, int target_nodes, const Cut2DOptions& options,
                      Cut2DReport& report);

}  // namespace hysim::cutting::detail
