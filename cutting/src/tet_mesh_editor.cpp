// TetMeshEditor: construction, stars and the quality cache (the primitives the optimiser
// uses); the checked operations are in tet_mesh_editor_ops.cpp.
#include "hysim/cutting/tet_mesh_editor.hpp"

#include <algorithm>
#include <cstdlib>
#include <functional>
#include <iterator>

#include "hysim/cutting/mesh_stats.hpp"
#include "tet_geometry_inline.hpp"

namespace hysim::cutting {
TetMeshEditor::TetMeshEditor(TetMesh& mesh, std::vector<std::uint8_t>& dead, StarLists* stars)
    : mesh_(mesh), dead_(dead) {
  const int N = mesh.numNodes(), M = mesh.numTets();
  if (dead_.size() != static_cast<size_t>(M)) dead_.assign(M, 0);
  touched_.assign(N, 0);
  nodeVer_.assign(N, 0);
  qSlot_.assign(M, -1);
  qPool_.resize(static_cast<size_t>(M));
  change_.old_num_nodes = N;
  change_.old_num_elements = M;
  if (stars != nullptr) {
    off_.swap(stars->off);
    star_.swap(stars->star);
    poolStart_.swap(stars->pool_start);
    poolLen_.swap(stars->pool_len);
    pool_.swap(stars->pool);
  } else {
    buildAllStars();
  }
}

void TetMeshEditor::buildAllStars() {
  const int N = numNodes(), M = numTets();
  off_.assign(N + 1, 0);
  star_.resize(4 * static_cast<size_t>(M));
  poolStart_.assign(N, -1);
  poolLen_.assign(N, 0);
  pool_.clear();
  for (int t = 0; t < M; ++t)
    if (!dead_[t])
      for (int k = 0; k < 4; ++k) ++off_[mesh_.T(t, k) + 1];
  for (int i = 0; i < N; ++i) off_[i + 1] += off_[i];
  std::vector<std::int32_t> fill(off_.begin(), off_.end() - 1);
  for (int t = 0; t < M; ++t)
    if (!dead_[t])
      for (int k = 0; k < 4; ++k) star_[fill[mesh_.T(t, k)]++] = t;
}

void TetMeshEditor::refreshStars() {
  // The same lists as a full rebuild: live tets with the node, in index order.
  std::sort(gained_.begin(), gained_.end());
  for (int n : touchedList_) {
    scratch_.assign(starBegin(n), starEnd(n));
    auto g = std::lower_bound(gained_.begin(), gained_.end(),
                              std::make_pair(static_cast<std::int32_t>(n), std::int32_t{-1}));
    // (Both runs are sorted, the gained tets as `gained_` is: merged, as a sort of the whole.)
    if (g != gained_.end() && g->first == n) {
      const size_t mid = scratch_.size();
      for (; g != gained_.end() && g->first == n; ++g) scratch_.push_back(g->second);
      mergeSortedRuns(scratch_, mid, scratch2_);
    }
#ifdef HYSIM_CHECK_EXACT
    if (std::adjacent_find(scratch_.begin(), scratch_.end(), std::greater_equal<std::int32_t>()) != scratch_.end())
      std::abort();
#endif
    poolStart_[n] = static_cast<std::int32_t>(pool_.size());
    for (int t : scratch_) {
      if (dead_[t]) continue;
      bool has = false;
      for (int k = 0; k < 4; ++k) has = has || mesh_.T(t, k) == n;
      if (has) pool_.push_back(t);
    }
    poolLen_[n] = static_cast<std::int32_t>(pool_.size()) - poolStart_[n];
    touched_[n] = 0;
  }
  touchedList_.clear();
  gained_.clear();
}

void TetMeshEditor::liveStar(int v, std::vector<std::int32_t>& out, const std::vector<std::int32_t>* extra) const {
  out.clear();
  for (const std::int32_t *s = starBegin(v), *sEnd = starEnd(v); s < sEnd; ++s)
    if (!dead_[*s]) out.push_back(*s);
  if (extra)
    for (int t : *extra)
      if (!dead_[t]) out.push_back(t);
}

void TetMeshEditor::setTetNodes(int t, int a, int b, int c, int d) {
  ++topoClock_;
  const int v[4] = {a, b, c, d};
  for (int k = 0; k < 4; ++k) {
    touch(mesh_.T(t, k));
    mesh_.T(t, k) = v[k];
    touch(v[k]);
    gained_.emplace_back(v[k], t);
  }
}

TetMeshEditor::QEntry TetMeshEditor::keyOf(int t) const {
  QEntry key;
  for (int k = 0; k < 4; ++k) {
    key.v[k] = mesh_.T(t, k);
    key.ver[k] = nodeVer_[key.v[k]];
  }
  return key;
}

TetMeshEditor::QEntry* TetMeshEditor::cached(int t, const QEntry& key) {
  const std::int32_t slot = qSlot_[t];
  if (slot < 0) return nullptr;
  QEntry& e = qPool_[slot];
  return std::equal(key.v, key.v + 4, e.v) && std::equal(key.ver, key.ver + 4, e.ver) ? &e : nullptr;
}

double TetMeshEditor::store(int t, QEntry entry, std::int8_t up) {
  if (qSlot_[t] < 0) qSlot_[t] = qNext_++;
  entry.q = radiusRatio(position(entry.v[0]), position(entry.v[1]), position(entry.v[2]), position(entry.v[3]));
  entry.up = up;
  qPool_[qSlot_[t]] = entry;
  return entry.q;
}

double TetMeshEditor::quality(int t) {
  const QEntry key = keyOf(t);
  if (const QEntry* e = cached(t, key)) return e->q;
  return store(t, key, -1);
}

double TetMeshEditor::qualityIfPositive(int t) {
  const QEntry key = keyOf(t);
  if (QEntry* e = cached(t, key)) {
    if (e->up < 0) e->up = tetVolume6Here(mesh_, t) > 0 ? 1 : 0;
    return e->up ? e->q : -1.0;
  }
  if (!(tetVolume6Here(mesh_, t) > 0)) return -1.0;
  return store(t, key, 1);
}

double TetMeshEditor::qualityWith(int t, int n, const Vec3& y) const {
  // (The corners passed directly, n's replaced by y: the same values as a copy.)
  const int a = mesh_.T(t, 0), b = mesh_.T(t, 1), c = mesh_.T(t, 2), d = mesh_.T(t, 3);
  if (a == n) return radiusRatioOriented(y, position(b), position(c), position(d));
  if (b == n) return radiusRatioOriented(position(a), y, position(c), position(d));
  if (c == n) return radiusRatioOriented(position(a), position(b), y, position(d));
  if (d == n) return radiusRatioOriented(position(a), position(b), position(c), y);
  return radiusRatioOriented(position(a), position(b), position(c), position(d));
}

double TetMeshEditor::worstAround(int n, int* worstTet) {
  double q = 1.0;
  for (const std::int32_t *s = starBegin(n), *sEnd = starEnd(n); s < sEnd; ++s) {
    const int t = *s;
    if (dead_[t]) continue;
    const double qt = qualityIfPositive(t);
    if (qt < q) {
      q = qt;
      if (worstTet) *worstTet = t;
      if (qt < 0) return qt;
    }
  }
  return q;
}

}  // namespace hysim::cutting
