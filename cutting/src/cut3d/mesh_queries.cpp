// Whole-mesh queries on a cut's result: volume, components, the side checks of a plane cut.
#include <algorithm>
#include <numeric>
#include <unordered_map>

#include "cut3d_maps.hpp"
#include "hysim/cutting/cut3d.hpp"

namespace hysim::cutting {

using cut3d_detail::FaceKey;
using cut3d_detail::FaceKeyHash;
using cut3d_detail::kFace;
using cut3d_detail::makeFace;
using cut3d_detail::Vec3;

double totalVolume(const TetMesh& mesh) {
  double v = 0;
  for (int t = 0; t < mesh.numTets(); ++t) v += tetVolume(mesh, t);
  return v;
}

Components3D tetComponents(const TetMesh& mesh, const std::vector<int>& anchored) {
  Components3D c;
  const int M = std::max(0, mesh.numTets());
  c.label = Eigen::VectorXi::Constant(M, -1);
  // Faces sorted by key; equal neighbours share a face.
  struct F {
    std::array<std::int32_t, 3> v;
    std::int32_t tet;
  };
  std::vector<F> faces;
  faces.reserve(4 * static_cast<size_t>(M));
  for (int t = 0; t < M; ++t)
    for (int f = 0; f < 4; ++f) {
      FaceKey k = makeFace(mesh.T(t, kFace[f][0]), mesh.T(t, kFace[f][1]), mesh.T(t, kFace[f][2]));
      faces.push_back({k.v, t});
    }
  std::sort(faces.begin(), faces.end(), [](const F& x, const F& y) { return x.v < y.v; });
  std::vector<int> parent(static_cast<size_t>(M));
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (size_t i = 0; i + 1 < faces.size(); ++i)
    if (faces[i].v == faces[i + 1].v) parent[find(faces[i].tet)] = find(faces[i + 1].tet);
  std::vector<int> id(static_cast<size_t>(M), -1);
  for (int t = 0; t < M; ++t) {
    const int r = find(t);
    if (id[r] < 0) {
      id[r] = c.count++;
      c.volume.push_back(0.0);
      c.elements.push_back(0);
    }
    c.label(t) = id[r];
    c.volume[id[r]] += tetVolume(mesh, t);
    ++c.elements[id[r]];
  }
  c.free.assign(c.count, true);
  std::vector<std::uint8_t> isAnchored(mesh.numNodes(), 0);
  for (int n : anchored)
    if (n >= 0 && n < mesh.numNodes()) isAnchored[n] = 1;
  for (int t = 0; t < M; ++t)
    for (int k = 0; k < 4; ++k)
      if (isAnchored[mesh.T(t, k)]) c.free[c.label(t)] = false;
  return c;
}

int countStraddling(const TetMesh& mesh, const Eigen::Vector3d& point, const Eigen::Vector3d& normal, double eps) {
  const Vec3 n = normal.normalized();
  int count = 0;
  for (int t = 0; t < mesh.numTets(); ++t) {
    bool pos = false, neg = false;
    for (int k = 0; k < 4; ++k) {
      const double f = n.dot(mesh.X.row(mesh.T(t, k)).transpose() - point);
      pos = pos || f > eps;
      neg = neg || f < -eps;
    }
    if (pos && neg) ++count;
  }
  return count;
}

int countFacesSharedAcross(const TetMesh& mesh, const Eigen::Vector3d& point, const Eigen::Vector3d& normal,
                           double eps) {
  const Vec3 n = normal.normalized();
  auto tetSide = [&](int t) {
    double best = 0;
    for (int k = 0; k < 4; ++k) {
      const double f = n.dot(mesh.X.row(mesh.T(t, k)).transpose() - point);
      if (std::abs(f) > std::abs(best)) best = f;
    }
    return best > eps ? 1 : best < -eps ? -1 : 0;
  };
  std::unordered_map<FaceKey, int, FaceKeyHash> owner;
  int count = 0;
  for (int t = 0; t < mesh.numTets(); ++t)
    for (int f = 0; f < 4; ++f) {
      const FaceKey k = makeFace(mesh.T(t, kFace[f][0]), mesh.T(t, kFace[f][1]), mesh.T(t, kFace[f][2]));
      auto [it, inserted] = owner.emplace(k, t);
      if (!inserted && tetSide(it->second) * tetSide(t) < 0) ++count;
    }
  return count;
}

}  // namespace hysim::cutting
