// Element quality (radius ratio, dihedral angles) and the paper's table columns.
//
// Formulas are chosen to stay finite on degenerate input: every ratio checks its
// denominator, and degenerate elements report q = 0 and angle 0 instead of NaN, so one
// collapsed element shows up as the minimum instead of poisoning the whole table.
#include "hysim/cutting/mesh_stats.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>
#include <vector>

namespace hysim::cutting {

namespace {

// Unsigned angle between two vectors in radians. atan2 of (|u x v|, u . v) keeps full
// precision near 0 and pi, where acos of a normalised dot product does not.
double angleBetween(const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
  return std::atan2(u.cross(v).norm(), u.dot(v));
}

constexpr double kRadToDeg = 180.0 / std::numbers::pi;

// Running min / mean / population std. Two-pass would be slightly more accurate, but
// Welford's update is stable enough for table output and needs no storage.
struct Accumulator {
  long long n = 0;
  double min = std::numeric_limits<double>::infinity();
  double mean = 0;
  double m2 = 0;
  void add(double v) {
    ++n;
    min = std::min(min, v);
    const double delta = v - mean;
    mean += delta / static_cast<double>(n);
    m2 += delta * (v - mean);
  }
  void store(double& outMin, double& outMean, double& outStd) const {
    if (n == 0) {
      outMin = outMean = outStd = 0;
      return;
    }
    outMin = min;
    outMean = mean;
    outStd = std::sqrt(std::max(0.0, m2 / static_cast<double>(n)));
  }
};

// Unique undirected edges (lo < hi) of elements with E.cols() nodes each, sorted. Edges
// with an index outside [0, numNodes) are skipped: stats do not validate.
// Counting sort by lo, then a small sort per node: several times faster than sorting all
// 6 #T pairs at once on 20k-tet meshes.
template <class Elements>
std::vector<std::pair<std::int32_t, std::int32_t>> uniqueEdges(const Elements& E, Eigen::Index numNodes) {
  const int cols = static_cast<int>(E.cols());
  std::vector<std::pair<std::int32_t, std::int32_t>> edges;
  edges.reserve(static_cast<std::size_t>(E.rows()) * cols * (cols - 1) / 2);
  std::vector<std::int32_t> bucketStart(static_cast<std::size_t>(numNodes) + 1, 0);  // #N + 1
  for (Eigen::Index e = 0; e < E.rows(); ++e) {
    for (int i = 0; i < cols; ++i) {
      for (int j = i + 1; j < cols; ++j) {
        const std::int32_t a = E(e, i);
        const std::int32_t b = E(e, j);
        if (a < 0 || b < 0 || a >= numNodes || b >= numNodes) continue;
        edges.emplace_back(std::min(a, b), std::max(a, b));
        ++bucketStart[static_cast<std::size_t>(std::min(a, b)) + 1];
      }
    }
  }
  for (std::size_t i = 1; i < bucketStart.size(); ++i) bucketStart[i] += bucketStart[i - 1];
  std::vector<std::pair<std::int32_t, std::int32_t>> bucketed(edges.size());
  std::vector<std::int32_t> fill(bucketStart.begin(), bucketStart.end() - 1);
  for (const auto& edge : edges)
    bucketed[static_cast<std::size_t>(fill[static_cast<std::size_t>(edge.first)]++)] = edge;
  for (std::size_t b = 0; b + 1 < bucketStart.size(); ++b) {
    std::sort(bucketed.begin() + bucketStart[b], bucketed.begin() + bucketStart[b + 1]);
  }
  bucketed.erase(std::unique(bucketed.begin(), bucketed.end()), bucketed.end());
  return bucketed;
}

template <class Elements>
int countReferencedNodes(const Elements& E, Eigen::Index numNodes) {
  std::vector<char> used(static_cast<std::size_t>(numNodes), 0);
  int count = 0;
  for (Eigen::Index e = 0; e < E.rows(); ++e) {
    for (Eigen::Index j = 0; j < E.cols(); ++j) {
      const std::int32_t v = E(e, j);
      if (v < 0 || v >= numNodes) continue;  // stats do not validate; skip bad references
      char& flag = used[static_cast<std::size_t>(v)];
      if (!flag) {
        flag = 1;
        ++count;
      }
    }
  }
  return count;
}

void fillEdgeStats(const Positions& X, const std::vector<std::pair<std::int32_t, std::int32_t>>& edges,
                   MeshStats& stats) {
  Accumulator acc;
  for (const auto& [a, b] : edges) acc.add((X.row(a) - X.row(b)).norm());
  acc.store(stats.edge_min, stats.edge_mean, stats.edge_std);
}

}  // namespace

double radiusRatio(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  // r_in = 2A / P and R_circ = l0 l1 l2 / (4A), so q = 8 A^2 / (P l0 l1 l2).
  // A from the cross product is accurate for slivers, unlike Heron's formula.
  const double l0 = (b - c).norm();
  const double l1 = (c - a).norm();
  const double l2 = (a - b).norm();
  const double area = 0.5 * (b - a).cross(c - a).norm();
  const double denominator = (l0 + l1 + l2) * l0 * l1 * l2;
  if (!(denominator > 0) || !std::isfinite(denominator)) return 0.0;
  const double q = 8.0 * area * area / denominator;
  return std::isfinite(q) ? q : 0.0;
}

double minDihedralDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                      const Eigen::Vector3d& d) {
  // Face normals n[k] of the face opposite vertex k, all outward for a positive tet (all
  // inward for a negative one; the angles between them are the same either way).
  const Eigen::Vector3d n[4] = {
      (c - b).cross(d - b),  // face (b, c, d)
      (d - a).cross(c - a),  // face (a, d, c)
      (b - a).cross(d - a),  // face (a, b, d)
      (c - a).cross(b - a),  // face (a, c, b)
  };
  for (const auto& normal : n) {
    if (!(normal.squaredNorm() > 0) || !normal.allFinite()) return 0.0;
  }
  // The dihedral angle at the edge shared by faces k and l is pi minus the angle between
  // their outward normals.
  double minAngle = std::numbers::pi;
  for (int k = 0; k < 4; ++k) {
    for (int l = k + 1; l < 4; ++l) {
      minAngle = std::min(minAngle, std::numbers::pi - angleBetween(n[k], n[l]));
    }
  }
  return minAngle * kRadToDeg;
}

