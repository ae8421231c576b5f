#include "hysim/cutting/tet_faces.hpp"

#include <algorithm>

namespace hysim::cutting {

bool matchFaces(const TetMesh& mesh, std::vector<int>& next) {
  const int M = mesh.numTets(), N = mesh.numNodes();
  const size_t S = 4 * static_cast<size_t>(M);
  struct Entry {
    int b, c, slot;  // the face's two larger nodes, and its slot
  };
  std::vector<int> start(static_cast<size_t>(N) + 2, 0);
  for (int k = 0; k < 4; ++k)
    for (int t = 0; t < M; ++t) {
      const int a = mesh.T(t, kTetFace[k][0]), b = mesh.T(t, kTetFace[k][1]), c = mesh.T(t, kTetFace[k][2]);
      if (std::min({a, b, c}) < 0 || std::max({a, b, c}) >= N) return false;
      ++start[static_cast<size_t>(std::min({a, b, c})) + 2];
    }
  for (int i = 0; i < N; ++i) start[i + 2] += start[i + 1];
  // start[a + 1] is the fill position of bucket a; after filling, start[a]..start[a + 1].
  std::vector<Entry> entries(S);
  for (int t = 0; t < M; ++t)
    for (int k = 0; k < 4; ++k) {
      int a = mesh.T(t, kTetFace[k][0]), b = mesh.T(t, kTetFace[k][1]), c = mesh.T(t, kTetFace[k][2]);
      if (a > b) std::swap(a, b);
      if (b > c) std::swap(b, c);
      if (a > b) std::swap(a, b);
      entries[start[a + 1]++] = {b, c, 4 * t + k};
    }
  next.assign(S, -1);
  for (int n = 0; n < N; ++n) {
    Entry* const first = entries.data() + start[n];
    Entry* const last = entries.data() + start[n + 1];
    // Insertion sort by (b, c), a bucket holds a few dozen faces; stable, so equal faces stay
    // in ascending slot order (the order they were filled in).
    for (Entry* i = first + 1; i < last; ++i) {
      const Entry e = *i;
      Entry* j = i;
      for (; j > first && (j[-1].b > e.b || (j[-1].b == e.b && j[-1].c > e.c)); --j) *j = j[-1];
      *j = e;
    }
    for (Entry* i = first; i < last;) {
      Entry* j = i + 1;
      while (j < last && j->b == i->b && j->c == i->c) ++j;
      if (j - i > 1) {
        for (Entry* q = i; q + 1 < j; ++q) next[q->slot] = (q + 1)->slot;
        next[(j - 1)->slot] = i->slot;
      }
      i = j;
    }
  }
  return true;
}

void matchFacesOfAnyIds(const TetMesh& mesh, std::vector<int>& next) {
  if (matchFaces(mesh, next)) return;
  std::vector<std::int32_t> ids(mesh.T.data(), mesh.T.data() + mesh.T.size());
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  TetMesh renumbered;
  renumbered.T = mesh.T.unaryExpr([&ids](std::int32_t id) {
    return static_cast<std::int32_t>(std::lower_bound(ids.begin(), ids.end(), id) - ids.begin());
  });
  renumbered.X = Positions::Zero(static_cast<Eigen::Index>(ids.size()), 3);
  matchFaces(renumbered, next);
}

void boundaryFromSlots(const TetMesh& mesh, const std::vector<std::uint8_t>& boundary, Tris& faces,
                       Eigen::VectorXi& face_tet) {
  const auto count = static_cast<Eigen::Index>(std::count(boundary.begin(), boundary.end(), 1));
  faces.resize(count, 3);
  face_tet.resize(count);
  Eigen::Index row = 0;
  for (size_t slot = 0; slot < boundary.size(); ++slot) {
    if (!boundary[slot]) continue;
    const int t = static_cast<int>(slot / 4);
    const int* local = kTetFace[slot % 4];
    faces.row(row) << mesh.T(t, local[0]), mesh.T(t, local[1]), mesh.T(t, local[2]);
    face_tet(row) = t;
    ++row;
  }
}

Pieces tetPieces(const TetMesh& mesh, const std::vector<int>& next, const std::vector<std::uint8_t>& anchored) {
  // Flood fill over shared faces, pieces numbered in the order of their lowest tet (as a
  // union-find numbering its roots in tet order would): O(#T), no long parent chains.
  const int M = mesh.numTets();
  Pieces c;
  c.label.assign(static_cast<size_t>(M), -1);
  std::vector<int> stack;
  stack.reserve(64);
  const size_t slots = std::min(next.size(), 4 * static_cast<size_t>(M));
  for (int t = 0; t < M; ++t) {
    if (c.label[t] >= 0) continue;
    const int id = c.count++;
    c.label[t] = id;
    stack.push_back(t);
    while (!stack.empty()) {
      const int u = stack.back();
      stack.pop_back();
      for (int f = 0; f < 4; ++f) {
        const size_t s = 4 * static_cast<size_t>(u) + f;
        if (s >= slots) break;
        const int p = next[s];
        if (p < 0 || p / 4 >= M || c.label[p / 4] >= 0) continue;
        c.label[p / 4] = id;
        stack.push_back(p / 4);
      }
    }
  }
  c.free.assign(static_cast<size_t>(c.count), 1);
  for (int t = 0; t < M; ++t)
    for (int k = 0; k < 4; ++k)
      if (anchored[mesh.T(t, k)]) c.free[c.label[t]] = 0;
  return c;
}

}  // namespace hysim::cutting
