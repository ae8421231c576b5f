// Flap peeling after a curved cut (shaving): thin pieces of tissue near the cut whose tets
// are all poor (q* below flap_quality) and that touch the boundary are removed as a group.
//
// Why: a shaving sweep that meets an earlier cut surface, or the outer boundary, at a shallow
// angle leaves a wedge of tissue between the two surfaces that is much thinner than the local
// edge length: a fan of flat tets around a boundary node lying a few hundredths of a
// millimetre off the cut, or a knife edge (tets with two boundary faces meeting at a small
// dihedral angle). Their nodes are all held (on the cut, on the rim, on boundary features),
// and removing one tet at a time leaves a non-manifold node (the flap's tets hang together
// around it), so the single-tet peeling of optimize3d.cpp refuses each of them. Removing the
// whole flap keeps the mesh manifold, and it is what the loop electrode does physically:
// tissue this thin between the loop and the surface is vaporised.
//
// Rule: candidates are the live tets with q* below flap_quality that have a node within
// flap_rings edge steps of the seeds (what the cut touched, and every node on the cut).
// Candidates sharing faces form
// groups; a group without a boundary face (poor tets inside a wedge whose nodes are all on the
// boundary) first takes the layer of its face neighbours that have one and q* below
// quality_target, within flap_grow_factor x its own volume (repairs below included); a group
// with at least one boundary face is removed when
//  - its volume is at most flap_group_volume x a regular tet with the cut's local edge, and
//    all removed flaps of this cut together at most flap_pass_volume x that;
//  - every node of the group keeps a manifold star (its remaining tets connected through
//    faces, every face at most twice, the boundary around it one closed loop) or loses all
//    its tets. A node whose remaining star falls apart into pieces is repaired by removing
//    every piece but the largest (by volume) too, if the volume limits allow (at most
//    flap_max_tets tets in the group). A node whose star was already not a manifold one
//    before (earlier cuts pinched it) is accepted as long as it stays so (no worse); at a
//    node where the flap would open a hole through the surface (one piece, two boundary
//    loops) the hole is opened to the boundary along the shortest chain of tets around the
//    node (at most 4), or else the flap keeps its tets there unless the worst tet is among them;
//  - the group is no bridge between two large parts: the tets next to it stay connected
//    (the first walk into a large part stops at 256 tets, the others go on until they meet
//    an earlier walk); a closed piece of fewer than 256 tets that hung on the group only (a
//    chip the sweep almost cut off, held by a neck this thin) is freed, as the cut frees chips.
// Local: it works on the optimiser's node -> tet lists and touches only the tets around the seeds.
#include "flap_peel.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <numeric>
#include <vector>

#include "hysim/cutting/mesh_stats.hpp"
#include "hysim/cutting/tet_faces.hpp"