MeshStats computeStats(const TetMesh& mesh) {
  MeshStats stats;
  stats.nodes = countReferencedNodes(mesh.T, mesh.X.rows());
  stats.elements = mesh.numTets();
  Accumulator size, quality;
  double minDihedral = std::numeric_limits<double>::infinity();
  for (Eigen::Index t = 0; t < mesh.T.rows(); ++t) {
    bool inRange = true;
    for (int j = 0; j < 4; ++j) inRange = inRange && mesh.T(t, j) >= 0 && mesh.T(t, j) < mesh.X.rows();
    if (!inRange) continue;
    const Eigen::Vector3d a = mesh.X.row(mesh.T(t, 0));
    const Eigen::Vector3d b = mesh.X.row(mesh.T(t, 1));
    const Eigen::Vector3d c = mesh.X.row(mesh.T(t, 2));
    const Eigen::Vector3d d = mesh.X.row(mesh.T(t, 3));
    size.add(tetVolume(mesh, static_cast<int>(t)));
    quality.add(radiusRatio(a, b, c, d));
    minDihedral = std::min(minDihedral, minDihedralDeg(a, b, c, d));
  }
  size.store(stats.size_min, stats.size_mean, stats.size_std);
  quality.store(stats.q_min, stats.q_mean, stats.q_std);
  stats.dihedral_min_deg = std::isfinite(minDihedral) ? minDihedral : 0.0;
  fillEdgeStats(mesh.X, uniqueEdges(mesh.T, mesh.X.rows()), stats);
  return stats;
}

MeshStats computeStats(const TriMesh& mesh) {
  MeshStats stats;
  stats.nodes = countReferencedNodes(mesh.F, mesh.X.rows());
  stats.elements = mesh.numTris();
  Accumulator size, quality;
  double minAngle = std::numeric_limits<double>::infinity();
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    bool inRange = true;
    for (int j = 0; j < 3; ++j) inRange = inRange && mesh.F(f, j) >= 0 && mesh.F(f, j) < mesh.X.rows();
    if (!inRange) continue;
    const Eigen::Vector3d a = mesh.X.row(mesh.F(f, 0));
    const Eigen::Vector3d b = mesh.X.row(mesh.F(f, 1));
    const Eigen::Vector3d c = mesh.X.row(mesh.F(f, 2));
    size.add(triArea(mesh, static_cast<int>(f)));
    quality.add(radiusRatio(a, b, c));
    // A degenerate triangle (coincident nodes) has an undefined angle; report 0.
    const bool degenerate =
        (b - a).squaredNorm() == 0 || (c - b).squaredNorm() == 0 || (a - c).squaredNorm() == 0;
    const double smallest =
        degenerate
            ? 0.0
            : std::min({angleBetween(b - a, c - a), angleBetween(c - b, a - b), angleBetween(a - c, b - c)});
    minAngle = std::min(minAngle, smallest * kRadToDeg);
  }
  size.store(stats.size_min, stats.size_mean, stats.size_std);
  quality.store(stats.q_min, stats.q_mean, stats.q_std);
  stats.dihedral_min_deg = std::isfinite(minAngle) ? minAngle : 0.0;
  fillEdgeStats(mesh.X, uniqueEdges(mesh.F, mesh.X.rows()), stats);
  return stats;
}

}  // namespace hysim::cutting
