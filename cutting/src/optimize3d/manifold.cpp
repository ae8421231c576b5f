// Manifold checks: how many boundary faces a tet has, and whether the tets around a node
// form a disc (each face used by at most two tets, the boundary around it one closed loop).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

#include "cut_optimizer.hpp"
#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::cutting::opt3d {

// The faces of t no other live tet has. Face f is shared when a live tet u != t around its
// first node holds its other two (a live tet's nodes are distinct, so the two positions of u
// equal to one of them are one each). Faces 1 to 3 start with t's node 0 and face 0 with its
// node 1: one pass over each of those two stars, with per tet the mask of t's nodes it holds.
int CutOptimizer::boundaryFaceCount(int t) const {
  const int t0 = mesh.T(t, 0), t1 = mesh.T(t, 1), t2 = mesh.T(t, 2), t3 = mesh.T(t, 3);
  auto holds = [&](int u) {
    const int w0 = mesh.T(u, 0), w1 = mesh.T(u, 1), w2 = mesh.T(u, 2), w3 = mesh.T(u, 3);
    return unsigned(w0 == t1 || w1 == t1 || w2 == t1 || w3 == t1) << 1 |
           unsigned(w0 == t2 || w1 == t2 || w2 == t2 || w3 == t2) << 2 |
           unsigned(w0 == t3 || w1 == t3 || w2 == t3 || w3 == t3) << 3;
  };
  unsigned shared = 0;  // bit f: face f is shared
  for (const std::int32_t *s = ed.starBegin(t0), *sEnd = ed.starEnd(t0); s < sEnd && shared != 0xEu; ++s) {
    const int u = (*s);
    if (u == t || dead[u]) continue;
    const unsigned h = holds(u);  // (bit 0 unused: u holds t's node 0)
    for (int f = 1; f < 4; ++f) {
      const unsigned S = 0xEu & ~(1u << f);
      if ((h & S) == S) shared |= 1u << f;
    }
  }
  for (const std::int32_t *s = ed.starBegin(t1), *sEnd = ed.starEnd(t1); s < sEnd; ++s) {
    const int u = (*s);
    if (u == t || dead[u]) continue;
    if ((holds(u) & 0xCu) == 0xCu) {
      shared |= 1u;
      break;
    }
  }
  constexpr int kUnshared[16] = {4, 3, 3, 2, 3, 2, 2, 1, 3, 2, 2, 1, 2, 1, 1, 0};  // 4 - popcount
  const int count = kUnshared[shared];
#ifdef HYSIM_CHECK_EXACT
  int ref = 0;
  for (int f = 0; f < 4; ++f) {
    const int a = mesh.T(t, kFace[f][0]), b = mesh.T(t, kFace[f][1]), c = mesh.T(t, kFace[f][2]);
    bool sh = false;
    for (const std::int32_t *s = ed.starBegin(a), *sEnd = ed.starEnd(a); s < sEnd && !sh; ++s) {
      const int u = (*s);
      if (u == t || dead[u]) continue;
      int hits = 0;
      for (int k = 0; k < 4; ++k) hits += mesh.T(u, k) == b || mesh.T(u, k) == c;
      sh = hits == 2;
    }
    ref += sh ? 0 : 1;
  }
  if (ref != count) std::abort();
#endif
  return count;
}

