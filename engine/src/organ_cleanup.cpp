// Boundary slivers: Delaunay refinement of a curved surface leaves a few flat tets whose four
// nodes all lie on the surface; perturbation and exudation cannot move surface nodes off it, so
// they stay. Such a tet with two faces on the boundary fills a dent of almost no volume:
// removing it leaves a valid surface.
#include <algorithm>
#include <map>

#include "hysim/cutting/mesh_stats.hpp"
#include "hysim/engine/organ_mesh.hpp"

namespace hysim::engine {
namespace {

using Face = std::array<int, 3>;

Face sortedFace(int a, int b, int c) {
  Face f{a, b, c};
  std::sort(f.begin(), f.end());
  return f;
}

// Per tet, how many of its faces are on the boundary.
std::vector<int> boundaryFaceCounts(const cutting::TetMesh& mesh) {
  static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  std::map<Face, int> uses;
  for (int t = 0; t < mesh.numTets(); ++t) {
    for (const auto& f : kFace) ++uses[sortedFace(mesh.T(t, f[0]), mesh.T(t, f[1]), mesh.T(t, f[2]))];
  }
  std::vector<int> count(static_cast<size_t>(mesh.numTets()), 0);
  for (int t = 0; t < mesh.numTets(); ++t) {
    for (const auto& f : kFace) count[t] += uses[sortedFace(mesh.T(t, f[0]), mesh.T(t, f[1]), mesh.T(t, f[2]))] == 1;
  }
  return count;
}

double quality(const cutting::TetMesh& m, int t) {
  return cutting::radiusRatio(m.X.row(m.T(t, 0)).transpose(), m.X.row(m.T(t, 1)).transpose(),
                              m.X.row(m.T(t, 2)).transpose(), m.X.row(m.T(t, 3)).transpose());
}

// The mesh without `drop`ped tets and without nodes no tet uses (first-use order kept).
cutting::TetMesh without(const cutting::TetMesh& mesh, const std::vector<char>& drop) {
  std::vector<int> index(static_cast<size_t>(mesh.numNodes()), -1);
  std::vector<int> kept_nodes;
  std::vector<int> kept_tets;
  for (int t = 0; t < mesh.numTets(); ++t) {
    if (drop[t]) continue;
    kept_tets.push_back(t);
    for (int k = 0; k < 4; ++k) {
      int& i = index[mesh.T(t, k)];
      if (i < 0) {
        i = static_cast<int>(kept_nodes.size());
        kept_nodes.push_back(mesh.T(t, k));
      }
    }
  }
  cutting::TetMesh out;
  out.X.resize(static_cast<Eigen::Index>(kept_nodes.size()), 3);
  for (size_t i = 0; i < kept_nodes.size(); ++i) out.X.row(static_cast<Eigen::Index>(i)) = mesh.X.row(kept_nodes[i]);
  out.T.resize(static_cast<Eigen::Index>(kept_tets.size()), 4);
  out.material.resize(static_cast<Eigen::Index>(kept_tets.size()));
  for (size_t e = 0; e < kept_tets.size(); ++e) {
    for (int k = 0; k < 4; ++k) out.T(static_cast<Eigen::Index>(e), k) = index[mesh.T(kept_tets[e], k)];
    out.material(static_cast<Eigen::Index>(e)) = mesh.material(kept_tets[e]);
  }
  return out;
}

}  // namespace

int peelBoundarySlivers(cutting::TetMesh& mesh, double min_quality) {
  int removed = 0;
  for (int round = 0; round < 3; ++round) {
    const std::vector<int> faces = boundaryFaceCounts(mesh);
    std::vector<char> drop(static_cast<size_t>(mesh.numTets()), 0);
    int n = 0;
    for (int t = 0; t < mesh.numTets(); ++t) {
      if (faces[t] >= 2 && quality(mesh, t) < min_quality) {
        drop[t] = 1;
        ++n;
      }
    }
    if (n == 0) break;
    mesh = without(mesh, drop);
    removed += n;
  }
  return removed;
}

}  // namespace hysim::engine
