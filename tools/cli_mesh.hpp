#pragma once
// `hysim mesh SCENE --out FILE.msh`: a scene's generated organ meshed (or taken from the
// cache) and written where ParaView or a pre-meshed scene can use it, with its statistics.
#include <CLI/CLI.hpp>
#include <memory>
#include <optional>
#include <string>

namespace hysim::tools {

struct MeshArgs {
  std::string scene;
  std::string out;        // empty: only the cache
  std::string cache_dir;  // empty: the default (organ_mesh.hpp)
  bool no_cache = false;  // mesh even when the cache has it
  bool json = false;
  std::string section;    // write a picture of the organ's section here
  bool section_only = false;  // and do not mesh
};

struct MeshCommand {
  CLI::App* mesh = nullptr;
  MeshArgs args;
};

std::shared_ptr<MeshCommand> addMeshCommand(CLI::App& app);
// The exit status when the command was given, else nothing.
std::optional<int> runMeshCommand(const MeshCommand& c);

}  // namespace hysim::tools
