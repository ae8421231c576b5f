#pragma once
// Small pieces the command-line programs share.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <string>

#include <vector>

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

// A number in [lo, hi], for numeric options. CLI11's Range (and PositiveNumber,
// NonNegativeNumber) let "nan" through, since every comparison with NaN is false.
CLI::Validator finiteRange(double lo, double hi);

// Parses "a,b,c" into exactly `count` finite numbers of magnitude at most `max_abs`; the error
// names the option, the text and the offending value.
Result<std::vector<double>> parseNumberList(const std::string& option, const std::string& text, int count,
                                            const std::string& expected, double max_abs);

}  // namespace hysim::tools
