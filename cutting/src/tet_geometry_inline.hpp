#pragma once
// Small geometric helpers the editor, the optimiser and the volume bookkeeping share, inlined
// for speed and written so their values are those of tetVolume (mesh.cpp) bit for bit.
#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <vector>

#include <Eigen/Geometry>

#include "hysim/cutting/mesh.hpp"

namespace hysim::cutting {

// Six times tetVolume, in scalars over the coordinate columns: Eigen's cross
// (y1 z2 - z1 y2, z1 x2 - x1 z2, x1 y2 - y1 x2) and 3-vector dot ((a0 b0 + a1 b1) + a2 b2),
// the same value as (x1 - x0).dot((x2 - x0).cross(x3 - x0)) (checked bit for bit).
inline double tetVolume6Here(const TetMesh& mesh, int t) {
  const double* cx = mesh.X.col(0).data();
  const double* cy = mesh.X.col(1).data();
  const double* cz = mesh.X.col(2).data();
  const int i0 = mesh.T(t, 0), i1 = mesh.T(t, 1), i2 = mesh.T(t, 2), i3 = mesh.T(t, 3);
  const double ax = cx[i1] - cx[i0], ay = cy[i1] - cy[i0], az = cz[i1] - cz[i0];
  const double bx = cx[i2] - cx[i0], by = cy[i2] - cy[i0], bz = cz[i2] - cz[i0];
  const double ex = cx[i3] - cx[i0], ey = cy[i3] - cy[i0], ez = cz[i3] - cz[i0];
  const double nx = by * ez - bz * ey, ny = bz * ex - bx * ez, nz = bx * ey - by * ex;
  const double v6 = (ax * nx + ay * ny) + az * nz;
#ifdef HYSIM_CHECK_EXACT
  const Eigen::Vector3d x0 = mesh.X.row(i0), x1 = mesh.X.row(i1), x2 = mesh.X.row(i2), x3 = mesh.X.row(i3);
  const double ref = (x1 - x0).dot((x2 - x0).cross(x3 - x0));
  if (std::memcmp(&ref, &v6, sizeof v6) != 0) std::abort();
#endif
  return v6;
}

// tetVolume inlined: the same value.
inline double tetVolumeHere(const TetMesh& mesh, int t) {
  const double v = tetVolume6Here(mesh, t) / 6.0;
#ifdef HYSIM_CHECK_EXACT
  const double ref = tetVolume(mesh, t);
  if (std::memcmp(&ref, &v, sizeof v) != 0) std::abort();
#endif
  return v;
}

// d volume(t) / d x(T(t, k)): a sixth of the cross product of the edges from node 0 (k > 0),
// or minus the sum of the others (k = 0). A tet's volume is linear in each node's position.
inline Eigen::Vector3d tetVolumeGradient(const TetMesh& mesh, int t, int k) {
  using V = Eigen::Vector3d;
  const V x0 = mesh.X.row(mesh.T(t, 0)), a = V(mesh.X.row(mesh.T(t, 1))) - x0, b = V(mesh.X.row(mesh.T(t, 2))) - x0,
          c = V(mesh.X.row(mesh.T(t, 3))) - x0;
  const V g1 = b.cross(c) / 6.0, g2 = c.cross(a) / 6.0, g3 = a.cross(b) / 6.0;
  switch (k) {
    case 1: return g1;
    case 2: return g2;
    case 3: return g3;
    default: return -(g1 + g2 + g3);
  }
}

// A tet's material label (0 in a mesh without labels).
inline std::int32_t labelOf(const TetMesh& mesh, int t) {
  return mesh.material.size() == mesh.numTets() ? mesh.material(t) : 0;
}

// v[0, mid) and v[mid, end), each sorted, into one sorted list without repeats (what sort +
// unique of the whole gives); scratch is working room.
inline void mergeSortedRuns(std::vector<std::int32_t>& v, size_t mid, std::vector<std::int32_t>& scratch) {
  scratch.clear();
  const auto m = v.begin() + static_cast<std::ptrdiff_t>(mid);
  std::merge(v.begin(), m, m, v.end(), std::back_inserter(scratch));
  scratch.erase(std::unique(scratch.begin(), scratch.end()), scratch.end());
  v.swap(scratch);
}

}  // namespace hysim::cutting
