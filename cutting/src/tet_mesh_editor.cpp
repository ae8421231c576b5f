// TetMeshEditor: construction, stars and the quality cache (the primitives the optimiser
// uses); the checked operations are in tet_mesh_editor_ops.cpp.
#include "hysim/cutting/tet_mesh_editor.hpp"

#include <algorithm>
#include <cstdlib>
#include <functional>
#include <iterator>

#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::cutting {
namespace {

// v[0, mid) and v[mid, end), each sorted, into one sorted list without repeats.
void mergeRuns(std::vector<std::int32_t>& v, size_t mid, std::vector<std::int32_t>& scratch) {
  scratch.clear();
  const auto m = v.begin() + static_cast<std::ptrdiff_t>(mid);
  std::merge(v.begin(), m, m, v.end(), std::back_inserter(scratch));
  scratch.erase(std::unique(scratch.begin(), scratch.end()), scratch.end());
  v.swap(scratch);
}

}  // namespace

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
      mergeRuns(scratch_, mid, scratch2_);
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

double TetMeshEditor::quality(int t) {
  QEntry cur;
  for (int k = 0; k < 4; ++k) {
    cur.v[k] = mesh_.T(t, k);
    cur.ver[k] = nodeVer_[cur.v[k]];
  }
  std::int32_t& slot = qSlot_[t];
  if (slot >= 0) {
    const QEntry& e = qPool_[slot];
    if (std::equal(cur.v, cur.v + 4, e.v) && std::equal(cur.ver, cur.ver + 4, e.ver)) return e.q;
  } else {
    slot = qNext_++;
  }
  cur.q = radiusRatio(position(cur.v[0]), position(cur.v[1]), position(cur.v[2]), position(cur.v[3]));
  cur.up = -1;
  qPool_[slot] = cur;
  return cur.q;
}

namespace {
// Six times tetVolume, in scalars over the coordinate columns (the same value as
// (x1 - x0).dot((x2 - x0).cross(x3 - x0))).
inline double volume6(const TetMesh& mesh, int t) {
  const double* cx = mesh.X.col(0).data();
  const double* cy = mesh.X.col(1).data();
  const double* cz = mesh.X.col(2).data();
  const int i0 = mesh.T(t, 0), i1 = mesh.T(t, 1), i2 = mesh.T(t, 2), i3 = mesh.T(t, 3);
  const double ax = cx[i1] - cx[i0], ay = cy[i1] - cy[i0], az = cz[i1] - cz[i0];
  const double bx = cx[i2] - cx[i0], by = cy[i2] - cy[i0], bz = cz[i2] - cz[i0];
  const double ex = cx[i3] - cx[i0], ey = cy[i3] - cy[i0], ez = cz[i3] - cz[i0];
  const double nx = by * ez - bz * ey, ny = bz * ex - bx * ez, nz = bx * ey - by * ex;
  return (ax * nx + ay * ny) + az * nz;
}
}  // namespace

double TetMeshEditor::qualityIfPositive(int t) {
  QEntry cur;
  for (int k = 0; k < 4; ++k) {
    cur.v[k] = mesh_.T(t, k);
    cur.ver[k] = nodeVer_[cur.v[k]];
  }
  std::int32_t& slot = qSlot_[t];
  if (slot >= 0) {
    QEntry& e = qPool_[slot];
    if (std::equal(cur.v, cur.v + 4, e.v) && std::equal(cur.ver, cur.ver + 4, e.ver)) {
      if (e.up < 0) e.up = volume6(mesh_, t) > 0 ? 1 : 0;
      return e.up ? e.q : -1.0;
    }
  }
  if (!(volume6(mesh_, t) > 0)) return -1.0;
  if (slot < 0) slot = qNext_++;
  cur.q = radiusRatio(position(cur.v[0]), position(cur.v[1]), position(cur.v[2]), position(cur.v[3]));
  cur.up = 1;
  qPool_[slot] = cur;
  return cur.q;
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
