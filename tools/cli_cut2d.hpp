#pragma once
// `hysim cut` (2D cutting of a triangle mesh file) and `hysim tables` (the paper's Table 1
// reproduced on DistMesh meshes). Kept out of hysim.cpp, which only registers them.
#include <CLI/CLI.hpp>
#include <memory>
#include <optional>

namespace hysim::tools {

struct Cut2dCommands;  // the subcommands and their parsed arguments

std::shared_ptr<Cut2dCommands> addCut2dCommands(CLI::App& app);
// The exit status when one of these subcommands was chosen, else nullopt.
std::optional<int> runCut2dCommands(const Cut2dCommands& commands);

}  // namespace hysim::tools