// Is the neighbourhood of v (tets `around`) manifold: every face used by at most two tets,
// and the boundary faces around v one closed loop (or none: interior)? No tets: the node
// goes away (compacted), which is fine.
// linkOnly: only fill `link` (the boundary edges around v, up to the first face used by
// more than two tets) and return whether the faces are; the loop check is skipped.
// (Scratch that only grows, so that it is written without zeroing: tetLocal, faceKey,
// linkInc and discNbrs, v's neighbours in local number order.)
bool CutOptimizer::discAround(int v, const std::vector<std::int32_t>& around, bool linkOnly) {
  link.clear();
  if (around.empty()) return true;
  // Every tet of `around` has v; a face (v, a, b) is used by the tets with both a and b:
  // count the pairs of each tet's other three nodes in a table over v's neighbours.
  // Each tet's three other nodes as local numbers (in the tet's order), read from the mesh
  // once.
  const size_t n = around.size();
  if (tetLocal.size() < 3 * n + 1) tetLocal.resize(3 * n + 1);  // (+1: a tet without v writes a fourth number)
  if (discNbrs.size() < 4 * n) discNbrs.resize(4 * n);
  std::int32_t* nb = discNbrs.data();
  std::int32_t L = 0;     // neighbours numbered so far
  bool threeEach = true;  // (every tet has v once: its three other nodes)
  for (size_t i = 0; i < n; ++i) {
    const int t = around[i];
    std::int32_t* o = &tetLocal[3 * i];
    int m = 0;
    for (int k = 0; k < 4; ++k) {
      const int w = mesh.T(t, k);
      if (w == v) continue;
      std::int32_t& id = cons.localId[w];
      if (id < 0) {
        id = L;
        nb[L++] = w;
      }
      o[m++] = id;
    }
    threeEach = threeEach && m == 3;
  }
  if (!threeEach) {  // not a star of v (never so here)
    for (std::int32_t i = 0; i < L; ++i) cons.localId[nb[i]] = -1;
    return false;
  }
  // The faces at v of each tet, in the order of the face opposite each other node (faces
  // f != v's in order f = 0..3: without o[0], without o[1], without o[2]): the pairs
  // (o1, o2), (o0, o2), (o0, o1), each as its table index min * L + max.
  faceUses.assign(static_cast<size_t>(L) * L, 0);
  if (faceKey.size() < 3 * n) faceKey.resize(3 * n);
  for (size_t i = 0; i < n; ++i) {
    const std::int32_t* o = &tetLocal[3 * i];
    std::int32_t* key = &faceKey[3 * i];
    const std::int32_t a = o[0], b = o[1], c = o[2];
    key[0] = std::min(b, c) * L + std::max(b, c);
    key[1] = std::min(a, c) * L + std::max(a, c);
    key[2] = std::min(a, b) * L + std::max(a, b);
    ++faceUses[key[0]];
    ++faceUses[key[1]];
    ++faceUses[key[2]];
  }
  // The boundary faces' edges, up to the first face used by more than two tets.
  bool manifold = true;
  for (size_t i = 0; i < n && manifold; ++i) {
    const std::int32_t* o = &tetLocal[3 * i];
    const std::int32_t* key = &faceKey[3 * i];
    for (int f = 0; f < 3; ++f) {
      const std::uint16_t uses = faceUses[key[f]];
      if (uses > 2) {
        manifold = false;
        break;
      }
      if (uses == 1) {
        const std::int32_t p = f == 0 ? o[1] : o[0], q = f == 2 ? o[1] : o[2];
        link.push_back(p);
        link.push_back(q);
      }
    }
  }
  for (std::int32_t i = 0; i < L; ++i) cons.localId[nb[i]] = -1;
  if (!manifold || link.empty() || linkOnly) return manifold;  // (link.empty(): an interior node)
  return linkIsOneLoop(L);
}

// Every link vertex has degree 2, and walking from one edge visits all: one closed loop. Each
// link vertex's (first two) edges in a table over v's L neighbours: with all degrees 2 the
// walk from edge 0 leaves each vertex by its other edge, and it visits all edges iff they
// form one loop.
bool CutOptimizer::linkIsOneLoop(std::int32_t L) {
  const size_t edges = link.size() / 2;
  linkDeg.assign(L, 0);
  if (linkInc.size() < 2 * static_cast<size_t>(L)) linkInc.resize(2 * static_cast<size_t>(L));
  for (size_t i = 0; i < link.size(); ++i) {
    const std::int32_t id = link[i];
    if (linkDeg[id] < 2) linkInc[2 * id + linkDeg[id]] = static_cast<std::int32_t>(i / 2);
    ++linkDeg[id];
  }
  bool loop = true;
  for (size_t i = 0; i < link.size() && loop; ++i) loop = linkDeg[link[i]] == 2;
  size_t visited = 1;
  std::int32_t start = link[0], at = link[1];
  std::int32_t prevEdge = 0;
  while (loop && at != start && visited <= edges) {
    const std::int32_t next = linkInc[2 * at] != prevEdge ? linkInc[2 * at] : linkInc[2 * at + 1];
    at = link[2 * next] == at ? link[2 * next + 1] : link[2 * next];
    prevEdge = next;
    ++visited;
  }
  return loop && at == start && visited == edges;
}

}  // namespace hysim::cutting::opt3d
