// Two clean-ups of a freshly generated mesh. Boundary slivers: Delaunay refinement of a curved surface leaves a few flat tets whose four
// nodes all lie on the surface; perturbation and exudation cannot move surface nodes off it, so
// they stay. Such a tet with two faces on the boundary fills a dent of almost no volume:
// removing it leaves a valid surface.
#include <algorithm>
#include <array>
#include <cstdint>
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

// Interleaves the bits of three 21-bit cell coordinates (a Morton code).
std::uint64_t morton(std::uint64_t x, std::uint64_t y, std::uint64_t z) {
  std::uint64_t code = 0;
  for (int b = 0; b < 21; ++b) {
    code |= ((x >> b) & 1u) << (3 * b) | ((y >> b) & 1u) << (3 * b + 1) | ((z >> b) & 1u) << (3 * b + 2);
  }
  return code;
}

}  // namespace

void orderForLocality(cutting::TetMesh& mesh) {
  const Eigen::RowVector3d lo = mesh.X.colwise().minCoeff();
  constexpr double kCellMm = 0.25;
  std::vector<std::pair<std::uint64_t, int>> keyed(static_cast<size_t>(mesh.numNodes()));
  for (int i = 0; i < mesh.numNodes(); ++i) {
    const Eigen::RowVector3d c = (mesh.X.row(i) - lo) / kCellMm;
    keyed[i] = {morton(static_cast<std::uint64_t>(c.x()), static_cast<std::uint64_t>(c.y()),
                       static_cast<std::uint64_t>(c.z())), i};
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<int> rank(static_cast<size_t>(mesh.numNodes()));
  cutting::Positions X(mesh.numNodes(), 3);
  for (int k = 0; k < mesh.numNodes(); ++k) {
    rank[keyed[k].second] = k;
    X.row(k) = mesh.X.row(keyed[k].second);
  }
  mesh.X = X;
  // Tets by their smallest node, so that a tet's neighbours in memory are its neighbours.
  std::vector<std::pair<std::array<int, 4>, int>> tets(static_cast<size_t>(mesh.numTets()));
  for (int t = 0; t < mesh.numTets(); ++t) {
    std::array<int, 4> n{};
    for (int k = 0; k < 4; ++k) n[k] = rank[mesh.T(t, k)];
    std::array<int, 4> sorted = n;
    std::sort(sorted.begin(), sorted.end());
    tets[t] = {sorted, t};
  }
  std::sort(tets.begin(), tets.end());
  cutting::Tets T(mesh.numTets(), 4);
  cutting::Labels material(mesh.numTets());
  for (int e = 0; e < mesh.numTets(); ++e) {
    const int t = tets[e].second;
    for (int k = 0; k < 4; ++k) T(e, k) = rank[mesh.T(t, k)];  // the tet's own order keeps its orientation
    material(e) = mesh.material(t);
  }
  mesh.T = T;
  mesh.material = material;
}

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