namespace hysim::cutting {
namespace {

using Vec3 = Eigen::Vector3d;
constexpr const auto& kFace = kTetFace;

int findRoot(std::vector<int>& parent, int a) {
  while (parent[a] != a) {
    parent[a] = parent[parent[a]];
    a = parent[a];
  }
  return a;
}

// Walks a star's link edges (a, b, index of the tet), sorted: two equal ones join their tets'
// pieces (union-find over `piece`), a single one is a boundary edge of the link (appended to
// `boundary`). False where an edge has more than two tets.
bool joinLinkEdges(const std::vector<std::array<std::int32_t, 3>>& pairs, std::vector<int>& piece,
                   std::vector<std::array<std::int32_t, 2>>& boundary) {
  for (size_t i = 0; i < pairs.size();) {
    size_t j = i;
    while (j < pairs.size() && pairs[j][0] == pairs[i][0] && pairs[j][1] == pairs[i][1]) ++j;
    if (j - i > 2) return false;
    if (j - i == 2) {
      piece[findRoot(piece, pairs[i][2])] = findRoot(piece, pairs[i + 1][2]);
    } else {
      boundary.push_back({pairs[i][0], pairs[i][1]});
    }
    i = j;
  }
  return true;
}

}  // namespace

StarShape starShape(const TetMesh& mesh, int v, const std::vector<std::int32_t>& around) {
  StarShape shape;
  const int S = static_cast<int>(around.size());
  if (S == 0) {
    shape.valid = true;
    return shape;
  }
  // Each tet's three edges opposite v (a, b: the face (v, a, b)), sorted: two equal ones
  // join their tets, a single one is a boundary edge of the link.
  std::vector<std::array<std::int32_t, 3>> pairs;  // (a, b, index in around), a < b
  pairs.reserve(3 * around.size());
  for (int i = 0; i < S; ++i) {
    std::int32_t o[3], m = 0;
    for (int k = 0; k < 4; ++k)
      if (mesh.T(around[i], k) != v && m < 3) o[m++] = mesh.T(around[i], k);
    if (m != 3) return shape;
    std::sort(o, o + 3);
    pairs.push_back({o[0], o[1], i});
    pairs.push_back({o[0], o[2], i});
    pairs.push_back({o[1], o[2], i});
  }
  std::sort(pairs.begin(), pairs.end());
  std::vector<int> piece(S);
  std::iota(piece.begin(), piece.end(), 0);
  std::vector<std::int32_t> ends;                  // boundary edges' end points, twice each
  std::vector<std::array<std::int32_t, 2>> edges;  // boundary edges of the link
  if (!joinLinkEdges(pairs, piece, edges)) return shape;
  for (const auto& e : edges) {
    ends.push_back(e[0]);
    ends.push_back(e[1]);
  }
  for (int i = 0; i < S; ++i) shape.pieces += findRoot(piece, i) == i;
  std::sort(ends.begin(), ends.end());
  for (size_t i = 0; i < ends.size();) {
    size_t j = i;
    while (j < ends.size() && ends[j] == ends[i]) ++j;
    if (j - i != 2) return shape;  // a pinched edge (v, w), or an open link
    i = j;
  }
  ends.erase(std::unique(ends.begin(), ends.end()), ends.end());
  std::vector<int> loop(ends.size());
  std::iota(loop.begin(), loop.end(), 0);
  auto local = [&](int n) {
    return static_cast<int>(std::lower_bound(ends.begin(), ends.end(), n) - ends.begin());
  };
  for (const auto& e : edges) loop[findRoot(loop, local(e[0]))] = findRoot(loop, local(e[1]));
  for (size_t i = 0; i < ends.size(); ++i) shape.loops += findRoot(loop, static_cast<int>(i)) == static_cast<int>(i);
  shape.valid = true;
  return shape;
}

namespace {

// Longest chain of tets around a node that opening a hole to the boundary may remove.
constexpr int kChain = 4;
// The first walk into a large part stops after this many tets.
constexpr int kCap = 256;

int sortedIndex(const std::vector<std::int32_t>& sorted, int n) {
  return static_cast<int>(std::lower_bound(sorted.begin(), sorted.end(), n) - sorted.begin());
}

// What changing a node's star did to the group (fixNonManifoldNode).
enum class NodeFix { kUnchanged, kGrew, kRefuse };

// The working state of one peelFlaps call: the candidates and their groups, and the scratch
// lists of the group being checked, kept as members so they are allocated once per call.
class FlapPeeler {
 public:
  FlapPeeler(const TetMesh& mesh, const NodeStars& stars, const Optimize3DOptions& options,
             std::vector<std::uint8_t>& gone, const std::function<double(int)>* quality, double groupLimit,
             double passLeft)
      : mesh(mesh), stars(stars), options(options), gone(gone), quality(quality), M(mesh.numTets()),
        groupLimit(groupLimit), passLeft(passLeft) {}

  void collectNearNodes(const CutRegion& region, const std::vector<std::int32_t>& seeds);
  bool collectCandidates();
  void orderGroups();
  void peelGroups();
  void addCounts(OptimizeCounts* counts) const;

