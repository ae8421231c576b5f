// Fuzz target: the scene parser (YAML text -> Scene). Any text must give a scene or an error
// naming the line. The scene is placed in scenes/ so that seeds from there find their meshes.
#include <cstddef>
#include <cstdint>
#include <string>

#include "hysim/engine/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  (void)hysim::engine::parseScene(text, HYSIM_SOURCE_DIR "/scenes/fuzz.yaml");
  return 0;
}
