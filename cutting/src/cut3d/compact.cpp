// Stage 7, compaction: deleted and peeled tets and the nodes no longer used go; the change
// lists are renumbered.
#include <algorithm>
#include <cstring>
#include <memory>

#include "cut3d_stages.hpp"

namespace hysim::cutting::cut3d_detail {

namespace {

// Kept rows in runs between the dropped ones (`gaps`, ascending).
template <class From, class To>
void keepRows(const From& from, To& to, const std::vector<std::int32_t>& gaps) {
  Eigen::Index src = 0, dst = 0;
  for (size_t g = 0; g <= gaps.size(); ++g) {
    const Eigen::Index end = g < gaps.size() ? gaps[g] : from.rows();
    if (end > src) to.middleRows(dst, end - src) = from.middleRows(src, end - src);
    dst += end - src;
    src = end + 1;
  }
}

// Kept tets in runs between the dropped ones, each shifted down by the number of dropped tets
// before it. (Every entry is written: no zero fill first.)
std::unique_ptr<std::int32_t[]> tetMapOf(const std::vector<std::int32_t>& drop, int M1) {
  auto tetMap = std::make_unique_for_overwrite<std::int32_t[]>(static_cast<size_t>(M1));
  std::int32_t* m = tetMap.get();
  int src = 0;
  for (size_t g = 0; g <= drop.size(); ++g) {
    const int end = g < drop.size() ? drop[g] : M1;
    const std::int32_t shift = static_cast<std::int32_t>(g);
    for (int t = src; t < end; ++t) m[t] = t - shift;
    if (end < M1) m[end] = -1;
    src = end + 1;
  }
  return tetMap;
}

// Kept nodes numbered in order, the others -1 (listed in *gone, ascending): a node no kept
// tet uses goes (all uses minus those of the dropped tets).
std::vector<std::int32_t> nodeMapOf(const Tets& T, int M1, int N1, const std::vector<std::int32_t>& drop,
                                    std::vector<std::int32_t>* gone) {
  std::vector<std::int32_t> nodeMap(N1, -1);
  std::int32_t* u = nodeMap.data();
  const std::int32_t *c0 = T.col(0).data(), *c1 = T.col(1).data(), *c2 = T.col(2).data(), *c3 = T.col(3).data();
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
  int mn = 0;
  for (int i = 0; i < N1; ++i) {
    if (nodeMap[i] >= 0) {
      nodeMap[i] = mn++;
    } else {
      nodeMap[i] = -1;
      gone->push_back(i);
    }
  }
  return nodeMap;
}

void remapList(std::vector<std::int32_t>& list, const std::int32_t* map) {
  std::vector<std::int32_t> kept;
  for (int n : list)
    if (map[n] >= 0) kept.push_back(map[n]);
  list = kept;
}

}  // namespace

void Cut3D::compact() {
  listMoved();
  const bool anyPeeled = std::find(peeled.begin(), peeled.end(), 1) != peeled.end();
  if (deleting || anyPeeled) compactMesh(droppedTets(anyPeeled));
  result.change.new_num_nodes = result.mesh.numNodes();
  result.change.new_num_elements = result.mesh.numTets();
  lap(result.report.compact_ms);
}

// Only surviving old nodes count as moved (new ones are described by new_nodes).
void Cut3D::listMoved() {
  {  // (Sorted without repeats, as sort + unique, through a bit per node.)
    IndexBits nodeBits(result.mesh.numNodes());
    for (const int n : moved) nodeBits.mark(n);
    moved.clear();
    nodeBits.drainInto(moved);
  }
  for (int n : moved)
    if (n < N0) result.change.moved_nodes.push_back(n);
  result.change.cut_nodes = cutNodes;
}

// Deleted and peeled tets, ascending.
std::vector<std::int32_t> Cut3D::droppedTets(bool anyPeeled) const {
  std::vector<std::int32_t> drop;
  if (deleting) {
    for (int t = 0; t < M1; ++t)
      if ((t < M0 && deleted[t]) || (anyPeeled && peeled[t])) drop.push_back(t);
  } else {
    // Peeled slivers only (few): found by memchr over the flags.
    const std::uint8_t* p = peeled.data();
    for (const std::uint8_t* q = p; (q = static_cast<const std::uint8_t*>(std::memchr(q, 1, p + M1 - q))) != nullptr; ++q)
      drop.push_back(static_cast<std::int32_t>(q - p));
  }
  return drop;
}

void Cut3D::compactMesh(const std::vector<std::int32_t>& drop) {
  TetMesh& out = result.mesh;
  const int mt = M1 - static_cast<int>(drop.size());
  const auto tetMap = tetMapOf(drop, M1);
  std::vector<std::int32_t> gone;
  const std::vector<std::int32_t> nodeMap = nodeMapOf(out.T, M1, N1, drop, &gone);
  const int mn = N1 - static_cast<int>(gone.size());
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
  remapChange(drop, nodeMap, tetMap.get());
}

void Cut3D::remapChange(const std::vector<std::int32_t>& drop, const std::vector<std::int32_t>& nodeMap,
                        const std::int32_t* tetMap) {
  TopologyChange& change = result.change;
  std::copy(nodeMap.begin(), nodeMap.begin() + N0, change.node_old_to_new.begin());
  // Old tets: each is its own index or -1 (split) so far; kept ones shift down with tetMap
  // (in runs), dropped ones go.
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
  std::sort(change.removed_elements.begin(), change.removed_elements.end());
  remapList(change.cut_nodes, nodeMap.data());
  remapList(change.moved_nodes, nodeMap.data());
  remapList(change.added_elements, tetMap);
  for (auto& nn : change.new_nodes) nn.id = nodeMap[nn.id];
  change.new_nodes.erase(
      std::remove_if(change.new_nodes.begin(), change.new_nodes.end(), [](const NewNode& nn) { return nn.id < 0; }),
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

}  // namespace hysim::cutting::cut3d_detail
