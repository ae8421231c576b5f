#pragma once
// Dumped default-scene passes (hysim run --dump-cuts DIR) for the replay benchmarks:
// $HYSIM_REPLAY_DIR/pass_NNN_mesh.msh and pass_NNN_surface.msh, NNN from 001.
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>

#include "hysim/cutting/cut_surface.hpp"
#include "hysim/cutting/mesh_io.hpp"

namespace hysim::bench {

// Pass i (from 1): its rest mesh and cut surface. False when there is no such pass, or no
// $HYSIM_REPLAY_DIR.
inline bool readDumpedPass(int i, cutting::TetMesh& mesh, cutting::TriMesh& surface) {
  const char* dir = std::getenv("HYSIM_REPLAY_DIR");
  if (dir == nullptr || *dir == 0) return false;
  char name[32];
  std::snprintf(name, sizeof(name), "/pass_%03d_", i);
  auto m = cutting::readTetMesh(std::string(dir) + name + "mesh.msh");
  auto tri = cutting::readTriMesh(std::string(dir) + name + "surface.msh");
  if (!m.ok() || !tri.ok()) return false;
  mesh = std::move(*m);
  surface = std::move(*tri);
  return true;
}

// The strip shape (rows, row_size) of a dumped surface whose triangles are
// CutSurface::stripTriangles(rows, row_size), as the simulator writes them; (0, 0) otherwise.
inline std::pair<int, int> stripShape(const cutting::TriMesh& tri) {
  const auto n = tri.X.rows();
  for (int row_size = 2; row_size <= n / 2; ++row_size) {
    if (n % row_size != 0) continue;
    const int rows = static_cast<int>(n / row_size);
    if (2 * static_cast<Eigen::Index>(rows - 1) * (row_size - 1) != tri.F.rows()) continue;
    if (cutting::CutSurface::stripTriangles(rows, row_size) == tri.F) return {rows, row_size};
  }
  return {0, 0};
}

// The pass's cut surface as the simulator builds it: a strip (CutSurface::strip) when the
// triangles are a strip's (they always are in a dump), else from the triangles.
// HYSIM_REPLAY_SORTED_TREE set: from the triangles (the centroid-sorted tree) always, for
// comparisons. The same surface either way (same triangles and numbers).
inline Result<cutting::CutSurface> dumpedSurface(const cutting::TriMesh& tri) {
  const char* sorted = std::getenv("HYSIM_REPLAY_SORTED_TREE");
  if (sorted == nullptr || *sorted == 0) {
    const auto [rows, row_size] = stripShape(tri);
    if (rows > 0) return cutting::CutSurface::strip(tri.X, rows, row_size);
  }
  return cutting::CutSurface::triangles(tri.X, tri.F);
}

}  // namespace hysim::bench
