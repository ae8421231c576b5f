#pragma once
// An editable tet mesh: the mesh, dead flags (removed tets stay in place until compact()),
// node -> tet stars, a per-tet quality cache keyed by node versions, and the TopologyChange of
// the edits made through it. The cut's optimisation works over it; tests call validate()
// after every operation.
//
// Two levels of operations:
//  - primitives (markDead, setTetNodes, setPosition, ...) change one thing and leave the stars
//    of the nodes they touch stale until refreshStars(); readers skip dead tets. The optimiser
//    batches them and refreshes once per batch. They are not recorded in the TopologyChange.
//  - operations (splitEdge, moveNode, duplicateNode, collapseEdge, flip23, flip32, removeTet,
//    compact) check what they do, keep everything valid (stars refreshed) and are recorded.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "hysim/cutting/mesh.hpp"
#include "hysim/cutting/no_init_allocator.hpp"
#include "hysim/cutting/result.hpp"
#include "hysim/cutting/topology_change.hpp"

namespace hysim::cutting {

using StarVector = std::vector<std::int32_t, NoInitAllocator<std::int32_t>>;

// Node -> tet lists of a tet mesh (each list ascending): CSR rows (off, star), or, where
// pool_start[n] >= 0, pool_len[n] entries of `pool` from there.
struct StarLists {
  std::vector<std::int32_t> off;
  StarVector star;  // (not zeroed as it grows: buildStarLists writes every entry)
  std::vector<std::int32_t> pool_start, pool_len, pool;
};

// A read-only view of an editor's stars (live tets with the node, in index order).
struct NodeStars {
  const std::vector<std::int32_t>& off;
  const StarVector& star;
  const std::vector<std::int32_t>& pool_start;  // -1: the CSR row
  const std::vector<std::int32_t>& pool_len;
  const std::vector<std::int32_t>& pool;
  const std::int32_t* begin(int n) const {
    return pool_start[n] >= 0 ? pool.data() + pool_start[n] : star.data() + off[n];
  }
  const std::int32_t* end(int n) const {
    return pool_start[n] >= 0 ? pool.data() + pool_start[n] + pool_len[n] : star.data() + off[n + 1];
  }
};

class TetMeshEditor {
 public:
  using Vec3 = Eigen::Vector3d;

  // Edits `mesh` in place; `dead` (#T, or empty: all live) marks removed tets. `stars`, when
  // given, are the lists of the live tets and are taken over (moved from) instead of built.
  TetMeshEditor(TetMesh& mesh, std::vector<std::uint8_t>& dead, StarLists* stars = nullptr);

  TetMesh& mesh() { return mesh_; }
  const TetMesh& mesh() const { return mesh_; }
  int numNodes() const { return mesh_.numNodes(); }
  int numTets() const { return mesh_.numTets(); }  // dead ones included
  bool isDead(int t) const { return dead_[t] != 0; }

  // ---- stars ----
  const std::int32_t* starBegin(int n) const {
    return poolStart_[n] >= 0 ? pool_.data() + poolStart_[n] : star_.data() + off_[n];
  }
  const std::int32_t* starEnd(int n) const {
    return poolStart_[n] >= 0 ? pool_.data() + poolStart_[n] + poolLen_[n] : star_.data() + off_[n + 1];
  }
  NodeStars stars() const { return NodeStars{off_, star_, poolStart_, poolLen_, pool_}; }
  // The live tets around v (from the stars, dead ones skipped), plus the live ones of `extra`.
  void liveStar(int v, std::vector<std::int32_t>& out, const std::vector<std::int32_t>* extra = nullptr) const;
  // Rebuilds the stars of the nodes touched since the last refresh (live tets with the node,
  // in index order: what a full rebuild gives).
  void refreshStars();
  bool starsPending() const { return !touchedList_.empty(); }
  const std::vector<std::int32_t>& pendingNodes() const { return touchedList_; }

  // ---- primitives ----
  void touch(int n) {
    if (!touched_[n]) {
      touched_[n] = 1;
      touchedList_.push_back(n);
    }
  }
  // Marks t dead (its slot joins killed()) and its nodes' stars stale.
  void markDead(int t) {
    dead_[t] = 1;
    killed_.push_back(t);
    for (int k = 0; k < 4; ++k) touch(mesh_.T(t, k));
  }
  // Tet t took node n (t's slot was rewritten): n's star gets t at the next refresh.
  void noteGained(int n, int t) { gained_.emplace_back(n, t); }
  // Rewrites tet t's nodes (old and new nodes' stars stale, the topology clock advances).
  void setTetNodes(int t, int a, int b, int c, int d);
  // Tets removed through markDead, in order (their slots may be reused).
  const std::vector<std::int32_t>& killed() const { return killed_; }
  // Counts changes of which tets hold which nodes (setTetNodes, or bumpTopology by a caller
  // that writes mesh().T itself).
  std::uint64_t topologyClock() const { return topoClock_; }
  void bumpTopology() { ++topoClock_; }

