// Whole-mesh queries on a cut's result: volume, components, the side checks of a plane cut.
#include <algorithm>
#include <numeric>

#include "cut3d_maps.hpp"
#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/tet_faces.hpp"

namespace hysim::cutting {

using cut3d_detail::Vec3;

double totalVolume(const TetMesh& mesh) {
  double v = 0;
  for (int t = 0; t < mesh.numTets(); ++t) v += tetVolume(mesh, t);
  return v;
}

Components3D tetComponents(const TetMesh& mesh, const std::vector<int>& anchored) {
  const int M = std::max(0, mesh.numTets());
  std::vector<int> next;
  matchFacesOfAnyIds(mesh, next);
  std::vector<std::uint8_t> isAnchored(static_cast<size_t>(mesh.numNodes()), 0);
  for (int n : anchored)
    if (n >= 0 && n < mesh.numNodes()) isAnchored[n] = 1;
  const Pieces pieces = tetPieces(mesh, next, isAnchored);
  Components3D c;
  c.count = pieces.count;
  c.label = Eigen::Map<const Eigen::VectorXi>(pieces.label.data(), M);
  c.volume.assign(static_cast<size_t>(c.count), 0.0);
  c.elements.assign(static_cast<size_t>(c.count), 0);
  for (int t = 0; t < M; ++t) {
    c.volume[pieces.label[t]] += tetVolume(mesh, t);
    ++c.elements[pieces.label[t]];
  }
  c.free.assign(pieces.free.begin(), pieces.free.end());
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
  std::vector<int> next;
  matchFacesOfAnyIds(mesh, next);
  int count = 0;
  // Each later tet of a face against the face's first (lowest) tet.
  for (int s = 0; s < static_cast<int>(next.size()); ++s) {
    const int first = firstSlotOfFace(next, s);
    if (first != s && tetSide(first / 4) * tetSide(s / 4) < 0) ++count;
  }
  return count;
}

}  // namespace hysim::cutting
