#pragma once
// Test meshes made by hand: a box of nx*ny*nz cubes, each split into the 6 Kuhn tets around
// its main diagonal (conforming across cubes, all positively oriented), and the unit corner tet.
#include <array>
#include <utility>

#include "hysim/cutting/mesh.hpp"

namespace hysim::testing {

inline cutting::TetMesh boxTetMesh(int nx, int ny, int nz, double h, int label = 1) {
  cutting::TetMesh m;
  auto id = [&](int i, int j, int k) { return (k * (ny + 1) + j) * (nx + 1) + i; };
  m.X.resize((nx + 1) * (ny + 1) * (nz + 1), 3);
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) m.X.row(id(i, j, k)) << i * h, j * h, k * h;
  const std::array<std::array<int, 3>, 6> perms = {{{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  m.T.resize(6 * nx * ny * nz, 4);
  int t = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& p : perms) {
          std::array<int, 3> c = {i, j, k};
          std::array<int, 4> v;
          v[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            c[p[s]] += 1;
            v[s + 1] = id(c[0], c[1], c[2]);
          }
          m.T.row(t) << v[0], v[1], v[2], v[3];
          if (cutting::tetVolume(m, t) < 0) std::swap(m.T(t, 2), m.T(t, 3));
          ++t;
        }
  m.material = cutting::Labels::Constant(m.T.rows(), label);
  return m;
}

// The tet (0,0,0), (1,0,0), (0,1,0), (0,0,1), material 0.
inline cutting::TetMesh singleTet() {
  cutting::TetMesh m;
  m.X.resize(4, 3);
  m.X << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  m.T.resize(1, 4);
  m.T << 0, 1, 2, 3;
  m.material = cutting::Labels::Zero(1);
  return m;
}

}  // namespace hysim::testing
