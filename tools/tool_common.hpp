#pragma once
// Small pieces the command-line programs share.
#include <nlohmann/json.hpp>
#include <string>

#include "hysim/cutting/mesh_stats.hpp"
#include "hysim/cutting/result.hpp"

namespace hysim::tools {

// scenes/default.yaml in the working directory, else in the source tree this was built from.
std::string defaultScenePath();

// The `hysim stats --json` keys: nodes, elements, size_min, size_mean, size_std, edge_min,
// edge_mean, edge_std, q_min, q_mean, q_std, dihedral_min_deg.
nlohmann::ordered_json statsJson(const cutting::MeshStats& stats);

// Writes `text` to `path` through a temporary file and a rename: an existing file is replaced
// whole or left as it was, never half-written.
Status writeFileAtomically(const std::string& path, const std::string& text);

}  // namespace hysim::tools
