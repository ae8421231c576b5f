#pragma once
// Hand-made planar triangle meshes for the 2D cutting tests.
#include <cmath>

#include "hysim/cutting/mesh.hpp"

namespace hysim::testing {

// nx x ny squares of side h, each split by the diagonal (i,j)-(i+1,j+1), counter-clockwise.
inline cutting::TriMesh gridTriMesh(int nx, int ny, double h) {
  cutting::TriMesh m;
  auto id = [&](int i, int j) { return j * (nx + 1) + i; };
  m.X.setZero((nx + 1) * (ny + 1), 3);
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) m.X.row(id(i, j)) << i * h, j * h, 0.0;
  m.F.resize(2 * nx * ny, 3);
  int f = 0;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      m.F.row(f++) << id(i, j), id(i + 1, j), id(i + 1, j + 1);
      m.F.row(f++) << id(i, j), id(i + 1, j + 1), id(i, j + 1);
    }
  m.material.setOnes(m.F.rows());
  return m;
}

// Regular hexagon of radius 1 around a centre node 0: six equilateral triangles.
inline cutting::TriMesh hexagonMesh() {
  cutting::TriMesh m;
  m.X.setZero(7, 3);
  for (int k = 0; k < 6; ++k) m.X.row(k + 1) << std::cos(k * M_PI / 3), std::sin(k * M_PI / 3), 0.0;
  m.F.resize(6, 3);
  for (int k = 0; k < 6; ++k) m.F.row(k) << 0, k + 1, (k + 1) % 6 + 1;
  m.material.setOnes(6);
  return m;
}

inline cutting::TriMesh singleTriangle() {
  cutting::TriMesh m;
  m.X.setZero(3, 3);
  m.X.row(1) << 1, 0, 0;
  m.X.row(2) << 0.5, std::sqrt(3.0) / 2, 0;
  m.F.resize(1, 3);
  m.F.row(0) << 0, 1, 2;
  m.material.setOnes(1);
  return m;
}

}  // namespace hysim::testing
