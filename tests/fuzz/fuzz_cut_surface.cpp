// Fuzz target: the cut-surface loaders of `hysim cut --surface` (STL, OBJ and PLY through
// assimp; the triangles of .msh and .vtk files). The first byte picks the extension, the rest
// is the file. The loaders read paths (assimp opens the file itself), so each input is written
// to a temporary file of its own (mkstemps) and removed after loading: libFuzzer ends a run
// without exit handlers. A surface that loads must answer queries.
#include <stdlib.h>
#include <unistd.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "hysim/engine/cut_surface_file.hpp"

namespace {

// Writes the bytes to a new file /tmp/hysim-fuzz-XXXXXX<extension>; its path, or "" on failure.
std::string writeTemporary(const char* extension, const std::uint8_t* data, std::size_t size) {
  std::string path = std::string("/tmp/hysim-fuzz-XXXXXX") + extension;
  const int fd = mkstemps(path.data(), 4);
  if (fd < 0) return "";
  const bool ok = write(fd, data, size) == static_cast<ssize_t>(size);
  close(fd);
  if (!ok) unlink(path.c_str());
  return ok ? path : "";
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static constexpr std::array<const char*, 5> kExtensions = {".stl", ".obj", ".ply", ".msh", ".vtk"};
  const std::string path = writeTemporary(kExtensions[data[0] % kExtensions.size()], data + 1, size - 1);
  if (path.empty()) std::abort();
  auto surface = hysim::engine::loadCutSurface(path);
  unlink(path.c_str());
  if (!surface.ok()) return 0;
  hysim::cutting::CutSurface::Hit hit;
  (void)surface->signedDistance(Eigen::Vector3d(0.5, 0.5, 0.5));
  (void)surface->intersectSegment(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1), 1e-9, &hit);
  return 0;
}
