// Local optimisation of a tet mesh around a cut (the paper's 2D regularisation carried to
// 3D, its "future work"). Only nodes near the cut take part, and only those with a poor
// element around them; cut and boundary nodes stay. Each candidate move (a spring step
// toward the local mean edge length, or a push away from the face opposite the node in its
// worst element, with step halving) is kept only if no incident tet inverts and the worst
// incident q* increases, so the local minimum quality never drops. Everything is local:
// the caller hands in the stars of the candidate nodes (no whole-mesh pass).
#include <algorithm>
#include <cmath>
#include <vector>

#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/mesh_stats.hpp"
#include "optimize3d_internal.hpp"

namespace hysim::cutting {

void optimizeLocal3D(TetMesh& mesh, const LocalStars& stars, const Optimize3DOptions& options,
                     std::vector<std::int32_t>* moved, int* iterations) {
  using Vec3 = Eigen::Vector3d;
  const int count = static_cast<int>(stars.nodes.size());
  if (iterations) *iterations = 0;
  if (count == 0) return;
  auto pos = [&](int i) -> Vec3 { return mesh.X.row(i).transpose(); };
  double scale = 0;
  // Worst q* around node n placed at `at`; sets *inverted when an element would invert and
  // *worstTet to the (star index of the) worst element.
  auto worst = [&](int j, const Vec3& at, bool* inverted, int* worstTet) {
    const int n = stars.nodes[j];
    double q = 1.0;
    for (int s = stars.offset[j]; s < stars.offset[j + 1]; ++s) {
      const int t = stars.tets[s];
      Vec3 p[4];
      for (int k = 0; k < 4; ++k) p[k] = mesh.T(t, k) == n ? at : pos(mesh.T(t, k));
      if (!((p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0])) > 0)) {
        *inverted = true;
        return 0.0;
      }
      const double qt = radiusRatio(p[0], p[1], p[2], p[3]);
      if (qt < q) {
        q = qt;
        if (worstTet) *worstTet = t;
      }
    }
    return q;
  };
  std::vector<std::uint8_t> didMove(count, 0);
  // Work list: the nodes with a poor element around them; a node that cannot improve drops out.
  std::vector<std::int32_t> work;
  for (int j = 0; j < count; ++j) {
    bool inv = false;
    if (worst(j, pos(stars.nodes[j]), &inv, nullptr) < options.quality_target && !inv) work.push_back(j);
  }
  int it = 0;
  for (; it < options.max_iterations && !work.empty(); ++it) {
    double largest = 0;
    std::vector<std::int32_t> keep;
    for (int j : work) {
      const int n = stars.nodes[j];
      const Vec3 x = pos(n);
      bool inv = false;
      int wt = -1;
      const double before = worst(j, x, &inv, &wt);
      if (inv || before >= options.quality_target || wt < 0) continue;
      // Mean incident edge length and the spring force toward it.
      double sum = 0;
      int deg = 0;
      for (int s = stars.offset[j]; s < stars.offset[j + 1]; ++s)
        for (int k = 0; k < 4; ++k) {
          const int m = mesh.T(stars.tets[s], k);
          if (m == n) continue;
          sum += (pos(m) - x).norm();
          ++deg;
        }
      if (deg == 0) continue;
      const double h = sum / deg;
      scale = std::max(scale, h);
      Vec3 force = Vec3::Zero();
      for (int s = stars.offset[j]; s < stars.offset[j + 1]; ++s)
        for (int k = 0; k < 4; ++k) {
          const int m = mesh.T(stars.tets[s], k);
          if (m == n) continue;
          const Vec3 d = pos(m) - x;
          const double len = d.norm();
          if (len > 0) force += (len - h) * d / len;
        }
      // Push direction: away from the face opposite n in its worst tet.
      Vec3 face[3];
      int f = 0;
      for (int k = 0; k < 4; ++k)
        if (mesh.T(wt, k) != n) face[f++] = pos(mesh.T(wt, k));
      Vec3 push = (face[1] - face[0]).cross(face[2] - face[0]);
      if (push.norm() > 0) push.normalize();
      if (push.dot(x - face[0]) < 0) push = -push;
      const Vec3 dirs[2] = {options.step_gain * 2.0 * force / deg, 0.3 * h * push};
      double best = before;
      Vec3 bestX = x;
      for (const Vec3& d : dirs) {
        double step = 1.0;
        for (int tries = 0; tries < 4; ++tries, step *= 0.5) {
          const Vec3 y = x + step * d;
          bool inverted = false;
          const double q = worst(j, y, &inverted, nullptr);
          if (!inverted && q > best) {
            best = q;
            bestX = y;
            break;
          }
        }
      }
      if (best > before) {
        largest = std::max(largest, (bestX - x).norm());
        mesh.X.row(n) = bestX.transpose();
        didMove[j] = 1;
        if (best < options.quality_target) keep.push_back(j);
      }
    }
    work.swap(keep);
    if (largest <= options.stop_fraction * scale) {
      ++it;
      break;
    }
  }
  if (iterations) *iterations = it;
  if (moved)
    for (int j = 0; j < count; ++j)
      if (didMove[j]) moved->push_back(stars.nodes[j]);
}

}  // namespace hysim::cutting
