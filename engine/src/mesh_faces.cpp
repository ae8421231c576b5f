#include "hysim/engine/mesh_faces.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

namespace hysim::engine {


bool updateFaces(const cutting::TetMesh& before, const std::vector<int>& next_before, const cutting::TetMesh& after,
                 const std::vector<std::int32_t>& node_old_to_new, const std::vector<std::int32_t>& element_old_to_new,
                 std::vector<int>& next, FaceChange* change) {
  const int T0 = before.numTets(), T1 = after.numTets(), N0 = before.numNodes(), N1 = after.numNodes();
  if (next_before.size() != 4 * static_cast<size_t>(T0) || element_old_to_new.size() != static_cast<size_t>(T0) ||
      node_old_to_new.size() != static_cast<size_t>(N0)) {
    return false;
  }
  if (T1 > 0 && (after.T.minCoeff() < 0 || after.T.maxCoeff() >= N1)) return false;
  if (N1 >= (1 << 21)) return false;  // (the open faces' keys below pack three node ids)
  // The old element of each new one, when it has the same nodes in the same order, and per
  // old element 4 x its new one (-1: not kept as it was). An element is kept when it maps to
  // a new one with the same nodes: no other old element can map to that one with the same
  // nodes too (two elements of a valid mesh never have the same nodes).
  // (Working arrays kept per thread between passes: every entry read is written first.)
  thread_local std::vector<int> new_of;
  thread_local std::vector<std::uint8_t> changed_node;
  thread_local std::vector<int> open;  // slots to match among themselves
  thread_local std::vector<std::pair<std::uint64_t, int>> keyed;
  std::vector<int> old_of(static_cast<size_t>(T1), -1);
  new_of.resize(static_cast<size_t>(T0));
  for (int t = 0; t < T0; ++t) {
    const int u = element_old_to_new[t];
    bool same = u >= 0 && u < T1;
    for (int k = 0; k < 4 && same; ++k) {
      const int i = before.T(t, k);
      same = i >= 0 && i < N0 && node_old_to_new[i] == after.T(u, k);
    }
    if (same) old_of[u] = t;
    new_of[t] = same ? 4 * u : -1;
  }
  changed_node.assign(static_cast<size_t>(N1), 0);
  for (int u = 0; u < T1; ++u)
    if (old_of[u] < 0)
      for (int k = 0; k < 4; ++k) changed_node[after.T(u, k)] = 1;
  // Kept neighbours are found per element (its four faces at once, the slots to match among
  // themselves collected after, in the same order): few values live across the faces, so
  // the loop keeps them in registers.
  std::vector<int> out(4 * static_cast<size_t>(T1));  // every entry written here
  open.clear();
  for (int u = 0; u < T1; ++u) {
    const int o = old_of[u];
    int* const row = out.data() + 4 * static_cast<size_t>(u);
    unsigned open_faces = 0;
    if (o < 0) {
      row[0] = row[1] = row[2] = row[3] = -1;
      open_faces = 15;
    } else {
      const int* const mine = next_before.data() + 4 * static_cast<size_t>(o);
      for (int f = 0; f < 4; ++f) {
        const int p = mine[f];
        int now = -1;
        if (p >= 0) {
          // Kept when both elements are kept as they were and the face had just the two.
          const int q = p / 4 < T0 ? new_of[p / 4] : -1;
          if (q >= 0) {
            now = q + p % 4;
          } else {
            open_faces |= 1u << f;
          }
        } else {
          const int* local = kTetFace[f];
          if (changed_node[after.T(u, local[0])] || changed_node[after.T(u, local[1])] ||
              changed_node[after.T(u, local[2])]) {
            open_faces |= 1u << f;
          }
        }
        row[f] = now;
      }
    }
    for (int f = 0; open_faces != 0; ++f, open_faces >>= 1)
      if (open_faces & 1u) open.push_back(4 * u + f);
  }
  // The open faces by their sorted nodes (a < b < c) packed into one key, 21 bits each (node
  // ids below 2^21, checked above), then the slot: equal faces next to each other, in slot
  // order.
  keyed.clear();
  for (int s : open) {
    const int t = s / 4;
    const int* local = kTetFace[s % 4];
    std::uint64_t a = static_cast<std::uint32_t>(after.T(t, local[0])), b = static_cast<std::uint32_t>(after.T(t, local[1])),
                  c = static_cast<std::uint32_t>(after.T(t, local[2]));
    if (a > b) std::swap(a, b);
    if (b > c) std::swap(b, c);
    if (a > b) std::swap(a, b);
    keyed.emplace_back(a << 42 | b << 21 | c, s);
  }
  std::sort(keyed.begin(), keyed.end());
  for (size_t i = 0; i < keyed.size();) {
    size_t j = i + 1;
    while (j < keyed.size() && keyed[j].first == keyed[i].first) ++j;
    if (j - i > 2) return false;  // a face of three elements: not a cut of a valid mesh
    if (j - i == 2) {
      out[keyed[i].second] = keyed[i + 1].second;
      out[keyed[i + 1].second] = keyed[i].second;
    }
    i = j;
  }
  next = std::move(out);
  if (change != nullptr) {
    change->near_cut.clear();
    for (int s : open)  // ascending slots: ascending tets
      if (change->near_cut.empty() || change->near_cut.back() != s / 4) change->near_cut.push_back(s / 4);
    change->old_of = std::move(old_of);
  }
  return true;
}


std::vector<int> anchorDistance(const cutting::TetMesh& mesh, const std::vector<int>& next,
                                const std::vector<std::uint8_t>& anchored) {
  const int M = mesh.numTets();
  std::vector<int> dist(static_cast<size_t>(M), std::numeric_limits<int>::max());
  std::vector<int> queue;
  queue.reserve(static_cast<size_t>(M));
  for (int t = 0; t < M; ++t)
    for (int k = 0; k < 4; ++k)
      if (anchored[mesh.T(t, k)]) {
        dist[t] = 0;
        queue.push_back(t);
        break;
      }
  const size_t slots = std::min(next.size(), 4 * static_cast<size_t>(M));
  for (size_t head = 0; head < queue.size(); ++head) {
    const int u = queue[head];
    for (int f = 0; f < 4; ++f) {
      const size_t s = 4 * static_cast<size_t>(u) + f;
      if (s >= slots) break;
      const int p = next[s];
      if (p < 0 || p / 4 >= M || dist[p / 4] != std::numeric_limits<int>::max()) continue;
      dist[p / 4] = dist[u] + 1;
      queue.push_back(p / 4);
    }
  }
  return dist;
}

Pieces freePiecesAfterCut(const cutting::TetMesh& after, const std::vector<int>& next,
                          const std::vector<std::uint8_t>& anchored, const FaceChange& change,
                          const std::vector<int>& distance_before) {
  const int M = after.numTets();
  const size_t slots = std::min(next.size(), 4 * static_cast<size_t>(M));
  auto distance = [&](int t) {
    const int o = t < static_cast<int>(change.old_of.size()) ? change.old_of[t] : -1;
    return o >= 0 && o < static_cast<int>(distance_before.size()) ? distance_before[o] : std::numeric_limits<int>::max();
  };
  // label: -1 unseen, else the search that reached the tet.
  std::vector<int> label(static_cast<size_t>(M), -1);
  std::vector<std::uint8_t> free_search;  // per search
  std::vector<int> stack;
  stack.reserve(256);
  for (int seed : change.near_cut) {
    if (seed < 0 || seed >= M || label[seed] >= 0) continue;
    const int id = static_cast<int>(free_search.size());
    bool anchored_found = false;
    label[seed] = id;
    stack.assign(1, seed);
    while (!stack.empty() && !anchored_found) {
      const int u = stack.back();
      stack.pop_back();
      for (int k = 0; k < 4 && !anchored_found; ++k) anchored_found = anchored[after.T(u, k)] != 0;
      if (anchored_found) break;
      // Unseen neighbours, the nearest to the anchors pushed last (popped first).
      int nb[4], nd[4], count = 0;
      for (int f = 0; f < 4; ++f) {
        const size_t s = 4 * static_cast<size_t>(u) + f;
        if (s >= slots) break;
        const int p = next[s];
        if (p < 0 || p / 4 >= M) continue;
        const int w = p / 4;
        if (label[w] == id) continue;
        if (label[w] >= 0) {  // an earlier search's tet: that search met the anchors
          anchored_found = true;
          break;
        }
        label[w] = id;
        int j = count++;
        const int d = distance(w);
        for (; j > 0 && nd[j - 1] < d; --j) {  // descending distance
          nb[j] = nb[j - 1];
          nd[j] = nd[j - 1];
        }
        nb[j] = w;
        nd[j] = d;
      }
      for (int j = 0; j < count; ++j) stack.push_back(nb[j]);
    }
    free_search.push_back(anchored_found ? 0 : 1);
  }
  // Free searches to pieces 1, 2, ... in the order of their first tet; the rest to piece 0.
  Pieces c;
  std::vector<int> piece_of(free_search.size(), 0);
  c.label.assign(static_cast<size_t>(M), 0);
  c.count = 1;
  for (int t = 0; t < M; ++t) {
    const int id = label[t];
    if (id < 0 || !free_search[id]) continue;
    if (piece_of[id] == 0) piece_of[id] = c.count++;
    c.label[t] = piece_of[id];
  }
  c.free.assign(static_cast<size_t>(c.count), 1);
  c.free[0] = 0;
  return c;
}


void NearestPoint::build(const sim::NodeVectors& x, const std::vector<int>& pts) {
  pts_ = &pts;
  x_ = &x;
  if (pts.empty()) return;
  Eigen::Vector3d lo = x.row(pts[0]).transpose(), hi = lo;
  for (int p : pts) {
    lo = lo.cwiseMin(x.row(p).transpose());
    hi = hi.cwiseMax(x.row(p).transpose());
  }
  const Eigen::Vector3d ext = (hi - lo).cwiseMax(1e-6);
  // About two points per cell.
  cell_ = std::cbrt(ext.prod() / std::max<double>(1.0, 0.5 * static_cast<double>(pts.size())));
  cell_ = std::max({cell_, ext.maxCoeff() / 256.0, 1e-6});
  origin_ = lo;
  for (int a = 0; a < 3; ++a) dims_[a] = std::max(1, static_cast<int>(std::floor(ext[a] / cell_)) + 1);
  const size_t cells = static_cast<size_t>(dims_[0]) * dims_[1] * dims_[2];
  start_.assign(cells + 1, 0);
  for (int p : pts) ++start_[cellOf(x.row(p).transpose()) + 1];
  for (size_t i = 0; i < cells; ++i) start_[i + 1] += start_[i];
  items_.resize(pts.size());
  std::vector<int> fill(start_.begin(), start_.end() - 1);
  for (size_t i = 0; i < pts.size(); ++i) items_[fill[cellOf(x.row(pts[i]).transpose())]++] = static_cast<int>(i);
}

int NearestPoint::nearest(const Eigen::Vector3d& q) const {
  const std::vector<int>& pts = *pts_;
  if (pts.empty()) return -1;
  Eigen::Vector3i c;
  for (int a = 0; a < 3; ++a) c[a] = clampIndex(q, a);
  double best = std::numeric_limits<double>::infinity();
  int best_i = -1;
  const int max_r = std::max({dims_[0], dims_[1], dims_[2]});
  for (int r = 0; r <= max_r; ++r) {
    // Cells at Chebyshev distance r from c.
    for (int i = c[0] - r; i <= c[0] + r; ++i) {
      if (i < 0 || i >= dims_[0]) continue;
      for (int j = c[1] - r; j <= c[1] + r; ++j) {
        if (j < 0 || j >= dims_[1]) continue;
        const bool edge_ij = std::abs(i - c[0]) == r || std::abs(j - c[1]) == r;
        for (int k = c[2] - r; k <= c[2] + r; k += (edge_ij || r == 0) ? 1 : 2 * r) {
          if (k < 0 || k >= dims_[2]) continue;
          const size_t cell = (static_cast<size_t>(i) * dims_[1] + j) * dims_[2] + k;
          for (int e = start_[cell]; e < start_[cell + 1]; ++e) {
            const int idx = items_[e];
            const double d = (x_->row(pts[idx]).transpose() - q).squaredNorm();
            if (d < best || (d == best && idx < best_i)) {
              best = d;
              best_i = idx;
            }
          }
        }
      }
    }
    // Points in cells further out lie at least r cells away (also when q is outside the
    // grid and its cell was clamped); stop once the best is clearly nearer than that.
    const double reach = static_cast<double>(r) * cell_;
    if (best_i >= 0 && best < reach * reach * (1.0 - 1e-9)) break;
  }
  return pts[best_i];
}

int NearestPoint::clampIndex(const Eigen::Vector3d& q, int a) const {
  const double f = std::floor((q[a] - origin_[a]) / cell_);
  return static_cast<int>(std::clamp(f, 0.0, static_cast<double>(dims_[a] - 1)));
}

size_t NearestPoint::cellOf(const Eigen::Vector3d& q) const {
  return (static_cast<size_t>(clampIndex(q, 0)) * dims_[1] + clampIndex(q, 1)) * dims_[2] + clampIndex(q, 2);
}

}  // namespace hysim::engine
