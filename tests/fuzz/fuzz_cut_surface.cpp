// Fuzz target: the cut-surface loaders of `hysim cut --surface` (STL, OBJ and PLY through
// assimp; the triangles of .msh and .vtk files). The first byte picks the extension, the rest
// is the file. The loaders read paths (assimp opens the file itself), so each process writes
// its input into a folder of its own under /tmp. A surface that loads must answer queries.
#include <unistd.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "hysim/engine/cut_surface_file.hpp"

namespace {

// The process's own folder, made once and removed at exit. A plain array, not a string: the
// exit handler runs after static objects are destroyed.
char g_folder[] = "/tmp/hysim-fuzz-XXXXXX";

const char* scratchFolder() {
  static const bool made = [] {
    if (mkdtemp(g_folder) == nullptr) std::abort();
    std::atexit([] { std::filesystem::remove_all(g_folder); });
    return true;
  }();
  (void)made;
  return g_folder;
}

bool writeFile(const std::string& path, const std::uint8_t* data, std::size_t size) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) return false;
  const bool ok = std::fwrite(data, 1, size, file) == size;
  return std::fclose(file) == 0 && ok;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static constexpr std::array<const char*, 5> kExtensions = {".stl", ".obj", ".ply", ".msh", ".vtk"};
  const std::string path = std::string(scratchFolder()) + "/surface" + kExtensions[data[0] % kExtensions.size()];
  if (!writeFile(path, data + 1, size - 1)) std::abort();
  auto surface = hysim::engine::loadCutSurface(path);
  if (!surface.ok()) return 0;
  hysim::cutting::CutSurface::Hit hit;
  (void)surface->signedDistance(Eigen::Vector3d(0.5, 0.5, 0.5));
  (void)surface->intersectSegment(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1), 1e-9, &hit);
  return 0;
}