  // ---- positions and quality ----
  Vec3 position(int i) const { return mesh_.X.row(i).transpose(); }
  // Each write takes a new version number; restorePosition puts back a position and the
  // number it had (so cached qualities computed there hit again).
  void setPosition(int n, const Vec3& x) {
    mesh_.X.row(n) = x.transpose();
    nodeVer_[n] = ++verClock_;
  }
  void restorePosition(int n, const Vec3& x, std::uint32_t ver) {
    mesh_.X.row(n) = x.transpose();
    nodeVer_[n] = ver;
  }
  std::uint32_t version(int n) const { return nodeVer_[n]; }
  // q* (radiusRatio) of tet t, cached: a hit needs the same nodes at the same versions, so it
  // is exactly what radiusRatio returns.
  double quality(int t);
  // quality(t) where t is positively oriented, else -1 (the sign cached with q*).
  double qualityIfPositive(int t);
  // q* of tet t with node n placed at y; -1 where it would invert or go flat.
  double qualityWith(int t, int n, const Vec3& y) const;
  // The worst qualityIfPositive around n (1 when none), and which tet (where asked).
  double worstAround(int n, int* worstTet);

  // ---- checked operations (stars refreshed, recorded) ----
  // Splits edge (a, b) at (1 - w) a + w b, 0 < w < 1: every live tet with the edge becomes
  // two. Returns the new node, or -1 when (a, b) is not an edge.
  int splitEdge(int a, int b, double w);
  // Moves n to y unless a tet around it would invert or its worst q* would fall below
  // min(floor, the worst before). Returns whether it moved.
  bool moveNode(int n, const Vec3& y, double floor);
  // moveNode's check alone (a caller that moves with setPosition and records nothing).
  bool moveAllowed(int n, const Vec3& y, double floor);
  // A copy of n at its position taking n's place in `tets` (tets around n): the two sides
  // of a cut separate there. Returns the copy, or -1 when a tet of `tets` does not hold n.
  int duplicateNode(int n, const std::vector<std::int32_t>& tets);
  // Merges u into v (v stays where it is): the tets with both die, the others take v. Refused
  // (false, nothing changed) where a tet would invert, two tets would coincide, a face would be
  // used by more than two tets, or (u, v) is not an edge.
  bool collapseEdge(int u, int v);
  // 2-3: tet t and its neighbour across face f become three tets around the edge between
  // their far nodes. Needs a free slot or appends one. Refused where a new tet is not positive,
  // the far nodes already share an edge, or there is no neighbour.
  bool flip23(int t, int f);
  // 3-2: the three tets around interior edge (a, b) become two. Refused where the edge has
  // not exactly three tets in a closed ring, a new tet is not positive, or the ring's triangle
  // is a face already.
  bool flip32(int a, int b);
  // Removes tet t (its nodes stay; an unused node goes at compact()).
  void removeTet(int t);
  // Drops dead tets and nodes no live tet uses, renumbering both (order kept), and completes
  // change() (old -> new maps) for the operations since construction or the last compact().
  // The editor then edits the compacted mesh; a later operation starts a new change.
  void compact();

  // Everything consistent: mesh valid (cutting::validate over live tets), dead flags sized,
  // stars equal to a rebuild (none pending), cached qualities exact, killed tets dead.
  Status validate() const;
  // What the checked operations changed, from the mesh at construction (or the last
  // compact()) to the mesh compact() makes; complete after compact().
  const TopologyChange& change() const { return change_; }

 private:
  int addNode(const Vec3& x);
  // A slot for a new tet: a dead one (killed()) or one appended; live, labelled, no origin.
  int takeSlot(std::int32_t label);
  // Tet t gets new nodes as a new element (its old one removed).
  void rewrite(int t, const std::array<int, 4>& v);
  void buildAllStars();
  void ensureTracking();
  void fillChange(const std::vector<std::int32_t>& newNode, const std::vector<std::int32_t>& newTet, int liveNodes,
                  int liveTets);
  bool isEdge(int a, int b) const;
  int faceUses(int a, int b, int c) const;  // live tets holding the triangle

  TetMesh& mesh_;
  std::vector<std::uint8_t>& dead_;
  std::vector<std::int32_t> off_, poolStart_, poolLen_, pool_;
  StarVector star_;
  std::vector<std::uint8_t> touched_;
  std::vector<std::int32_t> touchedList_;
  std::vector<std::pair<std::int32_t, std::int32_t>> gained_;  // (node, tet): tet took the node
  std::vector<std::int32_t> killed_, scratch_, scratch2_;
  std::vector<std::uint32_t> nodeVer_;
  std::uint32_t verClock_ = 0;
  std::uint64_t topoClock_ = 0;
  struct QEntry {
    std::int32_t v[4];
    std::uint32_t ver[4];
    double q;
    std::int8_t up;  // positively oriented at these positions (1, 0), -1: not asked yet
  };
  QEntry keyOf(int t) const;                    // t's nodes and their versions
  QEntry* cached(int t, const QEntry& key);      // t's entry where computed at key, else null
  double store(int t, QEntry key, std::int8_t up);  // computes q* at key, caches it
  std::vector<std::int32_t> qSlot_;  // per tet: its entry in qPool_, -1 none
  std::vector<QEntry, NoInitAllocator<QEntry>> qPool_;
  std::int32_t qNext_ = 0;
  // What the checked operations did (ensureTracking starts it at the first one): per tet slot
  // the element it still is (-1: new or rewritten), per node the node it was (-1: new), the
  // node a collapse merged it into, whether it moved; the nodes made.
  std::vector<std::int32_t> tetOrigin_, nodeOrigin_, mergedInto_;
  std::vector<std::uint8_t> movedFlag_;
  std::vector<NewNode> newNodes_;
  bool tracking_ = false;
  TopologyChange change_;
};

// The CSR rows of all numNodes nodes of T (pool empty).
void buildStarLists(const Tets& T, int numNodes, StarLists* lists);

}  // namespace hysim::cutting
