// TetMeshEditor: compact() (drop dead tets and unused nodes, complete the TopologyChange) and
// validate() (everything the editor keeps agrees with the mesh).
#include <algorithm>
#include <cstring>
#include <string>

#include "hysim/cutting/mesh_stats.hpp"
#include "hysim/cutting/tet_mesh_editor.hpp"

namespace hysim::cutting {

void TetMeshEditor::compact() {
  ensureTracking();
  refreshStars();
  const int N = numNodes(), M = numTets();
  std::vector<std::int32_t> newNode(N, -1), newTet(M, -1);
  int liveTets = 0;
  for (int t = 0; t < M; ++t)
    if (!dead_[t]) {
      newTet[t] = liveTets++;
      for (int k = 0; k < 4; ++k) newNode[mesh_.T(t, k)] = 0;
    }
  int liveNodes = 0;
  for (int n = 0; n < N; ++n)
    if (newNode[n] == 0) newNode[n] = liveNodes++;
  fillChange(newNode, newTet, liveNodes, liveTets);
  TetMesh out;
  out.X.resize(liveNodes, 3);
  out.T.resize(liveTets, 4);
  out.material.resize(liveTets);
  for (int n = 0; n < N; ++n)
    if (newNode[n] >= 0) out.X.row(newNode[n]) = mesh_.X.row(n);
  std::vector<std::int32_t> origin(liveTets, -1);
  for (int t = 0; t < M; ++t) {
    if (newTet[t] < 0) continue;
    for (int k = 0; k < 4; ++k) out.T(newTet[t], k) = newNode[mesh_.T(t, k)];
    out.material(newTet[t]) = mesh_.material(t);
    origin[newTet[t]] = tetOrigin_[t];
  }
  mesh_ = std::move(out);
  // The editor goes on over the compacted mesh: its own numbering from here.
  dead_.assign(liveTets, 0);
  killed_.clear();
  touched_.assign(liveNodes, 0);
  touchedList_.clear();
  gained_.clear();
  nodeVer_.assign(liveNodes, 0);
  verClock_ = 0;
  qSlot_.assign(liveTets, -1);
  qPool_.resize(static_cast<size_t>(liveTets));
  qNext_ = 0;
  ++topoClock_;
  buildAllStars();
  tracking_ = false;
}

// The TopologyChange from the construction's mesh to the compacted one (newNode / newTet: the
// current indices' places after compaction, -1 where dropped).
void TetMeshEditor::fillChange(const std::vector<std::int32_t>& newNode, const std::vector<std::int32_t>& newTet,
                               int liveNodes, int liveTets) {
  TopologyChange& c = change_;
  c.new_num_nodes = liveNodes;
  c.new_num_elements = liveTets;
  c.node_old_to_new.assign(c.old_num_nodes, -1);
  c.moved_nodes.clear();
  for (int n = 0; n < numNodes(); ++n) {
    if (nodeOrigin_[n] < 0) continue;
    int to = n;  // a node merged away maps to the node it was merged into
    for (int hops = 0; mergedInto_[to] >= 0 && hops < numNodes(); ++hops) to = mergedInto_[to];
    c.node_old_to_new[nodeOrigin_[n]] = newNode[to];
    if (movedFlag_[n] && newNode[n] >= 0) c.moved_nodes.push_back(newNode[n]);
  }
  std::sort(c.moved_nodes.begin(), c.moved_nodes.end());
  c.element_old_to_new.assign(c.old_num_elements, -1);
  c.added_elements.clear();
  for (int t = 0; t < numTets(); ++t) {
    if (newTet[t] < 0) continue;
    if (tetOrigin_[t] >= 0) {
      c.element_old_to_new[tetOrigin_[t]] = newTet[t];
    } else {
      c.added_elements.push_back(newTet[t]);
    }
  }
  std::sort(c.added_elements.begin(), c.added_elements.end());
  c.removed_elements.clear();
  for (int j = 0; j < c.old_num_elements; ++j)
    if (c.element_old_to_new[j] < 0) c.removed_elements.push_back(j);
  c.new_nodes.clear();
  for (NewNode nn : newNodes_) {
    if (newNode[nn.id] < 0) continue;
    nn.id = newNode[nn.id];
    c.new_nodes.push_back(nn);
  }
  std::sort(c.new_nodes.begin(), c.new_nodes.end(), [](const NewNode& a, const NewNode& b) { return a.id < b.id; });
}

Status TetMeshEditor::validate() const {
  const int N = numNodes(), M = numTets();
  if (dead_.size() != static_cast<size_t>(M)) return Error{"editor: dead flags sized " + std::to_string(dead_.size())};
  if (starsPending()) return Error{"editor: stars not refreshed"};
  TetMesh live;
  live.X = mesh_.X;
  int count = 0;
  for (int t = 0; t < M; ++t) count += dead_[t] ? 0 : 1;
  live.T.resize(count, 4);
  live.material.resize(count);
  std::vector<std::vector<std::int32_t>> expect(N);
  for (int t = 0, r = 0; t < M; ++t) {
    if (dead_[t]) continue;
    live.T.row(r) = mesh_.T.row(t);
    live.material(r++) = mesh_.material(t);
    for (int k = 0; k < 4; ++k) {
      const int n = mesh_.T(t, k);
      if (n < 0 || n >= N) return Error{"editor: tet " + std::to_string(t) + " has node " + std::to_string(n)};
      expect[n].push_back(t);
    }
  }
  if (const Status s = cutting::validate(live); !s.ok()) return Error{"editor: " + s.error()};
  for (int n = 0; n < N; ++n)
    if (!std::equal(starBegin(n), starEnd(n), expect[n].begin(), expect[n].end()))
      return Error{"editor: star of node " + std::to_string(n) + " differs from its live tets"};
  for (int t = 0; t < M; ++t) {
    if (qSlot_[t] < 0) continue;
    const QEntry& e = qPool_[qSlot_[t]];
    bool current = true;
    for (int k = 0; k < 4; ++k) current = current && e.v[k] == mesh_.T(t, k) && e.ver[k] == nodeVer_[e.v[k]];
    if (!current) continue;
    const double q = radiusRatio(position(e.v[0]), position(e.v[1]), position(e.v[2]), position(e.v[3]));
    if (std::memcmp(&q, &e.q, sizeof q) != 0) return Error{"editor: cached quality of tet " + std::to_string(t)};
  }
  return Status::Ok();
}

}  // namespace hysim::cutting
