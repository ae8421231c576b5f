// Hybrid cutting of tetrahedral meshes (see cut3d.hpp for the outline).
#include "hysim/cutting/cut3d.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <numeric>
#include <span>
#include <string>
#include <unordered_map>

#include "hysim/cutting/mesh_stats.hpp"
#include "optimize3d_internal.hpp"

namespace hysim::cutting {


namespace {

using Vec3 = Eigen::Vector3d;
using Tet = std::array<std::int32_t, 4>;

std::uint64_t edgeKey(std::int32_t a, std::int32_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

struct FaceKey {
  std::array<std::int32_t, 3> v;
  bool operator==(const FaceKey& o) const { return v[0] == o.v[0] && v[1] == o.v[1] && v[2] == o.v[2]; }
  bool operator<(const FaceKey& o) const {
    return v[0] != o.v[0] ? v[0] < o.v[0] : v[1] != o.v[1] ? v[1] < o.v[1] : v[2] < o.v[2];
  }
};
struct FaceKeyHash {
  size_t operator()(const FaceKey& k) const {
    std::uint64_t h = 1469598103934665603ull;
    for (int x : k.v) h = (h ^ static_cast<std::uint32_t>(x)) * 1099511628211ull;
    return static_cast<size_t>(h);
  }
};
// Open-addressing hash map (linear probing, power-of-two capacity) for the small maps of a
// cut: crossed edges, faces on the cut. Much cheaper than std::unordered_map (no node per
// entry); lookups only, so its layout never affects the results. `empty` is a key no entry
// uses.
template <class Key, class Value, class Hash>
class FlatMap {
 public:
  explicit FlatMap(Key empty) : empty_(empty) { rehash(64); }
  size_t size() const { return size_; }
  // Room for n entries without growing (capacity: a power of two >= 2 n).
  void reserve(size_t n) {
    size_t capacity = keys_.size();
    while (capacity < 2 * n) capacity *= 2;
    if (capacity > keys_.size()) rehash(capacity);
  }
  Value* find(const Key& k) {
    for (size_t i = Hash{}(k) & mask_;; i = (i + 1) & mask_) {
      if (keys_[i] == k) return &vals_[i];
      if (keys_[i] == empty_) return nullptr;
    }
  }
  bool contains(const Key& k) { return find(k) != nullptr; }
  // The value for k, inserting `v` if absent; second: whether it was inserted.
  std::pair<Value*, bool> tryEmplace(const Key& k, const Value& v) {
    if (2 * (size_ + 1) > keys_.size()) rehash(2 * keys_.size());
    size_t i = Hash{}(k) & mask_;
    for (; !(keys_[i] == empty_); i = (i + 1) & mask_)
      if (keys_[i] == k) return {&vals_[i], false};
    keys_[i] = k;
    vals_[i] = v;
    ++size_;
    return {&vals_[i], true};
  }
  template <class F>
  void forEach(F&& f) {
    for (size_t i = 0; i < keys_.size(); ++i)
      if (!(keys_[i] == empty_)) f(keys_[i], vals_[i]);
  }

 private:
  void rehash(size_t capacity) {
    std::vector<Key> keys(capacity, empty_);
    std::vector<Value> vals(capacity);
    keys.swap(keys_);
    vals.swap(vals_);
    mask_ = capacity - 1;
    size_ = 0;
    for (size_t i = 0; i < keys.size(); ++i)
      if (!(keys[i] == empty_)) tryEmplace(keys[i], vals[i]);
  }
  Key empty_;
  std::vector<Key> keys_;
  std::vector<Value> vals_;
  size_t mask_ = 0, size_ = 0;
};
struct EdgeKeyHash {
  size_t operator()(std::uint64_t k) const { return static_cast<size_t>((k * 0x9E3779B97F4A7C15ull) >> 20); }
};
using EdgeMap = FlatMap<std::uint64_t, std::int32_t, EdgeKeyHash>;
constexpr std::uint64_t kNoEdge = ~0ull;
struct FaceFlatHash {
  size_t operator()(const FaceKey& k) const {
    const std::uint64_t h = (static_cast<std::uint64_t>(static_cast<std::uint32_t>(k.v[0])) * 0x9E3779B97F4A7C15ull) ^
                            (static_cast<std::uint64_t>(static_cast<std::uint32_t>(k.v[1])) * 0xC2B2AE3D27D4EB4Full) ^
                            (static_cast<std::uint64_t>(static_cast<std::uint32_t>(k.v[2])) * 0x165667B19E3779F9ull);
    return static_cast<size_t>((h ^ (h >> 29)) * 0xBF58476D1CE4E5B9ull >> 20);
  }
};
constexpr FaceKey kNoFace{{-1, -1, -1}};

FaceKey makeFace(std::int32_t a, std::int32_t b, std::int32_t c) {
  // Sorted (three compare-exchanges).
  if (a > b) std::swap(a, b);
  if (b > c) std::swap(b, c);
  if (a > b) std::swap(a, b);
  return FaceKey{{a, b, c}};
}

// Outward faces of a positive tet, by the local index of the opposite vertex.
constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
constexpr int kEdge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
// The three faces of a tet containing its vertex k, each by its two other vertices.
constexpr int kFacePairs[4][3][2] = {{{2, 3}, {1, 3}, {1, 2}},
                                     {{2, 3}, {0, 3}, {0, 2}},
                                     {{1, 3}, {0, 3}, {0, 1}},
                                     {{1, 2}, {0, 2}, {0, 1}}};

double signedVolume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

struct CrossedEdge {
  std::int32_t a, b;   // original node indices
  double t;            // crossing at a + t (b - a)
  Vec3 point;          // crossing point (surface) -- plane recomputes from phi
  bool alive = true;   // still crossed (neither end snapped)
};

// An end node of a crossed edge whose crossing lies within `limit` (fraction of the edge) of
// it: the snap candidates, and the routing candidates. Nearest first, ties in edge order.
struct EndCandidate {
  double frac;
  std::int32_t node, edge;
};

std::vector<EndCandidate> endCandidates(const std::vector<CrossedEdge>& crossed, double limit, bool alive_only) {
  std::vector<EndCandidate> out;
  for (int e = 0; e < static_cast<int>(crossed.size()); ++e) {
    const CrossedEdge& c = crossed[e];
    if (alive_only && !c.alive) continue;
    if (c.t <= limit) out.push_back({c.t, c.a, e});
    if (1.0 - c.t <= limit) out.push_back({1.0 - c.t, c.b, e});
  }
  std::stable_sort(out.begin(), out.end(), [](const EndCandidate& x, const EndCandidate& y) { return x.frac < y.frac; });
  return out;
}

// Working mesh: row-major copies of the input arrays (a node's or a tet's entries in one
// place, which the local passes below read over and over) plus appended nodes and tets.
// The output mesh is written once from them (Assemble).
struct Work {
  std::vector<Vec3> X;             // #nodes: input rows (may move), then appended nodes
  // #tets: input rows (modified in place), then appended tets (not zeroed as it grows: the
  // constructor writes every input row, addTet the appended ones).
  std::vector<Tet, NoInitAllocator<Tet>> T;
  std::vector<std::int32_t> extraMat;  // material of the appended tets
  int N0, M0;

  Work(const TetMesh& input, size_t extraNodes, size_t extraTets) : N0(input.numNodes()), M0(input.numTets()) {
    X.reserve(N0 + extraNodes);
    T.reserve(M0 + extraTets);
    extraMat.reserve(extraTets);
    X.resize(N0);
    const double* c[3] = {input.X.col(0).data(), input.X.col(1).data(), input.X.col(2).data()};
    for (int i = 0; i < N0; ++i) X[i] = Vec3(c[0][i], c[1][i], c[2][i]);
    T.resize(M0);
    const std::int32_t* d[4] = {input.T.col(0).data(), input.T.col(1).data(), input.T.col(2).data(),
                                input.T.col(3).data()};
    for (int t = 0; t < M0; ++t) T[t] = {d[0][t], d[1][t], d[2][t], d[3][t]};
  }
  int numNodes() const { return static_cast<int>(X.size()); }
  int numTets() const { return static_cast<int>(T.size()); }
  const Vec3& x(int i) const { return X[i]; }
  const Tet& tet(int t) const { return T[t]; }
  std::vector<std::int32_t> changedNodes, changedTets;  // input rows written (may repeat)
  void setTet(int t, const Tet& v) {
    T[t] = v;
    if (t < M0) changedTets.push_back(t);
  }
  void setX(int i, const Vec3& p) {
    X[i] = p;
    if (i < N0) changedNodes.push_back(i);
  }
  int addTet(Tet v, std::int32_t material) {
    T.push_back(v);
    extraMat.push_back(material);
    return numTets() - 1;
  }
  int addNode(Vec3 p) {
    X.push_back(p);
    return numNodes() - 1;
  }
};

// Quick test for the usual case, an interior node: is every face containing n shared by an
// even number of n's tets? XOR of a 64-bit hash of each face (by its other two nodes) over
// the star: zero when every face occurs an even number of times; a face used once (a
// boundary face; there are at least three around a boundary node) leaves a random non-zero
// value (zero only with probability 2^-64).
inline std::uint64_t mix64(std::uint64_t x) {
  x ^= x >> 30;
  x *= 0xBF58476D1CE4E5B9ull;
  x ^= x >> 27;
  x *= 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
int findLocal(const Tet& t, int v);
template <class W>
bool evenFacePairs(const W& w, int n, const std::vector<std::int32_t>& starOff, const StarVector& starTet) {
  std::uint64_t acc = 0;
  for (int s = starOff[n]; s < starOff[n + 1]; ++s) {
    const auto& tv = w.tet(starTet[s]);
    // The three edges of the tet without n: the faces with n, by their other two nodes.
    for (const auto& e : kFacePairs[findLocal(tv, n)]) {
      const std::uint32_t a = static_cast<std::uint32_t>(tv[e[0]]), b = static_cast<std::uint32_t>(tv[e[1]]);
      acc ^= mix64((static_cast<std::uint64_t>(std::min(a, b)) << 32) | std::max(a, b));
    }
  }
  return acc == 0;
}

int findLocal(const Tet& t, int v) {
  for (int k = 0; k < 4; ++k)
    if (t[k] == v) return k;
  return -1;
}

// The pieces the cut cut off (see Cut3DOptions::anchored_nodes): node-connected parts of
// `mesh` (through the tets in each node's list) with no anchored node. A search from the
// seeds (the nodes on and around the cut), one front per part found, the open fronts in turn
// a node at a time; fronts that meet merge. A front that reaches an anchored node holds its
// part in place; one that runs out of nodes has seen all of a free part. The search stops
// when every front is decided, when one front is open and none held a part yet (that part
// holds the tissue, unless nothing does: it is not looked into and not marked), or after
// `limit` nodes in all (then no open part is marked). Marks the tets of the
// free parts in *tets (#T) and their nodes in *nodes (#N); returns the number of parts.
int cutOffPieces(const TetMesh& mesh, const StarLists& stars, const std::vector<std::int32_t>& seeds,
                 const std::function<bool(int)>& anchored, int limit, std::vector<std::uint8_t>* tets,
                 std::vector<std::uint8_t>* nodes) {
  const int N = mesh.numNodes();
  auto starOf = [&](int n) {
    const std::int32_t* b = stars.pool_start[n] >= 0 ? stars.pool.data() + stars.pool_start[n] : stars.star.data() + stars.off[n];
    const std::int32_t len = stars.pool_start[n] >= 0 ? stars.pool_len[n] : stars.off[n + 1] - stars.off[n];
    return std::make_pair(b, b + len);
  };
  enum : std::uint8_t { Open, Held, Free };
  struct Front {
    std::vector<std::int32_t> queue;
    size_t head = 0;
    std::int32_t parent;
    std::uint8_t state = Open;
  };
  std::vector<Front> fronts;
  std::vector<std::int32_t> owner(N, -1);
  auto root = [&](int f) {
    while (fronts[f].parent != f) f = fronts[f].parent = fronts[fronts[f].parent].parent;
    return f;
  };
  int open = 0, held = 0, seen = 0;
  // Node v joins front f (a root); false when that holds f's part in place.
  auto join = [&](int v, int f) {
    owner[v] = f;
    ++seen;
    if (!anchored(v)) {
      fronts[f].queue.push_back(v);
      return true;
    }
    fronts[f].state = Held;
    fronts[f].queue.clear();
    --open;
    ++held;
    return false;
  };
  for (const int s : seeds) {
    if (s < 0 || s >= N || owner[s] >= 0) continue;
    const int f = static_cast<int>(fronts.size());
    fronts.emplace_back();
    fronts[f].parent = f;
    ++open;
    join(s, f);
  }
  std::vector<std::int32_t> turn(fronts.size());
  std::iota(turn.begin(), turn.end(), 0);
  auto searching = [&] { return open > (held > 0 ? 0 : 1) && seen <= limit; };
  while (searching()) {
    size_t kept = 0;
    for (const int f0 : turn) {
      if (!searching()) break;
      if (fronts[f0].parent != f0 || fronts[f0].state != Open) continue;
      Front& front = fronts[f0];
      if (front.head == front.queue.size()) {  // all of its part seen
        front.state = Free;
        --open;
        continue;
      }
      const int u = front.queue[front.head++];
      const auto [b, e] = starOf(u);
      for (const std::int32_t* t = b; t < e && fronts[f0].state == Open; ++t)
        for (int k = 0; k < 4; ++k) {
          const int v = mesh.T(*t, k);
          if (owner[v] < 0) {
            if (!join(v, f0)) break;
            continue;
          }
          const int g = root(owner[v]);
          if (g == f0) continue;
          // Two fronts of one part: g goes into f0 (f0 keeps its turn).
          Front& other = fronts[g];
          other.parent = f0;
          if (other.state == Held) {
            fronts[f0].state = Held;
            fronts[f0].queue.clear();
            --open;
            ++held;
            break;
          }
          --open;  // (other was open: a free front has no node next to an unseen one)
          fronts[f0].queue.insert(fronts[f0].queue.end(), other.queue.begin() + static_cast<std::ptrdiff_t>(other.head),
                                  other.queue.end());
          other.queue.clear();
        }
      if (fronts[f0].parent == f0 && fronts[f0].state == Open) turn[kept++] = f0;
    }
    turn.resize(kept);
  }
  int pieces = 0;
  for (size_t f = 0; f < fronts.size(); ++f) pieces += fronts[f].parent == static_cast<int>(f) && fronts[f].state == Free;
  if (pieces == 0) return 0;
  tets->assign(static_cast<size_t>(mesh.numTets()), 0);
  nodes->assign(static_cast<size_t>(N), 0);
  for (int v = 0; v < N; ++v) {
    if (owner[v] < 0 || fronts[root(owner[v])].state != Free) continue;
    (*nodes)[v] = 1;
    const auto [b, e] = starOf(v);
    for (const std::int32_t* t = b; t < e; ++t) (*tets)[*t] = 1;
  }
  return pieces;
}

}  // namespace

void buildStarLists(const Tets& T, int numNodes, StarLists* lists) {
  const int M = static_cast<int>(T.rows());
  std::vector<std::int32_t>& off = lists->off;
  StarVector& star = lists->star;
  // Counts at off[n + 2], their prefix sums, then each tet at off[n + 1]++: afterwards
  // off[n] .. off[n + 1] is n's row (ascending: the tets in index order).
  off.assign(static_cast<size_t>(numNodes) + 2, 0);
  star.resize(4 * static_cast<size_t>(M));
  const std::int32_t *c0 = T.col(0).data(), *c1 = T.col(1).data(), *c2 = T.col(2).data(), *c3 = T.col(3).data();
  std::int32_t* o = off.data();
  std::int32_t* s = star.data();
  for (int t = 0; t < M; ++t) {
    ++o[c0[t] + 2];
    ++o[c1[t] + 2];
    ++o[c2[t] + 2];
    ++o[c3[t] + 2];
  }
  for (int i = 0; i < numNodes; ++i) o[i + 2] += o[i + 1];
  for (int t = 0; t < M; ++t) {
    s[o[c0[t] + 1]++] = t;
    s[o[c1[t] + 1]++] = t;
    s[o[c2[t] + 1]++] = t;
    s[o[c3[t] + 1]++] = t;
  }
  off.pop_back();
  lists->pool_start.clear();
  lists->pool_len.clear();
  lists->pool.clear();
}

void patchStarLists(const Tets& before, const Tets& after, int numNodesAfter, std::vector<std::int32_t> changed,
                    StarLists* lists) {
  const int M0 = static_cast<int>(before.rows()), M1 = static_cast<int>(after.rows());
  const int N0 = static_cast<int>(lists->off.size()) - 1;
  // The changed rows sorted, without repeats (what sort + unique gives), from a bit per row
  // (the words that got a bit, sorted, then each word's bits in order); the merge below reads
  // the bits.
  IndexBits changedBits(M0);
  for (const int t : changed) changedBits.mark(t);
  changed.clear();
  changedBits.listInto(changed);
  auto isChanged = [&changedBits](std::int32_t t) { return changedBits.has(t); };
  // The nodes whose lists change (those of the changed tets before and after, and of the
  // appended tets), numbered as met; for each, the changed and appended tets that have it
  // now (CSR over those numbers, ascending: the tets are visited in index order).
  std::vector<std::int32_t> local(numNodesAfter, -1), nodes, count;
  auto number = [&](std::int32_t n) {
    if (local[n] < 0) {
      local[n] = static_cast<std::int32_t>(nodes.size());
      nodes.push_back(n);
      count.push_back(0);
    }
    return local[n];
  };
  for (const int t : changed)
    for (int k = 0; k < 4; ++k) {
      number(before(t, k));
      ++count[number(after(t, k))];
    }
  for (int t = M0; t < M1; ++t)
    for (int k = 0; k < 4; ++k) ++count[number(after(t, k))];
  std::vector<std::int32_t> gainedOff(nodes.size() + 1, 0), gained;
  for (size_t i = 0; i < nodes.size(); ++i) gainedOff[i + 1] = gainedOff[i] + count[i];
  gained.resize(gainedOff.back());
  for (size_t i = 0; i < nodes.size(); ++i) count[i] = gainedOff[i];  // fill positions
  for (const int t : changed)
    for (int k = 0; k < 4; ++k) gained[count[local[after(t, k)]]++] = t;
  for (int t = M0; t < M1; ++t)
    for (int k = 0; k < 4; ++k) gained[count[local[after(t, k)]]++] = t;
  // Appended nodes: empty CSR rows.
  lists->off.resize(static_cast<size_t>(numNodesAfter) + 1, lists->off[N0]);
  lists->pool_start.assign(numNodesAfter, -1);
  lists->pool_len.assign(numNodesAfter, 0);
  std::vector<std::int32_t>& pool = lists->pool;
  pool.clear();
  pool.reserve(gained.size() + 8 * nodes.size());
  for (size_t i = 0; i < nodes.size(); ++i) {
    // Merge n's old row without the changed tets and the tets that now have n.
    const int n = nodes[i];
    const std::int32_t* o = n < N0 ? lists->star.data() + lists->off[n] : nullptr;
    const std::int32_t* oEnd = n < N0 ? lists->star.data() + lists->off[n + 1] : nullptr;
    const std::int32_t* g = gained.data() + gainedOff[i];
    const std::int32_t* gEnd = gained.data() + gainedOff[i + 1];
    const size_t start = pool.size();
    for (;;) {
      while (o < oEnd && isChanged(*o)) ++o;
      const bool haveOld = o < oEnd, haveNew = g < gEnd;
      if (!haveOld && !haveNew) break;
      if (haveOld && (!haveNew || *o < *g)) {
        pool.push_back(*o++);
      } else {
        pool.push_back(*g++);
      }
    }
    lists->pool_start[n] = static_cast<std::int32_t>(start);
    lists->pool_len[n] = static_cast<std::int32_t>(pool.size() - start);
  }
}

double totalVolume(const TetMesh& mesh) {
  double v = 0;
  for (int t = 0; t < mesh.numTets(); ++t) v += tetVolume(mesh, t);
  return v;
}

Result<Cut3DResult> cut3d(const TetMesh& input, const CutSurface& surface, const Cut3DOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const int N0 = input.numNodes(), M0 = input.numTets();
  if (M0 == 0 || N0 == 0) return Error{"cut3d: empty mesh"};
  if (input.material.size() != 0 && input.material.size() != M0) return Error{"cut3d: material size differs from #T"};
  if (input.T.minCoeff() < 0 || input.T.maxCoeff() >= N0)
    for (int t = 0; t < M0; ++t)
      for (int k = 0; k < 4; ++k)
        if (input.T(t, k) < 0 || input.T(t, k) >= N0)
          return Error{"cut3d: tet " + std::to_string(t) + " has a node index out of range"};
  if (!input.X.allFinite()) return Error{"cut3d: non-finite node coordinates"};
  if (!(options.snap_region >= 0 && options.snap_region <= 0.5)) return Error{"cut3d: snap_region must be in [0, 0.5]"};

  Cut3DResult result;
  TetMesh& out = result.mesh;  // written at Assemble
  Cut3DReport& report = result.report;
  // The steps' wall times (report.*_ms): each lap adds the time since the last.
  auto mark = start;
  auto lap = [&mark](double& into, std::chrono::steady_clock::time_point now = std::chrono::steady_clock::now()) {
    into += std::chrono::duration<double, std::milli>(now - mark).count();
    mark = now;
  };
  TopologyChange& change = result.change;
  auto materialOf = [&](int t) { return input.material.size() != 0 ? input.material(t) : 0; };

  const Vec3 lo = input.X.colwise().minCoeff().transpose(), hi = input.X.colwise().maxCoeff().transpose();
  const double diag = (hi - lo).norm();
  if (!(diag > 0)) return Error{"cut3d: degenerate mesh bounding box"};
  const double eps = options.on_surface_tolerance * diag;
  const bool plane = surface.isPlane();

  // 1. Classification. side: +1 / -1 strictly off the surface (where known), 0 on it or unknown.
  std::vector<double> phi;            // plane: signed distances
  std::vector<std::uint8_t> on;       // on the surface (grows with new nodes)
  on.assign(N0, 0);
  std::vector<CrossedEdge> crossed;
  std::vector<Vec3> crossedNormal;    // surface: normal of the hit triangle per crossed edge
  EdgeMap edgeIndex(kNoEdge);  // crossed edge -> index
  std::vector<std::int32_t> crossedTets;
  std::vector<std::int32_t> onNodes;  // original nodes on the surface
  if (plane) {
    phi.resize(N0);
    const Vec3 n = surface.planeNormal(), p = surface.planePoint();
    // Per node: 1 strictly on the positive side, 2 strictly on the negative side.
    std::vector<std::uint8_t> sideBits(N0);
    for (int i = 0; i < N0; ++i) {
      phi[i] = n.dot(input.X.row(i).transpose() - p);
      sideBits[i] = static_cast<std::uint8_t>((phi[i] > eps ? 1 : 0) | (phi[i] < -eps ? 2 : 0));
      if (std::abs(phi[i]) <= eps) {
        on[i] = 1;
        onNodes.push_back(i);
      }
    }
    const std::int32_t* T0c[4] = {input.T.col(0).data(), input.T.col(1).data(), input.T.col(2).data(),
                                  input.T.col(3).data()};
    for (int t = 0; t < M0; ++t)
      if ((sideBits[T0c[0][t]] | sideBits[T0c[1][t]] | sideBits[T0c[2][t]] | sideBits[T0c[3][t]]) == 3)
        crossedTets.push_back(t);
    edgeIndex.reserve(crossedTets.size());  // about as many crossed edges as crossed tets
    for (const int t : crossedTets) {
      const std::int32_t tv[4] = {T0c[0][t], T0c[1][t], T0c[2][t], T0c[3][t]};
      for (const auto& e : kEdge) {
        const int a = tv[e[0]], b = tv[e[1]];
        if (!((phi[a] > eps && phi[b] < -eps) || (phi[a] < -eps && phi[b] > eps))) continue;
        const auto key = edgeKey(a, b);
        if (!edgeIndex.tryEmplace(key, static_cast<std::int32_t>(crossed.size())).second) continue;
        const int lo_ = std::min(a, b), hi_ = std::max(a, b);
        const double tt = phi[lo_] / (phi[lo_] - phi[hi_]);
        crossed.push_back({lo_, hi_, tt, Vec3::Zero(), true});
      }
    }
  } else {
    std::vector<std::uint8_t> seen(N0, 0);
    FlatMap<std::uint64_t, std::uint8_t, EdgeKeyHash> tested(kNoEdge);
    // Outcodes against the surface's box grown by 2 eps (bit per side and axis): a tet whose
    // nodes share a bit lies outside that box, which is what mayTouch tests first.
    std::vector<std::uint8_t> outcode(N0);
    {
      const Eigen::Array3d blo = surface.bounds().min().array() - 2 * eps, bhi = surface.bounds().max().array() + 2 * eps;
      // Column by column (contiguous coordinates: the compares vectorise).
      const double *x0 = input.X.col(0).data(), *x1 = input.X.col(1).data(), *x2 = input.X.col(2).data();
      const double lo0 = blo[0], lo1 = blo[1], lo2 = blo[2], hi0 = bhi[0], hi1 = bhi[1], hi2 = bhi[2];
      std::uint8_t* oc = outcode.data();
      for (int i = 0; i < N0; ++i)
        oc[i] = static_cast<std::uint8_t>((x0[i] < lo0 ? 1 : 0) | (x0[i] > hi0 ? 2 : 0) | (x1[i] < lo1 ? 4 : 0) |
                                          (x1[i] > hi1 ? 8 : 0) | (x2[i] < lo2 ? 16 : 0) | (x2[i] > hi2 ? 32 : 0));
    }
    for (int t = 0; t < M0; ++t) {
      if (outcode[input.T(t, 0)] & outcode[input.T(t, 1)] & outcode[input.T(t, 2)] & outcode[input.T(t, 3)]) continue;
      Eigen::AlignedBox3d box;
      for (int k = 0; k < 4; ++k) box.extend(input.X.row(input.T(t, k)).transpose());
      // Tets away from every leaf of the surface's tree have no node on it and no crossed
      // edge (the margin 2 eps only adds tets, which then find nothing).
      if (!surface.mayTouch(box, 2 * eps)) continue;
      for (int k = 0; k < 4; ++k) {
        const int v = input.T(t, k);
        if (seen[v]) continue;
        seen[v] = 1;
        if (surface.within(input.X.row(v).transpose(), eps)) {
          on[v] = 1;
          onNodes.push_back(v);
        }
      }
      bool any = false;
      for (const auto& e : kEdge) {
        const int a = std::min(input.T(t, e[0]), input.T(t, e[1]));
        const int b = std::max(input.T(t, e[0]), input.T(t, e[1]));
        const auto key = edgeKey(a, b);
        if (edgeIndex.contains(key)) {
          any = true;
          continue;
        }
        if (on[a] || on[b] || !tested.tryEmplace(key, 1).second) continue;
        CutSurface::Hit hit;
        if (!surface.intersectSegment(input.X.row(a).transpose(), input.X.row(b).transpose(), eps, &hit)) continue;
        edgeIndex.tryEmplace(key, static_cast<std::int32_t>(crossed.size()));
        crossed.push_back({a, b, hit.t, hit.point, true});
        crossedNormal.push_back(hit.normal);
        any = true;
      }
      if (any) crossedTets.push_back(t);
    }
    std::sort(onNodes.begin(), onNodes.end());
  }
  report.crossed_edges = static_cast<int>(crossed.size());
  report.crossed_elements = static_cast<int>(crossedTets.size());
  // Crossed edges by end node (CSR): the edges of n that are in edgeIndex.
  std::vector<std::int32_t> crossOff(N0 + 1, 0), crossAt(2 * crossed.size());
  {
    for (const auto& ce : crossed) {
      ++crossOff[ce.a + 1];
      ++crossOff[ce.b + 1];
    }
    for (int i = 0; i < N0; ++i) crossOff[i + 1] += crossOff[i];
    std::vector<std::int32_t> fill(crossOff.begin(), crossOff.end() - 1);
    for (int e = 0; e < static_cast<int>(crossed.size()); ++e) {
      crossAt[fill[crossed[e].a]++] = e;
      crossAt[fill[crossed[e].b]++] = e;
    }
  }
  // Room for what the cut appends (split nodes and their tets, copies), so that the working
  // arrays are not copied as they grow (a guess; they still grow past it if needed).
  Work w(input, 4 * crossed.size() + 64, 12 * crossed.size() + 64);

  // Node -> tets (CSR) of the input mesh, all tets, each list ascending. The steps below look
  // only at the stars within one edge step of the crossed tets and of the nodes on the surface
  // (snap/away/route candidates are ends of crossed edges, feature tests look at their
  // neighbours, subdivision and separation at the crossed tets and the nodes on the cut); the
  // optimisation takes the lists over, patched where the cut changed tets (one O(#T) build
  // for both).
  StarLists stars;
  buildStarLists(input.T, N0, &stars);
  const std::vector<std::int32_t>& starOff = stars.off;
  const StarVector& starTet = stars.star;
  lap(report.classify_ms);

  auto crossingPoint = [&](const CrossedEdge& e) -> Vec3 {
    if (!plane) return e.point;
    const Vec3 xa = w.x(e.a), xb = w.x(e.b);
    return xa + e.t * (xb - xa);
  };

  std::vector<std::int32_t> moved;
  const bool deleting = options.method == CutMethod::Delete;
  std::vector<std::uint8_t> deleted;

  // Moving node n to `target` keeps every tet of its star positive, not flat and not badly
  // degraded (q* below min(before, min_quality)), and every edge of n at least
  // min_edge_fraction of its length.
  // (The conditions are independent, so they are tested cheapest first, and each edge of n
  // once although several tets share it.)
  std::vector<std::uint8_t> guardSeen(N0, 0);
  std::vector<std::int32_t> guardNbrs;
  auto guardOk = [&](int n, const Vec3& target) {
    const Vec3 old = w.x(n);
    for (int s = starOff[n]; s < starOff[n + 1]; ++s) {
      const Tet& tv = w.tet(starTet[s]);
      Vec3 p[4], q[4];
      for (int k = 0; k < 4; ++k) {
        p[k] = w.x(tv[k]);
        q[k] = tv[k] == n ? target : p[k];
      }
      const double v0 = signedVolume(p[0], p[1], p[2], p[3]);
      const double v1 = signedVolume(q[0], q[1], q[2], q[3]);
      if (!(v1 > 1e-3 * v0)) return false;
    }
    guardNbrs.clear();
    bool ok = true;
    for (int s = starOff[n]; s < starOff[n + 1] && ok; ++s)
      for (const int v : w.tet(starTet[s])) {
        if (v == n || guardSeen[v]) continue;
        guardSeen[v] = 1;
        guardNbrs.push_back(v);
        const Vec3& pv = w.x(v);
        if ((pv - target).norm() < options.min_edge_fraction * (pv - old).norm()) {
          ok = false;
          break;
        }
      }
    for (const int v : guardNbrs) guardSeen[v] = 0;
    if (!ok) return false;
    for (int s = starOff[n]; s < starOff[n + 1]; ++s) {
      const Tet& tv = w.tet(starTet[s]);
      Vec3 p[4], q[4];
      for (int k = 0; k < 4; ++k) {
        p[k] = w.x(tv[k]);
        q[k] = tv[k] == n ? target : p[k];
      }
      const double qa = radiusRatio(q[0], q[1], q[2], q[3]);
      if (qa < options.min_quality && qa < radiusRatio(p[0], p[1], p[2], p[3])) return false;
    }
    return true;
  };
  const double cosFeature = std::cos(options.feature_angle_deg * M_PI / 180.0);
  // Boundary faces around n (faces with n used by one tet of its star): the other two nodes
  // and the unit normal.
  struct BFace {
    std::int32_t u, v;
    Vec3 normal;
  };
  // The topology does not change before the subdivision (step 3), where the last call is:
  // the faces found for a node (three corners in the first tet's orientation, and the other
  // two nodes) are kept, and the normals come from the current positions.
  struct BFaceTopo {
    std::int32_t i0, i1, i2, u, v;
  };
  std::vector<std::int32_t> bfStart(N0, -1), bfCount(N0, 0);
  std::vector<BFaceTopo> bfPool;
  struct Seen {
    std::int32_t u, v, i0, i1, i2, count;
  };
  std::vector<Seen> seenFaces;
  std::vector<std::int32_t> bfNbrs, bfLocal(N0, -1), faceAt;
  // The faces go to `out` (cleared first): scratch vectors owned by the callers, so that no
  // call allocates once they have grown.
  auto boundaryFacesOf = [&](int n, std::vector<BFace>& out) {
    if (bfStart[n] < 0 && evenFacePairs(w, n, starOff, starTet)) {
      bfStart[n] = static_cast<std::int32_t>(bfPool.size());  // interior: no boundary face
      bfCount[n] = 0;
    }
    if (bfStart[n] < 0) {
      seenFaces.clear();
      // Local numbers of n's neighbours; faceAt: (pair of them) -> index in seenFaces.
      bfNbrs.clear();
      for (int s = starOff[n]; s < starOff[n + 1]; ++s)
        for (const int v : w.tet(starTet[s]))
          if (v != n && bfLocal[v] < 0) {
            bfLocal[v] = static_cast<std::int32_t>(bfNbrs.size());
            bfNbrs.push_back(v);
          }
      const size_t L = bfNbrs.size();
      if (faceAt.size() < L * L) faceAt.resize(L * L, -1);  // all -1 between calls
      for (int s = starOff[n]; s < starOff[n + 1]; ++s) {
        const Tet tv = w.tet(starTet[s]);
        const int ln = findLocal(tv, n);
        for (int f = 0; f < 4; ++f) {
          if (f == ln) continue;
          const int i0 = tv[kFace[f][0]], i1 = tv[kFace[f][1]], i2 = tv[kFace[f][2]];
          std::int32_t o[2], m = 0;
          for (int v : {i0, i1, i2})
            if (v != n) o[m++] = v;
          if (o[0] > o[1]) std::swap(o[0], o[1]);
          const std::int32_t a = bfLocal[o[0]], b = bfLocal[o[1]];
          std::int32_t& at = faceAt[std::min(a, b) * L + std::max(a, b)];
          if (at >= 0) {
            ++seenFaces[at].count;
          } else {
            at = static_cast<std::int32_t>(seenFaces.size());
            seenFaces.push_back({o[0], o[1], i0, i1, i2, 1});
          }
        }
      }
      for (const auto& q : seenFaces) {
        const std::int32_t a = bfLocal[q.u], b = bfLocal[q.v];
        faceAt[std::min(a, b) * L + std::max(a, b)] = -1;
      }
      for (int v : bfNbrs) bfLocal[v] = -1;
      bfStart[n] = static_cast<std::int32_t>(bfPool.size());
      for (const auto& q : seenFaces)
        if (q.count == 1) bfPool.push_back({q.i0, q.i1, q.i2, q.u, q.v});
      bfCount[n] = static_cast<std::int32_t>(bfPool.size()) - bfStart[n];
    }
    out.clear();
    for (int q = bfStart[n]; q < bfStart[n] + bfCount[n]; ++q) {
      const BFaceTopo& f = bfPool[q];
      out.push_back({f.u, f.v, Vec3((w.x(f.i1) - w.x(f.i0)).cross(w.x(f.i2) - w.x(f.i0))).normalized()});
    }
  };
  std::vector<BFace> candBf, feBf, feBfM;  // scratch: the callers below, featureEdgesOf
  // featureEdgesOf: boundary edges of n (by their other node) with the count of their
  // boundary faces around n and the first two faces' normals.
  struct FeEdge {
    std::int32_t v, count;
    Vec3 normal[2];
  };
  std::vector<FeEdge> feEdges;
  // Feature edges of a boundary node: boundary edges whose two faces meet at more than the
  // feature angle. `straight`: exactly two, nearly straight through n (a ridge node); a node
  // may slide along its feature edges and stays on the feature lines (a corner or a bent
  // ridge only a short way: feature_slide_fraction of the edge, 0 = never). Non-manifold: none.
  struct FeatureEdges {
    std::vector<std::int32_t> to;
    bool straight = false;
    bool polyhedral = false;  // all boundary faces around n in coplanar groups
  };
  auto featureEdgesOf = [&](int n) {
    FeatureEdges fe;
    boundaryFacesOf(n, feBf);
    const std::vector<BFace>& bf = feBf;
    feEdges.clear();
    auto add = [&](std::int32_t v, const Vec3& nrm) {
      for (auto& e : feEdges)
        if (e.v == v) {
          if (e.count < 2) e.normal[e.count] = nrm;
          ++e.count;
          return;
        }
      feEdges.push_back({v, 1, {nrm, Vec3::Zero()}});
    };
    for (const auto& f : bf) {
      add(f.u, f.normal);
      add(f.v, f.normal);
    }
    for (const auto& e : feEdges) {
      if (e.count != 2) return FeatureEdges{};
      if (e.normal[0].dot(e.normal[1]) < cosFeature) fe.to.push_back(e.v);
    }
    if (fe.to.size() == 2) {
      const Vec3 d0 = (w.x(fe.to[0]) - w.x(n)).normalized(), d1 = (w.x(fe.to[1]) - w.x(n)).normalized();
      fe.straight = d0.dot(d1) < -cosFeature;
    }
    // A corner of flat facets (every boundary face around n coplanar with another one, as on
    // a box): sliding it would bend a facet and change the volume, so it does not slide.
    // A face's twin may also be a boundary face of its other two nodes.
    fe.polyhedral = !fe.to.empty();
    for (size_t i = 0; i < bf.size() && fe.polyhedral; ++i) {
      bool twin = false;
      for (size_t j = 0; j < bf.size() && !twin; ++j) twin = j != i && bf[i].normal.dot(bf[j].normal) > 1.0 - 1e-9;
      for (const int m : {bf[i].u, bf[i].v}) {
        if (twin) break;
        boundaryFacesOf(m, feBfM);
        for (const auto& g : feBfM)
          if (g.u != n && g.v != n && bf[i].normal.dot(g.normal) > 1.0 - 1e-9) twin = true;
      }
      fe.polyhedral = twin;
    }
    return fe;
  };

  // 2. Snapping (hybrid / snap only).
  const double region = options.method == CutMethod::Hybrid ? options.snap_region
                        : options.method == CutMethod::Snap ? 0.5
                                                            : 0.0;
  if (region > 0 && !crossed.empty()) {
    const std::vector<EndCandidate> candidates = endCandidates(crossed, region, /*alive_only=*/false);
    std::vector<std::uint8_t> refused(N0, 0);
    for (const auto& cand : candidates) {
      const int n = cand.node;
      if (on[n] || !crossed[cand.edge].alive) continue;
      const CrossedEdge& ce = crossed[cand.edge];
      const int other = ce.a == n ? ce.b : ce.a;
      // Boundary faces around n: faces containing n used by one tet of its star.
      bool boundary = false, feature = false, boundaryEdge = false;
      Vec3 firstNormal = Vec3::Zero();
      Vec3 normalSum = Vec3::Zero();  // mean boundary normal at n (its tangent plane)
      boundaryFacesOf(n, candBf);
      for (const BFace& bf : candBf) {
        if (!boundary) firstNormal = bf.normal;
        normalSum += bf.normal;
        boundary = true;
        if (bf.normal.dot(firstNormal) < cosFeature) feature = true;
        if (bf.u == other || bf.v == other) boundaryEdge = true;
      }
      Vec3 target;
      bool ridgeSnap = false;
      if (boundary) {
        // Boundary nodes stay within the boundary: only where it is flat around them (no
        // feature edge or corner), sliding along the crossed boundary edge, or else within
        // the boundary's tangent plane onto the cut.
        if (feature) {
          // A ridge node slides along a crossed ridge edge (it stays on the feature line).
          bool slid = false;
          if (options.method == CutMethod::Hybrid) {
            const auto fe = featureEdgesOf(n);
            const double reach = fe.straight ? region : fe.polyhedral ? 0.0 : std::min(region, options.feature_slide_fraction);
            for (int r : fe.to) {
              const std::int32_t* it = edgeIndex.find(edgeKey(n, r));
              if (!it) continue;
              const CrossedEdge& re = crossed[*it];
              if (!re.alive || (re.a == n ? re.t : 1.0 - re.t) > reach) continue;
              target = crossingPoint(re);
              slid = true;
              break;
            }
          }
          if (!slid) {
            ++report.feature_skips;
            continue;
          }
          ridgeSnap = true;
        } else if (boundaryEdge) {
          target = crossingPoint(ce);
        } else {
          const Vec3 m = normalSum.normalized();
          // Cut plane near n: the plane itself, or the plane of the hit triangle.
          const Vec3 cn = plane ? surface.planeNormal() : crossedNormal[cand.edge];
          const double dist = plane ? phi[n] : cn.dot(w.x(n) - ce.point);
          const Vec3 d = cn - cn.dot(m) * m;  // steepest direction within the tangent plane
          const double slope = cn.dot(d);
          if (!(slope > 0.25)) {               // cut nearly parallel to the boundary there
            ++report.feature_skips;
            continue;
          }
          target = w.x(n) - (dist / slope) * d;
          // A curved surface: the hit triangle's plane is only good where it is the surface.
          if (!plane && !surface.within(target, 10 * eps)) {
            ++report.feature_skips;
            continue;
          }
        }
      } else if (plane) {
        target = w.x(n) - phi[n] * surface.planeNormal();
      } else {
        target = ce.point;
      }
      // Guard: no inverted, flat or badly degraded tet; no collapsed edge. An interior node
      // refused at the nearest point of the cut tries the crossing on its edge instead.
      bool ok = false;
      for (int attempt = 0; attempt < (boundary ? 1 : 2) && !ok; ++attempt) {
        if (attempt == 1) target = crossingPoint(ce);
        ok = guardOk(n, target);
      }
      if (!ok) {
        if (!refused[n]) ++report.refused_snaps;
        refused[n] = 1;
        continue;
      }
      w.setX(n, target);
      on[n] = 1;
      if (plane) phi[n] = 0;
      onNodes.push_back(n);
      moved.push_back(n);
      ++report.snapped_nodes;
      if (boundary) ++report.boundary_snaps;
      if (ridgeSnap) ++report.ridge_snaps;
      for (int x = crossOff[n]; x < crossOff[n + 1]; ++x) crossed[crossAt[x]].alive = false;
    }
  }

  // 2a. Hybrid, plane: a node not on the cut whose crossed edges are still cut within
  //     away_fraction * |e| of it would leave tiny edges and slivers after the split. It moves
  //     away from the plane instead (interior: along the normal; flat boundary: within its
  //     tangent plane; ridge: along a ridge edge), just far enough that every crossing on its
  //     edges lies at >= away_fraction of the edge; if the guard refuses, at 3/4 or 1/2 of that.
  //     The cut stays exactly the plane: only the crossings move along their edges.
  if (options.method == CutMethod::Hybrid && plane && options.away_fraction > 0 && !crossed.empty()) {
    const double f = std::min(options.away_fraction, 0.45);
    const Vec3 pn = surface.planeNormal().normalized(), pp = surface.planePoint();
    struct Near {
      double frac;
      std::int32_t node;
    };
    std::vector<Near> near;
    for (const auto& c : crossed) {
      if (!c.alive) continue;
      if (c.t < f) near.push_back({c.t, c.a});
      if (1.0 - c.t < f) near.push_back({1.0 - c.t, c.b});
    }
    std::stable_sort(near.begin(), near.end(), [](const Near& x, const Near& y) { return x.frac < y.frac; });
    std::vector<std::uint8_t> tried(N0, 0);
    for (const auto& nr : near) {
      const int n = nr.node;
      if (on[n] || tried[n]) continue;
      tried[n] = 1;
      // |phi| that puts every crossing on n's edges at >= f of the edge.
      double need = 0;
      for (int x = crossOff[n]; x < crossOff[n + 1]; ++x) {
        const CrossedEdge& ce = crossed[crossAt[x]];
        if (ce.alive) need = std::max(need, f / (1.0 - f) * std::abs(phi[ce.a == n ? ce.b : ce.a]));
      }
      const double sgn = phi[n] > 0 ? 1.0 : -1.0;
      const double have = std::abs(phi[n]);
      if (!(need > have)) continue;
      // Direction (unit) and the rate at which |phi| grows along it.
      Vec3 dir;
      double rate, maxStep = std::numeric_limits<double>::infinity();
      boundaryFacesOf(n, candBf);
      const std::vector<BFace>& bf = candBf;
      if (bf.empty()) {
        dir = sgn * pn;
        rate = 1.0;
      } else {
        bool feature = false;
        Vec3 m = Vec3::Zero();
        for (const auto& b : bf) {
          if (b.normal.dot(bf[0].normal) < cosFeature) feature = true;
          m += b.normal;
        }
        if (!feature) {
          m.normalize();
          const Vec3 d = pn - pn.dot(m) * m;  // steepest direction within the tangent plane
          rate = d.norm();
          if (!(rate > 0.25)) continue;  // plane nearly parallel to the boundary there
          dir = sgn * d / rate;
        } else {
          // Along the ridge edge on which |phi| grows fastest, at most half of it.
          rate = 0;
          const auto fe = featureEdgesOf(n);
          for (int r : fe.to) {
            const Vec3 e = w.x(r) - w.x(n);
            const double len = e.norm();
            const double g = sgn * (phi[r] - phi[n]) / len;
            if (on[r] || !(g > rate)) continue;
            rate = g;
            dir = e / len;
            maxStep = (fe.straight ? 0.5 : fe.polyhedral ? 0.0 : options.feature_slide_fraction) * len;
          }
          if (!(rate > 0.25)) continue;
        }
      }
      for (const double level : {1.0, 0.75, 0.5, 0.35, 0.25}) {
        const double want = level * need;
        if (!(want > have)) break;
        const double step = (want - have) / rate;
        if (step > maxStep) continue;
        const Vec3 target = w.x(n) + step * dir;
        if (!guardOk(n, target)) continue;
        w.setX(n, target);
        phi[n] = pn.dot(target - pp);
        for (int x = crossOff[n]; x < crossOff[n + 1]; ++x) {
          CrossedEdge& ce = crossed[crossAt[x]];
          ce.t = phi[ce.a] / (phi[ce.a] - phi[ce.b]);
        }
        moved.push_back(n);
        ++report.away_moves;
        break;
      }
    }
  }

  // 2b. Hybrid: a crossing still within through_node_fraction * |e| of an end node that could
  //     not be snapped (feature/boundary node, refused move) would leave a tiny edge and
  //     slivers. The cut passes through that node instead: it is treated as lying on the
  //     surface and its crossed edges are not split. The cut surface is then approximated
  //     locally, off by at most through_node_fraction * |e| (measured along the edge).
  std::vector<std::uint8_t> approx;  // nodes treated as on the surface without moving
  if (options.method == CutMethod::Hybrid && options.through_node_fraction > 0 && !crossed.empty()) {
    const std::vector<EndCandidate> near =
        endCandidates(crossed, std::nextafter(options.through_node_fraction, 0.0), /*alive_only=*/true);
    for (const auto& nr : near) {
      const int n = nr.node;
      if (on[n] || !crossed[nr.edge].alive) continue;
      if (approx.empty()) approx.assign(N0, 0);
      approx[n] = 1;
      on[n] = 1;
      onNodes.push_back(n);
      ++report.routed_nodes;
      for (int x = crossOff[n]; x < crossOff[n + 1]; ++x) {
        // Edges crossed nearer n than their other end now end on the cut; the others
        // (crossed nearer the other end, which may itself be routed through) stay split.
        CrossedEdge& ce = crossed[crossAt[x]];
        if ((ce.a == n ? ce.t : 1.0 - ce.t) <= 0.5) ce.alive = false;
      }
    }
    // Two routed nodes on opposite sides: their edge is split after all (else one tet would
    // hold both), unless the crossing is too near one of them.
    if (!approx.empty())
      for (auto& ce : crossed)
        if (!ce.alive && approx[ce.a] && approx[ce.b] && ce.t >= options.through_node_fraction &&
            1.0 - ce.t >= options.through_node_fraction)
          ce.alive = true;
    if (!approx.empty())
      for (int n = 0; n < N0; ++n)
        if (approx[n])
          report.max_route_deviation_mm =
              std::max(report.max_route_deviation_mm, std::abs(plane ? phi[n] : surface.signedDistance(w.x(n))));
  }

  lap(report.snap_ms);
  // 3. Subdivision: split every edge still crossed (conforming bisection of the tets around
  //    it), or, for deletion, remove the crossed tets.
  std::vector<std::int32_t> localOf(M0, -1);   // original tet -> index into fragments
  std::vector<std::vector<std::int32_t>> fragments;
  std::vector<std::int32_t> splitOriginals;
  std::vector<NewNode>& newNodes = change.new_nodes;
  if (deleting) {
    deleted.assign(M0, 0);
    for (int t : crossedTets) deleted[t] = 1;
    report.deleted_elements = static_cast<int>(crossedTets.size());
  } else {
    for (auto& ce : crossed) {
      if (!ce.alive) continue;
      const Vec3 p = crossingPoint(ce);
      const int pn = w.addNode(p);
      on.push_back(1);
      NewNode nn;
      nn.id = pn;
      nn.num_parents = 2;
      nn.parents = {ce.a, ce.b, -1};
      nn.weights = {1.0 - ce.t, ce.t, 0.0};
      newNodes.push_back(nn);
      ++report.split_edges;
      for (int s = starOff[ce.a]; s < starOff[ce.a + 1]; ++s) {
        const int o = starTet[s];
        if (findLocal(Tet{input.T(o, 0), input.T(o, 1), input.T(o, 2), input.T(o, 3)}, ce.b) < 0) continue;
        if (localOf[o] < 0) {
          localOf[o] = static_cast<std::int32_t>(fragments.size());
          fragments.push_back({o});
          splitOriginals.push_back(o);
        }
        auto& list = fragments[localOf[o]];
        const size_t count = list.size();
        for (size_t f = 0; f < count; ++f) {
          const int t = list[f];
          Tet tv = w.tet(t);
          const int la = findLocal(tv, ce.a), lb = findLocal(tv, ce.b);
          if (la < 0 || lb < 0) continue;
          Tet other = tv;
          tv[lb] = pn;
          other[la] = pn;
          w.setTet(t, tv);
          list.push_back(w.addTet(other, materialOf(o)));
        }
      }
    }
    report.split_elements = static_cast<int>(splitOriginals.size());
  }

  lap(report.subdivide_ms);
  // 4. Separation. Local tets: the current stars of all nodes on the cut.
  auto isDeleted = [&](int t) { return deleting && t < M0 && deleted[t]; };
  std::vector<std::int32_t> local;
  std::vector<std::uint8_t> inLocal(w.numTets(), 0);
  {
    auto add = [&](int t) {
      if (!inLocal[t] && !isDeleted(t)) {
        inLocal[t] = 1;
        local.push_back(t);
      }
    };
    for (int n : onNodes)
      for (int s = starOff[n]; s < starOff[n + 1]; ++s) {
        const int o = starTet[s];
        if (localOf[o] < 0) {
          add(o);
        } else {
          for (int f : fragments[localOf[o]]) add(f);
        }
      }
    for (const auto& frag : fragments)
      for (int f : frag) add(f);
  }
  struct FaceUse {
    std::int32_t tet[2];
    std::int8_t opposite[2];
    int count = 0;
  };
  FlatMap<FaceKey, FaceUse, FaceFlatHash> onFaces(kNoFace);
  if (options.separate) {
    for (int t : local) {
      const Tet tv = w.tet(t);
      for (int f = 0; f < 4; ++f) {
        const int i0 = tv[kFace[f][0]], i1 = tv[kFace[f][1]], i2 = tv[kFace[f][2]];
        if (!on[i0] || !on[i1] || !on[i2]) continue;
        FaceUse& u = *onFaces.tryEmplace(makeFace(i0, i1, i2), FaceUse{}).first;
        if (u.count < 2) {
          u.tet[u.count] = t;
          u.opposite[u.count] = static_cast<std::int8_t>(f);
        }
        ++u.count;
      }
    }
  }
  std::vector<std::pair<FaceKey, FaceUse>> cutFaceList;
  std::vector<std::pair<std::int32_t, std::int8_t>> cutFaceSides;  // (tet, opposite local vertex)
  // Side of a tet at a face on the cut: the signed distance of the vertex opposite the face
  // (a node treated as on the surface without moving keeps its own small distance).
  // Side of a tet: the sign of the distances of its nodes off the cut (all alike after the
  // subdivision); when every node is on the cut, of the nodes the cut was routed through.
  auto sideOf = [&](int t, int) {
    const Tet tv = w.tet(t);
    double off = 0, routed = 0;
    for (int v : tv) {
      if (v >= N0 || (on[v] && !approx[v])) continue;
      const double d = plane ? phi[v] : surface.signedDistance(w.x(v));
      (on[v] ? routed : off) += d;
    }
    return off != 0 ? off : routed;
  };
  onFaces.forEach([&](const FaceKey& key, const FaceUse& use) {
    if (use.count != 2) return;
    // Only a face between the two sides is cut (with through-node approximation, a face of
    // on-nodes may have both its tets on one side).
    if (!approx.empty() && !(sideOf(use.tet[0], use.opposite[0]) * sideOf(use.tet[1], use.opposite[1]) < 0)) return;
    if (!plane) {
      // The face must lie in the surface, not just have its corners on it.
      const Vec3 a = w.x(key.v[0]), b = w.x(key.v[1]), c = w.x(key.v[2]);
      const double size = std::max({(b - a).norm(), (c - a).norm(), (c - b).norm()});
      const Vec3 centre = (a + b + c) / 3.0;
      if (!surface.within(centre, eps + 0.05 * size)) {
        // On a curved surface a flat face with its corners on the surface lies off it by the
        // sagitta (about size^2 / (8 R)), and a thin tet next to it may lie wholly on the far
        // side of the surface. The face is still on the cut when the surface passes between
        // the two tets there: the segment between their vertices opposite the face (or,
        // where one of those is on the surface, between their centroids) crosses it near
        // the face.
        auto crossesNear = [&](const Vec3& p, const Vec3& q) {
          CutSurface::Hit hit;
          return surface.intersectSegment(p, q, eps, &hit) &&
                 (hit.point - centre).norm() <= std::max(size, (q - p).norm());
        };
        auto centroid = [&](int t) {
          const Tet tv = w.tet(t);
          return Vec3((w.x(tv[0]) + w.x(tv[1]) + w.x(tv[2]) + w.x(tv[3])) / 4.0);
        };
        const int o0 = w.tet(use.tet[0])[use.opposite[0]], o1 = w.tet(use.tet[1])[use.opposite[1]];
        const bool across = (!on[o0] && !on[o1] && crossesNear(w.x(o0), w.x(o1))) ||
                            crossesNear(centroid(use.tet[0]), centroid(use.tet[1]));
        if (!across) return;
      }
    }
    cutFaceList.emplace_back(key, use);
  });
  // Deterministic order for the side records.
  std::sort(cutFaceList.begin(), cutFaceList.end(), [](const auto& x, const auto& y) { return x.first.v < y.first.v; });
  for (const auto& [key, use] : cutFaceList) {
    cutFaceSides.emplace_back(use.tet[0], use.opposite[0]);
    cutFaceSides.emplace_back(use.tet[1], use.opposite[1]);
  }
  report.cut_faces = static_cast<int>(cutFaceList.size());

  std::vector<std::int32_t> cutNodes;
  if (!cutFaceList.empty()) {
    // (Sorted without repeats, as sort + unique, through a bit per node.)
    IndexBits nodeBits(w.numNodes());
    for (const auto& key : cutFaceList)
      for (int v : key.first.v) nodeBits.mark(v);
    nodeBits.drainInto(cutNodes);
    std::vector<std::int32_t> slot(w.numNodes(), -1);
    for (size_t i = 0; i < cutNodes.size(); ++i) slot[cutNodes[i]] = static_cast<std::int32_t>(i);
    // Stars of the cut nodes within the local tets (CSR, each ascending: filled from the
    // local tets in ascending order). One pass over the local tets lists (cut node, tet).
    const size_t numCut = cutNodes.size();
    std::vector<std::int32_t> cutStarOff(numCut + 1, 0), cutStarTet;
    std::vector<std::array<std::int32_t, 2>> incidence;
    incidence.reserve(4 * local.size());
    // (The flags are scanned eight at a time: few tets are local.)
    const int numFlags = static_cast<int>(inLocal.size());
    for (int t = 0; t < numFlags; ++t) {
      if ((t & 7) == 0 && t + 8 <= numFlags) {
        std::uint64_t word;
        std::memcpy(&word, inLocal.data() + t, 8);
        if (word == 0) {
          t += 7;
          continue;
        }
      }
      if (!inLocal[t]) continue;
      for (const int v : w.tet(t)) {
        const std::int32_t sl = slot[v];
        if (sl < 0) continue;
        ++cutStarOff[sl + 1];
        incidence.push_back({sl, t});
      }
    }
    for (size_t i = 0; i < numCut; ++i) cutStarOff[i + 1] += cutStarOff[i];
    cutStarTet.resize(cutStarOff[numCut]);
    {
      std::vector<std::int32_t> fill(cutStarOff.begin(), cutStarOff.end() - 1);
      for (const auto& [sl, t] : incidence) cutStarTet[fill[sl]++] = t;
    }
    std::vector<int> parent, copyOf;
    std::vector<std::int32_t> sepLocal, sepNbrs, firstTet, firstUsed;
    std::vector<std::int8_t> localOfN;
    std::vector<std::array<std::int32_t, 4>> facePairs;  // first tet, tet, opposite local vertex, larger other node
    // Cut faces by tet: bit k of cutMask[t]: the face opposite local vertex k of t is cut.
    std::vector<std::uint8_t> cutMask(w.numTets(), 0);
    for (const auto& [key, use] : cutFaceList)
      for (int side = 0; side < 2; ++side) cutMask[use.tet[side]] |= static_cast<std::uint8_t>(1u << use.opposite[side]);
    const std::int32_t numSep = w.numNodes();
    for (size_t i = 0; i < numCut; ++i) {
      const int n = cutNodes[i];
      const std::span<std::int32_t> st(cutStarTet.data() + cutStarOff[i], cutStarTet.data() + cutStarOff[i + 1]);
      parent.resize(st.size());
      std::iota(parent.begin(), parent.end(), 0);
      auto find = [&](int x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
      };
      // Tets sharing a face with n that is not cut are in one group: faces by the pair of
      // their other two nodes (local numbers over n's neighbours), the first tet seen for each.
      // Local numbers of n's neighbours, given as they are met (at most 3 per tet: stride L).
      if (sepLocal.size() < static_cast<size_t>(w.numNodes())) sepLocal.resize(w.numNodes(), -1);
      sepNbrs.clear();
      const size_t L = 3 * st.size();
      if (firstTet.size() < L * L) firstTet.resize(L * L, -1);  // all -1 between nodes
      // Pass 1: each face occurrence after the first gives a pair (first tet, this tet, the
      // local vertex opposite the face in this tet, the face's other two nodes). Pass 2:
      // pairs not across a cut face are joined.
      firstUsed.resize(3 * st.size());
      facePairs.resize(3 * st.size());
      localOfN.resize(st.size());  // n's local index in each tet of its star
      size_t numPairs = 0;
      for (size_t j = 0, q = 0; j < st.size(); ++j) {
        const Tet& tv = w.tet(st[j]);
        const int ln = findLocal(tv, n);
        localOfN[j] = static_cast<std::int8_t>(ln);
        for (int k = 0; k < 4; ++k)
          if (k != ln && sepLocal[tv[k]] < 0) {
            sepLocal[tv[k]] = static_cast<std::int32_t>(sepNbrs.size());
            sepNbrs.push_back(tv[k]);
          }
        for (const auto& pair : kFacePairs[ln]) {
          const std::int32_t o0 = tv[pair[0]], o1 = tv[pair[1]];
          const std::int32_t a = sepLocal[o0], b = sepLocal[o1];
          const std::int32_t at = static_cast<std::int32_t>(std::min(a, b) * L + std::max(a, b));
          const std::int32_t first = firstTet[at];
          firstTet[at] = first < 0 ? static_cast<std::int32_t>(j) : first;
          firstUsed[q++] = at;
          facePairs[numPairs] = {first, static_cast<std::int32_t>(j), 6 - ln - pair[0] - pair[1], std::max(o0, o1)};
          numPairs += first >= 0 ? 1 : 0;
        }
      }
      for (int v : sepNbrs) sepLocal[v] = -1;
      for (const std::int32_t at : firstUsed) firstTet[at] = -1;
      // A face is cut where this tet's face opposite `opp` was found cut and is still that
      // face: its other two nodes are not copies made since (copies are >= numSep).
      for (size_t q = 0; q < numPairs; ++q) {
        const auto& [first, j, opp, ids] = facePairs[q];
        if (!((cutMask[st[j]] >> opp) & 1) || ids >= numSep) parent[find(first)] = find(j);
      }
      // The group of the first tet keeps n; every other group gets a copy.
      copyOf.assign(st.size(), -1);
      const int keep = find(0);
      for (size_t j = 0; j < st.size(); ++j) {
        const int g = find(static_cast<int>(j));
        if (g == keep) continue;
        if (copyOf[g] < 0) {
          copyOf[g] = w.addNode(w.x(n));
          on.push_back(1);
          NewNode nn;
          nn.id = copyOf[g];
          nn.duplicate = true;
          if (n < N0) {
            nn.num_parents = 1;
            nn.parents = {n, -1, -1};
            nn.weights = {1.0, 0.0, 0.0};
          } else {
            const NewNode& src = newNodes[n - N0];  // split nodes come first, in id order
            nn.num_parents = src.num_parents;
            nn.parents = src.parents;
            nn.weights = src.weights;
          }
          newNodes.push_back(nn);
          cutNodes.push_back(copyOf[g]);
          ++report.duplicated_nodes;
        }
        Tet tv = w.tet(st[j]);
        tv[localOfN[j]] = copyOf[g];
        w.setTet(st[j], tv);
      }
    }
    // The copies were appended in increasing id order, above every node before them: still
    // sorted (the check is cheap; the sort is kept for safety).
    if (!std::is_sorted(cutNodes.begin(), cutNodes.end())) std::sort(cutNodes.begin(), cutNodes.end());
  }
  for (const auto& [t, opp] : cutFaceSides) {
    const Tet tv = w.tet(t);
    change.cut_faces.push_back({tv[kFace[opp][0]], tv[kFace[opp][1]], tv[kFace[opp][2]]});
  }
  const auto cutEnd = std::chrono::steady_clock::now();
  report.cut_ms = std::chrono::duration<double, std::milli>(cutEnd - start).count();
  lap(report.separate_ms, cutEnd);  // (the steps so far add up to cut_ms)

  // Assemble.
  const int N1 = w.numNodes(), M1 = w.numTets();
  // The input arrays (column copies), the rows the cut wrote, then the appended rows.
  out.X.resize(N1, 3);
  out.X.topRows(N0) = input.X;
  for (const int i : w.changedNodes) out.X.row(i) = w.X[i].transpose();
  for (int i = N0; i < N1; ++i) out.X.row(i) = w.X[i].transpose();
  out.T.resize(M1, 4);
  out.T.topRows(M0) = input.T;
  {
    std::int32_t* d[4] = {out.T.col(0).data(), out.T.col(1).data(), out.T.col(2).data(), out.T.col(3).data()};
    for (const int t : w.changedTets)
      for (int k = 0; k < 4; ++k) d[k][t] = w.T[t][k];
    for (int t = M0; t < M1; ++t)
      for (int k = 0; k < 4; ++k) d[k][t] = w.T[t][k];
  }
  out.material.resize(M1);
  if (input.material.size() != 0) {
    out.material.head(M0) = input.material;
  } else {
    out.material.head(M0).setZero();
  }
  for (int t = M0; t < M1; ++t) out.material(t) = w.extraMat[t - M0];

  change.old_num_nodes = N0;
  change.old_num_elements = M0;
  change.node_old_to_new.resize(N0);
  std::iota(change.node_old_to_new.begin(), change.node_old_to_new.end(), 0);
  change.element_old_to_new.resize(M0);
  std::iota(change.element_old_to_new.begin(), change.element_old_to_new.end(), 0);
  {  // (Each split original once: sorted through a bit per tet, as std::sort.)
    IndexBits tetBits(M0);
    for (const int o : splitOriginals) tetBits.mark(o);
    splitOriginals.clear();
    tetBits.drainInto(splitOriginals);
  }
  // Added: the pieces of the split tets, i.e. each split original (its first piece keeps its
  // index) and every appended tet (the subdivision appends nothing else), ascending: the
  // originals (< M0) in order, then M0 .. M1-1.
  change.removed_elements.reserve(splitOriginals.size());
  change.added_elements.reserve(splitOriginals.size() + static_cast<size_t>(M1 - M0));
  for (int o : splitOriginals) {
    change.element_old_to_new[o] = -1;
    change.removed_elements.push_back(o);
    change.added_elements.push_back(o);
  }
  for (int t = M0; t < M1; ++t) change.added_elements.push_back(t);

  lap(report.assemble_ms);
  std::vector<std::uint8_t> peeled;  // #M1: slivers the optimisation removed
  std::vector<MaterialVolume> inputVolumes;  // per label (volume kept)
  // 5. Local optimisation (hybrid), from the nodes the cut created, moved or separated.
  // (Also when the surface split edges but made no cut face, e.g. a sweep's edge grazing the
  // tissue: the splits may leave slivers; then the new nodes are the seeds.)
  if (options.method == CutMethod::Hybrid && options.optimize.enabled && (!cutNodes.empty() || N1 > N0)) {
    const auto optStart = std::chrono::steady_clock::now();
    CutRegion region;
    region.surface = &surface;
    region.eps = eps;
    region.on_cut.assign(on.begin(), on.end());
    region.on_cut.resize(N1, 1);
    region.seeds = cutNodes;
    if (cutNodes.empty())
      for (int i = N0; i < N1; ++i) region.seeds.push_back(i);
    for (const auto& ce : crossed)
      region.edge_length += (input.X.row(ce.a) - input.X.row(ce.b)).norm() / static_cast<double>(crossed.size());
    region.seeds.insert(region.seeds.end(), moved.begin(), moved.end());
    // The input's lists, patched to the output mesh (the rows the cut wrote, the appended
    // tets); the optimisation takes them over.
    patchStarLists(input.T, out.T, N1, std::move(w.changedTets), &stars);
#ifdef HYSIM_CHECK_EXACT
    {
      StarLists full;
      buildStarLists(out.T, N1, &full);
      for (int i = 0; i < N1; ++i) {
        const std::int32_t* b = stars.pool_start[i] >= 0 ? stars.pool.data() + stars.pool_start[i] : stars.star.data() + stars.off[i];
        const size_t len = stars.pool_start[i] >= 0 ? stars.pool_len[i] : stars.off[i + 1] - stars.off[i];
        if (len != static_cast<size_t>(full.off[i + 1] - full.off[i]) || !std::equal(b, b + len, full.star.data() + full.off[i]))
          std::abort();
      }
    }
#endif
    region.stars = &stars;
    inputVolumes = materialVolumes(input);
    region.volume_target = inputVolumes;
    // The pieces cut off (options.anchored_nodes) are left as they are: no seeds there, and
    // their tets are dead to the optimisation (unmarked in `peeled` after it).
    std::vector<std::uint8_t> cutOffTets, cutOffNodes;
    if (options.anchored_nodes != nullptr) {
      IndexBits repositioned(N1);  // nodes the cut made, moved or put on the cut: anchored_at
      for (const int n : moved) repositioned.mark(n);
      for (const int n : cutNodes) repositioned.mark(n);
      const std::vector<std::uint8_t>& flags = *options.anchored_nodes;
      const std::function<bool(int)> anchored = [&](int n) {
        if (n >= N0 || repositioned.has(n))
          return options.anchored_at ? options.anchored_at(out.X.row(n).transpose()) : false;
        return n < static_cast<int>(flags.size()) && flags[n] != 0;
      };
      report.cut_off_pieces = cutOffPieces(out, stars, region.seeds, anchored, options.free_piece_search_limit,
                                           &cutOffTets, &cutOffNodes);
      if (report.cut_off_pieces > 0) {
        region.seeds.erase(std::remove_if(region.seeds.begin(), region.seeds.end(), [&](int n) { return cutOffNodes[n] != 0; }),
                           region.seeds.end());
        region.left_alone = &cutOffTets;
        for (const std::uint8_t f : cutOffTets) report.cut_off_elements += f;
      }
    }
    const size_t before = moved.size();
    OptimizeCounts counts;
    optimizeAroundCut(out, region, options.optimize, &moved, &peeled, &counts);
    if (region.left_alone != nullptr)
      for (size_t t = 0; t < cutOffTets.size(); ++t)
        if (cutOffTets[t]) {
          peeled[t] = 0;
          report.cut_off_volume += tetVolume(out, t);
        }
    report.optimize_iterations = counts.iterations;
    report.peeled_elements = counts.peeled;
    report.flap_peeled = counts.flap_peeled;
    report.collapsed_edges = counts.collapsed;
    report.late_snaps = counts.late_snaps;
    // (cutNodes is sorted: the added nodes sorted and merged in, as a sort of the whole.)
    const auto mid = static_cast<std::ptrdiff_t>(cutNodes.size());
    cutNodes.insert(cutNodes.end(), counts.onto_cut.begin(), counts.onto_cut.end());
    std::sort(cutNodes.begin() + mid, cutNodes.end());
    std::inplace_merge(cutNodes.begin(), cutNodes.begin() + mid, cutNodes.end());
    report.peeled_volume = counts.peeled_volume;
    report.volume_restored = counts.volume_restored;
    report.volume_moves = counts.volume_moves;
    report.optimized_nodes = static_cast<int>(moved.size() - before);
    report.optimize_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - optStart).count();
    report.collapse_ms = counts.collapse_ms;
    report.late_snap_ms = counts.late_snap_ms;
    report.move_ms = counts.move_ms;
  }
  mark = std::chrono::steady_clock::now();  // (the optimisation is optimize_ms)
  {  // (Sorted without repeats, as sort + unique, through a bit per node.)
    IndexBits nodeBits(out.numNodes());
    for (const int n : moved) nodeBits.mark(n);
    moved.clear();
    nodeBits.drainInto(moved);
  }
  // Only surviving old nodes count as moved (new ones are described by new_nodes).
  for (int n : moved)
    if (n < N0) change.moved_nodes.push_back(n);
  change.cut_nodes = cutNodes;

  const bool anyPeeled = std::find(peeled.begin(), peeled.end(), 1) != peeled.end();
  if (deleting || anyPeeled) {
    // Compact: drop deleted and peeled tets and the nodes no longer used.
    std::vector<std::int32_t> drop;  // ascending
    if (deleting) {
      for (int t = 0; t < M1; ++t)
        if ((t < M0 && deleted[t]) || (anyPeeled && peeled[t])) drop.push_back(t);
    } else {
      // Peeled slivers only (few): found by memchr over the flags.
      const std::uint8_t* p = peeled.data();
      for (const std::uint8_t* q = p; (q = static_cast<const std::uint8_t*>(std::memchr(q, 1, p + M1 - q))) != nullptr; ++q)
        drop.push_back(static_cast<std::int32_t>(q - p));
    }
    const int mt = M1 - static_cast<int>(drop.size());
    // tetMap: kept tets in runs between the dropped ones, each shifted down by the number of
    // dropped tets before it. (Every entry is written: no zero fill first.)
    const auto tetMap = std::make_unique_for_overwrite<std::int32_t[]>(static_cast<size_t>(M1));
    {
      std::int32_t* m = tetMap.get();
      int src = 0;
      for (size_t g = 0; g <= drop.size(); ++g) {
        const int end = g < drop.size() ? drop[g] : M1;
        const std::int32_t shift = static_cast<std::int32_t>(g);
        for (int t = src; t < end; ++t) m[t] = t - shift;
        if (end < M1) m[end] = -1;
        src = end + 1;
      }
    }
    // Uses of each node by the kept tets (all uses minus those of the dropped tets): a node
    // no kept tet uses goes.
    std::vector<std::int32_t> nodeMap(N1, -1);
    {
      std::int32_t* u = nodeMap.data();
      const std::int32_t *c0 = out.T.col(0).data(), *c1 = out.T.col(1).data(), *c2 = out.T.col(2).data(),
                         *c3 = out.T.col(3).data();
      for (int t = 0; t < M1; ++t) {  // from -1: uses - 1
        ++u[c0[t]];
        ++u[c1[t]];
        ++u[c2[t]];
        ++u[c3[t]];
      }
      for (const int t : drop) {
        --u[c0[t]];
        --u[c1[t]];
        --u[c2[t]];
        --u[c3[t]];
      }
    }
    // Kept nodes numbered in order; the others (ascending) go.
    int mn = 0;
    std::vector<std::int32_t> gone;
    for (int i = 0; i < N1; ++i) {
      if (nodeMap[i] >= 0) {
        nodeMap[i] = mn++;
      } else {
        nodeMap[i] = -1;
        gone.push_back(i);
      }
    }
    // Kept rows in runs between the dropped tets (nodes likewise).
    auto keepRows = [](const auto& from, auto& to, const std::vector<std::int32_t>& gaps) {
      Eigen::Index src = 0, dst = 0;
      for (size_t g = 0; g <= gaps.size(); ++g) {
        const Eigen::Index end = g < gaps.size() ? gaps[g] : from.rows();
        if (end > src) to.middleRows(dst, end - src) = from.middleRows(src, end - src);
        dst += end - src;
        src = end + 1;
      }
    };
    TetMesh compact;
    compact.T.resize(mt, 4);
    compact.material.resize(mt);
    keepRows(out.material, compact.material, drop);
    if (mn == N1) {
      keepRows(out.T, compact.T, drop);
      compact.X = std::move(out.X);
    } else {
      compact.X.resize(mn, 3);
      keepRows(out.X, compact.X, gone);
      // The kept tets' rows, renumbered as they are copied.
      const std::int32_t* map = nodeMap.data();
      for (int k = 0; k < 4; ++k) {
        const std::int32_t* from = out.T.col(k).data();
        std::int32_t* to = compact.T.col(k).data();
        int src = 0, dst = 0;
        for (size_t g = 0; g <= drop.size(); ++g) {
          const int end = g < drop.size() ? drop[g] : M1;
          for (int t = src; t < end; ++t) to[dst++] = map[from[t]];
          src = end + 1;
        }
      }
    }
    out = std::move(compact);
    std::copy(nodeMap.begin(), nodeMap.begin() + N0, change.node_old_to_new.begin());
    // Old tets: each is its own index or -1 (split) so far; kept ones shift down with tetMap
    // (in runs), dropped ones go.
    {
      std::int32_t* e = change.element_old_to_new.data();
      int src = 0;
      for (size_t g = 0; g <= drop.size() && src < M0; ++g) {
        const int end = g < drop.size() ? std::min(drop[g], M0) : M0;
        const std::int32_t shift = static_cast<std::int32_t>(g);
        for (int t = src; t < end; ++t) e[t] = e[t] >= 0 ? t - shift : -1;
        if (end < M0) {
          if (e[end] >= 0) change.removed_elements.push_back(end);
          e[end] = -1;
        }
        src = end + 1;
      }
    }
    std::sort(change.removed_elements.begin(), change.removed_elements.end());
    auto remapList = [&](std::vector<std::int32_t>& list, const std::int32_t* map) {
      std::vector<std::int32_t> kept;
      for (int n : list)
        if (map[n] >= 0) kept.push_back(map[n]);
      list = kept;
    };
    remapList(change.cut_nodes, nodeMap.data());
    remapList(change.moved_nodes, nodeMap.data());
    remapList(change.added_elements, tetMap.get());
    for (auto& nn : change.new_nodes) nn.id = nodeMap[nn.id];
    change.new_nodes.erase(std::remove_if(change.new_nodes.begin(), change.new_nodes.end(),
                                          [](const NewNode& nn) { return nn.id < 0; }),
                           change.new_nodes.end());
    std::vector<std::array<std::int32_t, 3>> faces;
    for (auto f : change.cut_faces) {
      bool keep = true;
      for (auto& v : f) {
        v = nodeMap[v];
        keep = keep && v >= 0;
      }
      if (keep) faces.push_back(f);
    }
    change.cut_faces = faces;
  }
  change.new_num_nodes = out.numNodes();
  change.new_num_elements = out.numTets();
  lap(report.compact_ms);
  // Volume kept: every tet of the input and the output, per material.
  if (inputVolumes.empty()) inputVolumes = materialVolumes(input);
  addVolumesAfter(out, &inputVolumes);
  report.material_volumes = std::move(inputVolumes);
  for (const MaterialVolume& m : report.material_volumes) {
    report.volume_before += m.before;
    report.volume_after += m.after;
  }
  report.volume_drift = report.volume_before - report.volume_after;
  return result;
}

Components3D tetComponents(const TetMesh& mesh, const std::vector<int>& anchored) {
  Components3D c;
  const int M = std::max(0, mesh.numTets());
  c.label = Eigen::VectorXi::Constant(M, -1);
  // Faces sorted by key; equal neighbours share a face.
  struct F {
    std::array<std::int32_t, 3> v;
    std::int32_t tet;
  };
  std::vector<F> faces;
  faces.reserve(4 * static_cast<size_t>(M));
  for (int t = 0; t < M; ++t)
    for (int f = 0; f < 4; ++f) {
      FaceKey k = makeFace(mesh.T(t, kFace[f][0]), mesh.T(t, kFace[f][1]), mesh.T(t, kFace[f][2]));
      faces.push_back({k.v, t});
    }
  std::sort(faces.begin(), faces.end(), [](const F& x, const F& y) { return x.v < y.v; });
  std::vector<int> parent(static_cast<size_t>(M));
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (size_t i = 0; i + 1 < faces.size(); ++i)
    if (faces[i].v == faces[i + 1].v) parent[find(faces[i].tet)] = find(faces[i + 1].tet);
  std::vector<int> id(static_cast<size_t>(M), -1);
  for (int t = 0; t < M; ++t) {
    const int r = find(t);
    if (id[r] < 0) {
      id[r] = c.count++;
      c.volume.push_back(0.0);
      c.elements.push_back(0);
    }
    c.label(t) = id[r];
    c.volume[id[r]] += tetVolume(mesh, t);
    ++c.elements[id[r]];
  }
  c.free.assign(c.count, true);
  std::vector<std::uint8_t> isAnchored(mesh.numNodes(), 0);
  for (int n : anchored)
    if (n >= 0 && n < mesh.numNodes()) isAnchored[n] = 1;
  for (int t = 0; t < M; ++t)
    for (int k = 0; k < 4; ++k)
      if (isAnchored[mesh.T(t, k)]) c.free[c.label(t)] = false;
  return c;
}

int countStraddling(const TetMesh& mesh, const Eigen::Vector3d& point, const Eigen::Vector3d& normal, double eps) {
  const Vec3 n = normal.normalized();
  int count = 0;
  for (int t = 0; t < mesh.numTets(); ++t) {
    bool pos = false, neg = false;
    for (int k = 0; k < 4; ++k) {
      const double f = n.dot(mesh.X.row(mesh.T(t, k)).transpose() - point);
      pos = pos || f > eps;
      neg = neg || f < -eps;
    }
    if (pos && neg) ++count;
  }
  return count;
}

int countFacesSharedAcross(const TetMesh& mesh, const Eigen::Vector3d& point, const Eigen::Vector3d& normal,
                           double eps) {
  const Vec3 n = normal.normalized();
  auto tetSide = [&](int t) {
    double best = 0;
    for (int k = 0; k < 4; ++k) {
      const double f = n.dot(mesh.X.row(mesh.T(t, k)).transpose() - point);
      if (std::abs(f) > std::abs(best)) best = f;
    }
    return best > eps ? 1 : best < -eps ? -1 : 0;
  };
  std::unordered_map<FaceKey, int, FaceKeyHash> owner;
  int count = 0;
  for (int t = 0; t < mesh.numTets(); ++t)
    for (int f = 0; f < 4; ++f) {
      const FaceKey k = makeFace(mesh.T(t, kFace[f][0]), mesh.T(t, kFace[f][1]), mesh.T(t, kFace[f][2]));
      auto [it, inserted] = owner.emplace(k, t);
      if (!inserted && tetSide(it->second) * tetSide(t) < 0) ++count;
    }
  return count;
}

}  // namespace hysim::cutting
