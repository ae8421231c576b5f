#pragma once
// Mesh statistics with the paper's columns (Tables 1 and 2).
#include <algorithm>
#include <cmath>

#include "hysim/cutting/mesh.hpp"

namespace hysim::cutting {

// Standard deviations are population standard deviations (divide by n).
struct MeshStats {
  int nodes = 0;            // #N: nodes referenced by at least one element
  int elements = 0;         // #E
  double size_min = 0, size_mean = 0, size_std = 0;  // area (2D) or volume (3D)
  double edge_min = 0, edge_mean = 0, edge_std = 0;  // over unique edges
  double q_min = 0, q_mean = 0, q_std = 0;           // r_in / R_circ: [0,1/2] triangles, [0,1/3] tets
  double dihedral_min_deg = 0;  // tets: minimum dihedral angle; triangles: minimum interior angle
};

// q = r_in / R_circ of one element.
double radiusRatio(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);
// Inline: the optimiser's hot loops evaluate it millions of times.
inline double radiusRatio(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                          const Eigen::Vector3d& d) {
  // r_in = 3V / S (S = total face area). The circumradius from the six edge lengths:
  //   R = sqrt((p+q+r)(p+q-r)(p-q+r)(-p+q+r)) / (24 V)
  // with p, q, r the products of the lengths of opposite edge pairs. Hence
  //   q* = r_in / R = 72 V^2 / (S sqrt(...)).
  const double volume = std::abs((b - a).dot((c - a).cross(d - a))) / 6.0;
  const double p = (b - a).norm() * (d - c).norm();
  const double q = (c - a).norm() * (d - b).norm();
  const double r = (d - a).norm() * (c - b).norm();
  // Rounding can push a factor of a degenerate tet slightly below zero; clamp it.
  const double product = std::max(0.0, (p + q + r) * (p + q - r) * (p - q + r) * (-p + q + r));
  const double faceArea = 0.5 * ((b - a).cross(c - a).norm() + (b - a).cross(d - a).norm() +
                                 (c - a).cross(d - a).norm() + (c - b).cross(d - b).norm());
  const double denominator = faceArea * std::sqrt(product);
  if (!(denominator > 0) || !std::isfinite(denominator)) return 0.0;
  const double ratio = 72.0 * volume * volume / denominator;
  return std::isfinite(ratio) ? ratio : 0.0;
}
// Smallest of the six dihedral angles of a tet, in degrees.
double minDihedralDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                      const Eigen::Vector3d& d);

MeshStats computeStats(const TetMesh& mesh);
MeshStats computeStats(const TriMesh& mesh);

}  // namespace hysim::cutting
