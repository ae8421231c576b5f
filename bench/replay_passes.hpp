#pragma once
// Dumped default-scene passes (hysim run --dump-cuts DIR) for the replay benchmarks:
// $HYSIM_REPLAY_DIR/pass_NNN_mesh.msh and pass_NNN_surface.msh, NNN from 001.
#include <cstdio>
#include <cstdlib>
#include <string>

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

}  // namespace hysim::bench