 private:
  Vec3 pos(int n) const { return Vec3(mesh.X.row(n).transpose()); }
  double volume(int t) const {
    const Vec3 a = pos(mesh.T(t, 0));
    return (pos(mesh.T(t, 1)) - a).dot((pos(mesh.T(t, 2)) - a).cross(pos(mesh.T(t, 3)) - a)) / 6.0;
  }
  bool has(int t, int n) const {
    return mesh.T(t, 0) == n || mesh.T(t, 1) == n || mesh.T(t, 2) == n || mesh.T(t, 3) == n;
  }
  double tetQuality(int t) const {
    return quality ? (*quality)(t)
                   : radiusRatio(pos(mesh.T(t, 0)), pos(mesh.T(t, 1)), pos(mesh.T(t, 2)), pos(mesh.T(t, 3)));
  }
  int candIndex(int t) const {
    const auto it = std::lower_bound(cands.begin(), cands.end(), t);
    return it != cands.end() && *it == t ? static_cast<int>(it - cands.begin()) : -1;
  }
  bool inGroup(int t) const { return std::find(group.begin(), group.end(), t) != group.end(); }
  int aroundIndex(int t) const {
    return static_cast<int>(std::find(around.begin(), around.end(), t) - around.begin());
  }
  void takeTet(int t) {
    group.push_back(t);
    vol += volume(t);
    gone[t] = 1;
  }
  int across(int t, int f) const;
  int acrossWithGroup(int t, int f) const;
  void liveStar(int v);
  int pieces(int v);
  int checkLink(const std::vector<std::array<std::int32_t, 2>>& boundary, int count);
  void startChains(int v);
  bool openHoleToBoundary(int v);
  bool gatherGroup(int root, double* grownLimit);
  bool growWedge(double* grownLimit);
  int worstTetOfGroup() const;
  void collectGroupNodes();
  void splitPinchedEdges();
  NodeFix fixNonManifoldNode(int v, int worstTet);
  void removeSmallerPieces();
  bool repairStars(double grownLimit, int worstTet);
  bool walkFrom(size_t r, int big);
  bool noBridge();

  const TetMesh& mesh;
  const NodeStars& stars;
  const Optimize3DOptions& options;
  std::vector<std::uint8_t>& gone;
  const std::function<double(int)>* quality;
  const int M;
  const double groupLimit;
  double passLeft;

