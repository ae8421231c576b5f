#pragma once
// Mesh statistics with the paper's columns (Tables 1 and 2).
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
double radiusRatio(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                   const Eigen::Vector3d& d);
// Smallest of the six dihedral angles of a tet, in degrees.
double minDihedralDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                      const Eigen::Vector3d& d);

MeshStats computeStats(const TetMesh& mesh);
MeshStats computeStats(const TriMesh& mesh);

}  // namespace hysim::cutting
