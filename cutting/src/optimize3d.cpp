// Local regularisation of a tet mesh around a cut (the paper's 2D mass-spring step carried
// to 3D, its "future work"): nodes one or two edge steps from the cut move under springs
// with rest length = local mean edge length, heavily damped; cut and boundary nodes stay.
// A move is kept only if no incident tet inverts and the worst incident q* does not drop.
#include <algorithm>
#include <cmath>
#include <unordered_set>
#include <vector>

#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::cutting {

void optimizeAfterCut3D(TetMesh& mesh, const std::vector<std::int32_t>& cut_nodes, const Optimize3DOptions& options,
                        std::vector<std::int32_t>* moved, int* iterations) {
  using Vec3 = Eigen::Vector3d;
  const int N = mesh.numNodes(), M = mesh.numTets();
  if (cut_nodes.empty() || options.rings <= 0) return;
  std::vector<std::int32_t> off(N + 1, 0), star(4 * static_cast<size_t>(M));
  for (int t = 0; t < M; ++t)
    for (int k = 0; k < 4; ++k) ++off[mesh.T(t, k) + 1];
  for (int i = 0; i < N; ++i) off[i + 1] += off[i];
  {
    std::vector<std::int32_t> fill(off.begin(), off.end() - 1);
    for (int t = 0; t < M; ++t)
      for (int k = 0; k < 4; ++k) star[fill[mesh.T(t, k)]++] = t;
  }
  // level: 0 on the cut, 1..rings around it, -1 elsewhere.
  std::vector<std::int8_t> level(N, -1);
  std::vector<std::int32_t> frontier(cut_nodes.begin(), cut_nodes.end()), region;
  for (int n : cut_nodes) level[n] = 0;
  for (int r = 1; r <= options.rings; ++r) {
    std::vector<std::int32_t> next;
    for (int n : frontier)
      for (int s = off[n]; s < off[n + 1]; ++s)
        for (int k = 0; k < 4; ++k) {
          const int m = mesh.T(star[s], k);
          if (level[m] < 0) {
            level[m] = static_cast<std::int8_t>(r);
            next.push_back(m);
          }
        }
    region.insert(region.end(), next.begin(), next.end());
    frontier.swap(next);
  }
  // Movable: interior ring nodes (every face around them shared by two tets).
  auto isBoundary = [&](int n) {
    std::vector<std::array<int, 3>> faces;
    static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
    for (int s = off[n]; s < off[n + 1]; ++s) {
      const int t = star[s];
      for (int f = 0; f < 4; ++f) {
        std::array<int, 3> v = {mesh.T(t, kFace[f][0]), mesh.T(t, kFace[f][1]), mesh.T(t, kFace[f][2])};
        if (v[0] != n && v[1] != n && v[2] != n) continue;
        std::sort(v.begin(), v.end());
        auto it = std::find(faces.begin(), faces.end(), v);
        if (it == faces.end()) {
          faces.push_back(v);
        } else {
          faces.erase(it);
        }
      }
    }
    return !faces.empty();
  };
  std::vector<std::int32_t> movable;
  for (int n : region)
    if (!isBoundary(n)) movable.push_back(n);
  if (movable.empty()) return;
  std::sort(movable.begin(), movable.end());
  // Mean edge length around the movable nodes.
  double sum = 0;
  int count = 0;
  for (int n : movable)
    for (int s = off[n]; s < off[n + 1]; ++s)
      for (int k = 0; k < 4; ++k) {
        const int m = mesh.T(star[s], k);
        if (m == n) continue;
        sum += (mesh.X.row(m) - mesh.X.row(n)).norm();
        ++count;
      }
  const double rest = sum / std::max(count, 1);
  auto worstQuality = [&](int n, const Vec3& at, bool* inverted) {
    double worst = 1.0;
    for (int s = off[n]; s < off[n + 1]; ++s) {
      const int t = star[s];
      Vec3 p[4];
      for (int k = 0; k < 4; ++k) p[k] = mesh.T(t, k) == n ? at : Vec3(mesh.X.row(mesh.T(t, k)).transpose());
      if ((p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0])) <= 0) *inverted = true;
      worst = std::min(worst, radiusRatio(p[0], p[1], p[2], p[3]));
    }
    return worst;
  };
  std::unordered_set<std::int32_t> movedSet;
  // Worst q* around each movable node, recomputed only after it or a neighbour moved.
  std::vector<double> cached(N, -1.0);
  int it = 0;
  for (; it < options.max_iterations; ++it) {
    double largest = 0;
    for (int n : movable) {
      const Vec3 x = mesh.X.row(n).transpose();
      {
        bool inv = false;
        if (cached[n] < 0) cached[n] = worstQuality(n, x, &inv);
        if (cached[n] >= options.quality_target) continue;
      }
      Vec3 force = Vec3::Zero();
      int degree = 0;
      for (int s = off[n]; s < off[n + 1]; ++s)
        for (int k = 0; k < 4; ++k) {
          const int m = mesh.T(star[s], k);
          if (m == n) continue;
          const Vec3 d = mesh.X.row(m).transpose() - x;
          const double len = d.norm();
          if (len > 0) force += (len - rest) * d / len;
          ++degree;
        }
      if (degree == 0) continue;
      const Vec3 target = x + options.step_gain * force / degree * 2.0;
      bool invertedBefore = false, invertedAfter = false;
      if (cached[n] < 0) cached[n] = worstQuality(n, x, &invertedBefore);
      const double before = cached[n];
      if (before >= options.quality_target) continue;  // its elements are good enough
      const double after = worstQuality(n, target, &invertedAfter);
      if (invertedAfter || after < before) continue;
      const double move = (target - x).norm();
      if (move <= 0) continue;
      mesh.X.row(n) = target.transpose();
      for (int s = off[n]; s < off[n + 1]; ++s)
        for (int k = 0; k < 4; ++k) cached[mesh.T(star[s], k)] = -1.0;
      cached[n] = after;
      movedSet.insert(n);
      largest = std::max(largest, move);
    }
    if (largest < options.stop_fraction * rest) {
      ++it;
      break;
    }
  }
  if (iterations) *iterations = it;
  if (moved)
    for (int n : movedSet) moved->push_back(n);
}

}  // namespace hysim::cutting