  std::vector<std::int32_t> nearNodes, cands;
  std::vector<double> candQ;
  std::vector<int> parent;
  std::vector<std::pair<double, int>> order;  // (worst q* of the group, root)
  // pieces(): the live star of a node and its pieces.
  std::vector<std::int32_t> around;
  std::vector<int> pieceOf, linkParent;
  std::vector<std::array<std::int32_t, 3>> pairs;  // (a, b, index in around), a < b
  std::vector<std::int32_t> linkNodes, pinched;
  // The group being checked.
  std::vector<std::int32_t> group, groupNodes, rim, restored;
  double vol = 0;  // of the group
  std::vector<int> chainFrom, chainDepth, chainQueue;
  std::vector<double> pieceVolume;
  std::vector<std::int32_t> fanTets, walked, allWalked;
  std::vector<int> mark;  // #T walk marks, allocated when first needed
  std::vector<int> fanParent;
  int peeled = 0;
  double peeledVolume = 0;
};

// The live tet other than t across face f of t, or -1 (a boundary face).
int FlapPeeler::across(int t, int f) const {
  const int a = mesh.T(t, kFace[f][0]), b = mesh.T(t, kFace[f][1]), c = mesh.T(t, kFace[f][2]);
  for (const std::int32_t *s = stars.begin(a), *sEnd = stars.end(a); s < sEnd; ++s) {
    const int u = *s;
    if (u != t && !gone[u] && has(u, b) && has(u, c)) return u;
  }
  return -1;
}

// The tet across face f of t among the live tets and the group's, or -1.
int FlapPeeler::acrossWithGroup(int t, int f) const {
  const int a = mesh.T(t, kFace[f][0]), b = mesh.T(t, kFace[f][1]), c = mesh.T(t, kFace[f][2]);
  for (const std::int32_t *s = stars.begin(a), *sEnd = stars.end(a); s < sEnd; ++s) {
    const int u = *s;
    if (u != t && (!gone[u] || inGroup(u)) && has(u, b) && has(u, c)) return u;
  }
  return -1;
}

// Nodes within flap_rings edge steps of the seeds.
void FlapPeeler::collectNearNodes(const CutRegion& region, const std::vector<std::int32_t>& seeds) {
  const int N = mesh.numNodes();
  std::vector<std::int8_t> ring(N, -1);
  std::vector<std::int32_t> frontier, next;
  for (int n : seeds)
    if (n >= 0 && n < N && ring[n] < 0) {
      ring[n] = 0;
      frontier.push_back(n);
      nearNodes.push_back(n);
    }
  // Nodes on the cut that the cut did not touch (it passed within eps of them) are seeds too.
  for (int n = 0; n < N && n < static_cast<int>(region.on_cut.size()); ++n)
    if (region.on_cut[n] && ring[n] < 0 && stars.end(n) > stars.begin(n)) {
      ring[n] = 0;
      frontier.push_back(n);
      nearNodes.push_back(n);
    }
  for (int r = 1; r <= options.flap_rings && !frontier.empty(); ++r) {
    next.clear();
    for (int n : frontier)
      for (const std::int32_t *s = stars.begin(n), *sEnd = stars.end(n); s < sEnd; ++s)
        for (int k = 0; k < 4; ++k) {
          const int v = mesh.T(*s, k);
          if (ring[v] < 0) {
            ring[v] = static_cast<std::int8_t>(r);
            next.push_back(v);
            nearNodes.push_back(v);
          }
        }
    frontier.swap(next);
  }
}

// Candidates: poor live tets around the near nodes, each once; false if there are none.
bool FlapPeeler::collectCandidates() {
  // (The tets of the near nodes' lists, each once, in index order.)
  {
    IndexBits bits(M);
    for (int n : nearNodes)
      for (const std::int32_t *s = stars.begin(n), *sEnd = stars.end(n); s < sEnd; ++s) bits.mark(*s);
    bits.drainInto(cands);
  }
  size_t kept = 0;
  for (int t : cands) {
    const double q = tetQuality(t);
    if (q < options.flap_quality) {
      cands[kept++] = t;
      candQ.push_back(q);
    }
  }
  cands.resize(kept);
  return !cands.empty();
}

// Groups: candidates connected through shared faces; the worst first.
void FlapPeeler::orderGroups() {
  parent.resize(cands.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (size_t i = 0; i < cands.size(); ++i)
    for (int f = 0; f < 4; ++f) {
      const int u = across(cands[i], f);
      const int j = u >= 0 ? candIndex(u) : -1;
      if (j >= 0) parent[findRoot(parent, static_cast<int>(i))] = findRoot(parent, j);
    }
  std::vector<double> worst(cands.size(), 1.0);
  for (size_t i = 0; i < cands.size(); ++i) {
    const int r = findRoot(parent, static_cast<int>(i));
    worst[r] = std::min(worst[r], candQ[i]);
  }
  for (size_t i = 0; i < cands.size(); ++i)
    if (findRoot(parent, static_cast<int>(i)) == static_cast<int>(i)) order.emplace_back(worst[i], static_cast<int>(i));
  std::sort(order.begin(), order.end());
}

// The live tets around v.
void FlapPeeler::liveStar(int v) {
  around.clear();
  for (const std::int32_t *s = stars.begin(v), *sEnd = stars.end(v); s < sEnd; ++s)
    if (!gone[*s]) around.push_back(*s);
}

// Pieces of v's live star (connected through faces with v) into pieceOf (index in
// `around`); returns the number of pieces, -2 if an edge (v, w) has two or more fans of tets
// (w in `pinched`), or -1 if a face is used more than twice or the boundary around v is not
// one closed loop per piece.
int FlapPeeler::pieces(int v) {
  pinched.clear();
  const int S = static_cast<int>(around.size());
  pieceOf.assign(S, 0);
  if (S == 0) return 0;
  pairs.clear();
  for (int i = 0; i < S; ++i) {
    std::int32_t o[3], m = 0;
    for (int k = 0; k < 4; ++k)
      if (mesh.T(around[i], k) != v && m < 3) o[m++] = mesh.T(around[i], k);
    std::sort(o, o + 3);
    pairs.push_back({o[0], o[1], i});
    pairs.push_back({o[0], o[2], i});
    pairs.push_back({o[1], o[2], i});
  }
  std::sort(pairs.begin(), pairs.end());
  std::vector<int>& p = pieceOf;
  std::iota(p.begin(), p.end(), 0);
  linkNodes.clear();
  std::vector<std::array<std::int32_t, 2>> boundary;
  const bool paired = joinLinkEdges(pairs, p, boundary);
  for (const auto& e : boundary) {
    linkNodes.push_back(e[0]);
    linkNodes.push_back(e[1]);
  }
  if (!paired) return -1;
  int count = 0;
  for (int i = 0; i < S; ++i)
    if (findRoot(p, i) == i) ++count;
  for (int i = 0; i < S; ++i) p[i] = findRoot(p, i);
  return checkLink(boundary, count);
}

// Boundary link: every node twice, as many closed loops as pieces (a piece without
// boundary is a closed ball around an interior node: only alone). Returns count if so.
int FlapPeeler::checkLink(const std::vector<std::array<std::int32_t, 2>>& boundary, int count) {
  std::sort(linkNodes.begin(), linkNodes.end());
  for (size_t i = 0; i < linkNodes.size();) {
    size_t j = i;
    while (j < linkNodes.size() && linkNodes[j] == linkNodes[i]) ++j;
    if (j - i != 2) {
      if ((j - i) % 2 != 0) return -1;
      pinched.push_back(linkNodes[i]);  // edge (v, w) with two or more fans of tets
    }
    i = j;
  }
  if (!pinched.empty()) return -2;
  linkNodes.erase(std::unique(linkNodes.begin(), linkNodes.end()), linkNodes.end());
  linkParent.resize(linkNodes.size());
  std::iota(linkParent.begin(), linkParent.end(), 0);
  for (const auto& e : boundary)
    linkParent[findRoot(linkParent, sortedIndex(linkNodes, e[0]))] = findRoot(linkParent, sortedIndex(linkNodes, e[1]));
  int loops = 0;
  for (size_t i = 0; i < linkNodes.size(); ++i)
    if (findRoot(linkParent, static_cast<int>(i)) == static_cast<int>(i)) ++loops;
  if (loops != count && !(count == 1 && loops == 0)) return -1;
  return count;
}

// The chains start at the tets of v's live star that face a removed tet of the group.
void FlapPeeler::startChains(int v) {
  const int S = static_cast<int>(around.size());
  chainFrom.assign(S, -2);
  chainDepth.assign(S, 0);
  chainQueue.clear();
  for (int i = 0; i < S; ++i)
    for (int f = 0; f < 4; ++f)
      if (mesh.T(around[i], f) != v) {
        const int u = acrossWithGroup(around[i], f);
        if (u >= 0 && gone[u] && chainFrom[i] == -2) {
          chainFrom[i] = -1;
          chainDepth[i] = 1;
          chainQueue.push_back(i);
        }
      }
}

// v's live star is in `around`; the group's tets at v leave a hole in the boundary around
// v. Removes the shortest chain of tets around v (face to face through faces at v) from a
// tet at the hole to one on the outer boundary, adding it to the group; false if none of
// at most kChain tets.
bool FlapPeeler::openHoleToBoundary(int v) {
  const int S = static_cast<int>(around.size());
  startChains(v);
  for (size_t h = 0; h < chainQueue.size(); ++h) {
    const int i = chainQueue[h];
    bool outer = false;
    for (int f = 0; f < 4 && !outer; ++f)
      if (mesh.T(around[i], f) != v) outer = acrossWithGroup(around[i], f) < 0;
    if (outer) {
      for (int j = i; j >= 0; j = chainFrom[j]) takeTet(around[j]);
      return true;
    }
    if (chainDepth[i] >= kChain) continue;
    for (int f = 0; f < 4; ++f)
      if (mesh.T(around[i], f) != v) {
        const int u = across(around[i], f);
        const int j = u >= 0 ? aroundIndex(u) : S;
        if (j < S && chainFrom[j] == -2) {
          chainFrom[j] = i;
          chainDepth[j] = chainDepth[i] + 1;
          chainQueue.push_back(j);
        }
      }
  }
  return false;
}

// The live candidates of the group `root`, grown if it is inside a wedge; false if it has
// no boundary face or is too large (*grownLimit: the group's volume limit).
bool FlapPeeler::gatherGroup(int root, double* grownLimit) {
  group.clear();
  for (size_t i = 0; i < cands.size(); ++i)
    if (findRoot(parent, static_cast<int>(i)) == root && !gone[cands[i]]) group.push_back(cands[i]);
  if (group.empty()) return false;
  bool onBoundary = false;
  vol = 0;
  for (int t : group) {
    vol += volume(t);
    for (int f = 0; f < 4 && !onBoundary; ++f) onBoundary = across(t, f) < 0;
  }
  *grownLimit = groupLimit;
  if (!onBoundary && options.flap_grow_factor > 0) onBoundary = growWedge(grownLimit);
  return !(!onBoundary || vol > *grownLimit || vol > passLeft);
}

// Poor tets inside a wedge (no boundary face): the layer of their face neighbours on the
// boundary that are not good either joins, within flap_grow_factor x their own volume.
// True if any joined.
bool FlapPeeler::growWedge(double* grownLimit) {
  *grownLimit = std::min(groupLimit, options.flap_grow_factor * vol);
  bool grew = false;
  const size_t inner = group.size();
  for (size_t i = 0; i < inner; ++i)
    for (int f = 0; f < 4; ++f) {
      const int u = across(group[i], f);
      if (u < 0 || gone[u] || inGroup(u)) continue;
      bool boundaryFace = false;
      for (int g = 0; g < 4 && !boundaryFace; ++g) boundaryFace = across(u, g) < 0;
      if (!boundaryFace || !(tetQuality(u) < options.quality_target)) continue;
      group.push_back(u);
      vol += volume(u);
      grew = true;
    }
  return grew;
}

// The group's tet of least q*, computed here (not cached).
int FlapPeeler::worstTetOfGroup() const {
  int worstTet = group[0];
  double wq = 2;
  for (int t : group) {
    const double q = radiusRatio(pos(mesh.T(t, 0)), pos(mesh.T(t, 1)), pos(mesh.T(t, 2)), pos(mesh.T(t, 3)));
    if (q < wq) {
      wq = q;
      worstTet = t;
    }
  }
  return worstTet;
}

void FlapPeeler::collectGroupNodes() {
  groupNodes.clear();
  for (int t : group)
    for (int k = 0; k < 4; ++k) groupNodes.push_back(mesh.T(t, k));
  std::sort(groupNodes.begin(), groupNodes.end());
  groupNodes.erase(std::unique(groupNodes.begin(), groupNodes.end()), groupNodes.end());
}

// Pinched edges (v, w): keep the largest fan of tets around each, remove the others.
void FlapPeeler::splitPinchedEdges() {
  for (int w : pinched) {
    fanTets.clear();
    for (int t : around)
      if (!gone[t] && has(t, w)) fanTets.push_back(t);
    const int F = static_cast<int>(fanTets.size());
    fanParent.resize(F);
    std::iota(fanParent.begin(), fanParent.end(), 0);
    for (int a = 0; a < F; ++a)
      for (int b = a + 1; b < F; ++b) {
        int shared = 0;
        for (int k = 0; k < 4; ++k) shared += has(fanTets[b], mesh.T(fanTets[a], k));
        if (shared == 3) fanParent[findRoot(fanParent, a)] = findRoot(fanParent, b);
      }
    pieceVolume.assign(F, 0.0);
    for (int a = 0; a < F; ++a) pieceVolume[findRoot(fanParent, a)] += volume(fanTets[a]);
    const int keep = static_cast<int>(std::max_element(pieceVolume.begin(), pieceVolume.end()) - pieceVolume.begin());
    for (int a = 0; a < F; ++a)
      if (findRoot(fanParent, a) != keep) takeTet(fanTets[a]);
  }
}

// v's star is no manifold one without the group's tets.
NodeFix FlapPeeler::fixNonManifoldNode(int v, int worstTet) {
  // A node whose star was already not a manifold one before (earlier cuts left it
  // pinched) and stays so: the flap does not make it worse.
  restored.clear();
  for (int t : group)
    if (has(t, v)) {
      restored.push_back(t);
      gone[t] = 0;
    }
  liveStar(v);
  const int before = pieces(v);
  for (int t : restored) gone[t] = 1;
  if (before == -1) return NodeFix::kUnchanged;
  // The flap would open a hole through the surface around v (its star keeps one
  // piece, but the boundary around v becomes two loops): open the hole to the
  // boundary along the shortest chain of tets around v (at most kChain), so the
  // boundary around v is one loop again ...
  liveStar(v);
  if (openHoleToBoundary(v)) return NodeFix::kGrew;
  // ... or keep the flap's tets at v where the worst tet is not among them and the
  // rest is still a flap.
  bool worstKept = false;
  for (int t : restored) worstKept = worstKept || t == worstTet;
  if (worstKept || restored.size() == group.size()) return NodeFix::kRefuse;
  for (int t : restored) {
    gone[t] = 0;
    vol -= volume(t);
    group.erase(std::find(group.begin(), group.end(), t));
  }
  return NodeFix::kGrew;
}

// v's live star fell apart: every piece but the largest (by volume) joins the group.
void FlapPeeler::removeSmallerPieces() {
  pieceVolume.assign(around.size(), 0.0);
  for (size_t i = 0; i < around.size(); ++i) pieceVolume[pieceOf[i]] += volume(around[i]);
  const int keep = static_cast<int>(std::max_element(pieceVolume.begin(), pieceVolume.end()) - pieceVolume.begin());
  for (size_t i = 0; i < around.size(); ++i)
    if (pieceOf[i] != keep) takeTet(around[i]);
}

// Check the stars of the group's nodes; repair pinched nodes by removing the smaller pieces.
// The group's tets are marked gone; false if the group cannot be removed.
bool FlapPeeler::repairStars(double grownLimit, int worstTet) {
  bool ok = true;
  for (int round = 0; ok; ++round) {
    collectGroupNodes();
    bool grew = false;
    for (int v : groupNodes) {
      liveStar(v);
      const int count = pieces(v);
      if (count == -2) {
        splitPinchedEdges();
        grew = true;
        continue;
      }
      if (count < 0) {
        const NodeFix fix = fixNonManifoldNode(v, worstTet);
        if (fix == NodeFix::kRefuse) {
          ok = false;
          break;
        }
        if (fix == NodeFix::kGrew) grew = true;
        continue;
      }
      if (count <= 1) continue;
      removeSmallerPieces();
      grew = true;
    }
    if (!ok || !grew) break;
    if (round >= 3 || static_cast<int>(group.size()) > options.flap_max_tets || vol > grownLimit || vol > passLeft)
      ok = false;
  }
  return ok;
}

// Walks from rim tet r through the live tets, marking them r, until it meets an earlier
// walk (true), ends by itself, or, while no large part is known (big == 0), reaches kCap tets.
bool FlapPeeler::walkFrom(size_t r, int big) {
  walked.assign(1, rim[r]);
  mark[rim[r]] = static_cast<int>(r);
  bool met = false;
  for (size_t i = 0; i < walked.size() && !met && (big > 0 || static_cast<int>(walked.size()) < kCap); ++i)
    for (int f = 0; f < 4; ++f) {
      const int u = across(walked[i], f);
      if (u < 0) continue;
      if (mark[u] < 0) {
        mark[u] = static_cast<int>(r);
        walked.push_back(u);
      } else if (mark[u] != static_cast<int>(r)) {
        met = true;
      }
    }
  allWalked.insert(allWalked.end(), walked.begin(), walked.end());
  return met;
}

// The tets next to the group must stay connected through the tets around the group's nodes.
// Walk from each rim tet through the live tets: the rim tets one walk reaches are
// connected. The first walk into a large part stops at kCap tets; a later walk that
// reaches a tet of an earlier walk is connected to it (to the large part: a walk that
// ended by itself covered its whole piece) and stops there. A later walk that ends by
// itself before kCap tets has found a closed piece that hung on the group only (a chip
// the sweep almost cut off, held by a neck thinner than the flap): it is freed, as the
// cut frees chips. A later walk that passes kCap goes on until it meets an earlier
// walk (the rim tets are connected around a longer way: no bridge) or ends by itself
// (a second large part: the group is a bridge between large parts; refused).
bool FlapPeeler::noBridge() {
  rim.clear();
  for (int t : group)
    for (int f = 0; f < 4; ++f) {
      const int u = across(t, f);
      if (u >= 0) rim.push_back(u);
    }
  std::sort(rim.begin(), rim.end());
  rim.erase(std::unique(rim.begin(), rim.end()), rim.end());
  if (rim.size() <= 1) return true;
  if (mark.empty()) mark.assign(M, -1);
  bool ok = true;
  int big = 0;
  for (size_t r = 0; r < rim.size() && ok; ++r) {
    if (mark[rim[r]] >= 0) continue;
    if (walkFrom(r, big)) continue;
    if (static_cast<int>(walked.size()) >= kCap) {
      ok = ++big <= 1;
      continue;
    }
    // A closed piece: it hung on the group (a chip the sweep almost cut off); it is freed.
  }
  for (int t : allWalked) mark[t] = -1;
  allWalked.clear();
  return ok;
}

// The groups, worst first: each is removed if its stars can be kept manifold and it is no
// bridge; else its tets are live again.
void FlapPeeler::peelGroups() {
  for (const auto& entry : order) {
    double grownLimit = groupLimit;
    if (!gatherGroup(entry.second, &grownLimit)) continue;
    const int worstTet = worstTetOfGroup();
    for (int t : group) gone[t] = 1;
    bool ok = repairStars(grownLimit, worstTet);
    if (ok) ok = noBridge();
    if (!ok) {
      for (int t : group) gone[t] = 0;
      continue;
    }
    passLeft -= vol;
    peeled += static_cast<int>(group.size());
    peeledVolume += vol;
  }
}

void FlapPeeler::addCounts(OptimizeCounts* counts) const {
  if (counts) {
    counts->peeled += peeled;
    counts->flap_peeled += peeled;
    counts->peeled_volume += peeledVolume;
  }
}

}  // namespace

void peelFlaps(const TetMesh& mesh, const CutRegion& region, const std::vector<std::int32_t>& seeds,
               const NodeStars& stars, const Optimize3DOptions& options, std::vector<std::uint8_t>* dead,
               OptimizeCounts* counts, const std::function<double(int)>* quality) {
  const int N = mesh.numNodes();
  if (!(options.flap_quality > 0) || seeds.empty() || N == 0 || !(region.edge_length > 0)) return;
  const double edgeTet = region.edge_length * region.edge_length * region.edge_length / (6.0 * std::sqrt(2.0));
  const double groupLimit = options.flap_group_volume * edgeTet;
  const double passLeft = options.flap_pass_volume * edgeTet;
  if (!(groupLimit > 0) || !(passLeft > 0)) return;
  FlapPeeler peeler(mesh, stars, options, *dead, quality, groupLimit, passLeft);
  peeler.collectNearNodes(region, seeds);
  if (!peeler.collectCandidates()) return;
  peeler.orderGroups();
  peeler.peelGroups();
  peeler.addCounts(counts);
}

}  // namespace hysim::cutting
