// The pieces a cut cut off (Cut3DOptions::anchored_nodes), left out of the optimisation.
#include <numeric>

#include "cut3d_stages.hpp"

namespace hysim::cutting::cut3d_detail {

// The pieces the cut cut off (see Cut3DOptions::anchored_nodes): node-connected parts of
// `mesh` (through the tets in each node's list) with no anchored node. A search from the
// seeds (the nodes on and around the cut), one front per part found, the open fronts in turn
// a node at a time; fronts that meet merge. A front that reaches an anchored node holds its
// part in place; one that runs out of nodes has seen all of a free part. The search stops
// when every front is decided, when one front is open and none held a part yet (that part
// holds the tissue, unless nothing does: it is not looked into and not marked), or after
// `limit` nodes in all (then no open part is marked). Marks the tets of the
// free parts in *tets (#T) and their nodes in *nodes (#N); returns the number of parts.
namespace {

// The search of cutOffPieces: one front per part found, merged where two meet.
class PieceSearch {
 public:
  PieceSearch(const TetMesh& mesh, const StarLists& stars, const std::function<bool(int)>& anchored)
      : mesh_(mesh), stars_(stars), anchored_(anchored), owner_(static_cast<size_t>(mesh.numNodes()), -1) {}

  void seed(const std::vector<std::int32_t>& seeds) {
    for (const int s : seeds) {
      if (s < 0 || s >= mesh_.numNodes() || owner_[s] >= 0) continue;
      const int f = static_cast<int>(fronts_.size());
      fronts_.emplace_back();
      fronts_[f].parent = f;
      ++open_;
      join(s, f);
    }
  }

  // The open fronts in turn, a node at a time.
  void run(int limit) {
    std::vector<std::int32_t> turn(fronts_.size());
    std::iota(turn.begin(), turn.end(), 0);
    while (searching(limit)) {
      size_t kept = 0;
      for (const int f0 : turn) {
        if (!searching(limit)) break;
        if (fronts_[f0].parent != f0 || fronts_[f0].state != Open) continue;
        step(f0);
        if (fronts_[f0].parent == f0 && fronts_[f0].state == Open) turn[kept++] = f0;
      }
      turn.resize(kept);
    }
  }

  // Marks the free parts' tets and nodes; returns their number.
  int mark(std::vector<std::uint8_t>* tets, std::vector<std::uint8_t>* nodes) {
    int pieces = 0;
    for (size_t f = 0; f < fronts_.size(); ++f)
      pieces += fronts_[f].parent == static_cast<int>(f) && fronts_[f].state == Free;
    if (pieces == 0) return 0;
    const int N = mesh_.numNodes();
    tets->assign(static_cast<size_t>(mesh_.numTets()), 0);
    nodes->assign(static_cast<size_t>(N), 0);
    for (int v = 0; v < N; ++v) {
      if (owner_[v] < 0 || fronts_[root(owner_[v])].state != Free) continue;
      (*nodes)[v] = 1;
      const auto [b, e] = starOf(v);
      for (const std::int32_t* t = b; t < e; ++t) (*tets)[*t] = 1;
    }
    return pieces;
  }

 private:
  enum : std::uint8_t { Open, Held, Free };
  struct Front {
    std::vector<std::int32_t> queue;
    size_t head = 0;
    std::int32_t parent;
    std::uint8_t state = Open;
  };

  std::pair<const std::int32_t*, const std::int32_t*> starOf(int n) const {
    const StarLists& s = stars_;
    const std::int32_t* b = s.pool_start[n] >= 0 ? s.pool.data() + s.pool_start[n] : s.star.data() + s.off[n];
    const std::int32_t len = s.pool_start[n] >= 0 ? s.pool_len[n] : s.off[n + 1] - s.off[n];
    return std::make_pair(b, b + len);
  }
  int root(int f) {
    while (fronts_[f].parent != f) f = fronts_[f].parent = fronts_[fronts_[f].parent].parent;
    return f;
  }
  bool searching(int limit) const { return open_ > (held_ > 0 ? 0 : 1) && seen_ <= limit; }
  void hold(int f) {
    fronts_[f].state = Held;
    fronts_[f].queue.clear();
    --open_;
    ++held_;
  }
  // Node v joins front f (a root); false when that holds f's part in place.
  bool join(int v, int f) {
    owner_[v] = f;
    ++seen_;
    if (anchored_(v)) {
      hold(f);
      return false;
    }
    fronts_[f].queue.push_back(v);
    return true;
  }
  // The next node of f0's queue, or f0 is free: all of its part seen.
  void step(int f0) {
    Front& front = fronts_[f0];
    if (front.head == front.queue.size()) {
      front.state = Free;
      --open_;
      return;
    }
    const int u = front.queue[front.head++];
    const auto [b, e] = starOf(u);
    for (const std::int32_t* t = b; t < e && fronts_[f0].state == Open; ++t)
      for (int k = 0; k < 4; ++k)
        if (!visit(f0, mesh_.T(*t, k))) break;
  }
  // A neighbour v of f0's node; false when f0 is held now.
  bool visit(int f0, int v) {
    if (owner_[v] < 0) return join(v, f0);
    const int g = root(owner_[v]);
    if (g == f0) return true;
    // Two fronts of one part: g goes into f0 (f0 keeps its turn).
    Front& other = fronts_[g];
    other.parent = f0;
    if (other.state == Held) {
      hold(f0);
      return false;
    }
    --open_;  // (other was open: a free front has no node next to an unseen one)
    fronts_[f0].queue.insert(fronts_[f0].queue.end(), other.queue.begin() + static_cast<std::ptrdiff_t>(other.head),
                             other.queue.end());
    other.queue.clear();
    return true;
  }

  const TetMesh& mesh_;
  const StarLists& stars_;
  const std::function<bool(int)>& anchored_;
  std::vector<Front> fronts_;
  std::vector<std::int32_t> owner_;
  int open_ = 0, held_ = 0, seen_ = 0;
};

}  // namespace

int cutOffPieces(const TetMesh& mesh, const StarLists& stars, const std::vector<std::int32_t>& seeds,
                 const std::function<bool(int)>& anchored, int limit, std::vector<std::uint8_t>* tets,
                 std::vector<std::uint8_t>* nodes) {
  PieceSearch search(mesh, stars, anchored);
  search.seed(seeds);
  search.run(limit);
  return search.mark(tets, nodes);
}

}  // namespace hysim::cutting::cut3d_detail
