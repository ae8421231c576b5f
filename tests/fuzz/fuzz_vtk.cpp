// Fuzz target: the legacy VTK ASCII reader (tet and triangle meshes). Any bytes must give a mesh
// or an error; a mesh that reads must survive validate() (which may still reject it).
#include <cstddef>
#include <cstdint>
#include <string>

#include "hysim/cutting/mesh_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  if (auto tets = hysim::cutting::parseTetMesh("fuzz.vtk", text); tets.ok()) (void)hysim::cutting::validate(*tets);
  if (auto tris = hysim::cutting::parseTriMesh("fuzz.vtk", text); tris.ok()) (void)hysim::cutting::validate(*tris);
  return 0;
}
