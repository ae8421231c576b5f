#include "tool_common.hpp"

#include <filesystem>

namespace hysim::tools {

std::string defaultScenePath() {
  if (std::filesystem::exists("scenes/default.yaml")) return "scenes/default.yaml";
  return std::string(HYSIM_SOURCE_DIR) + "/scenes/default.yaml";
}

nlohmann::ordered_json statsJson(const cutting::MeshStats& s) {
  nlohmann::ordered_json j;
  j["nodes"] = s.nodes;
  j["elements"] = s.elements;
  j["size_min"] = s.size_min;
  j["size_mean"] = s.size_mean;
  j["size_std"] = s.size_std;
  j["edge_min"] = s.edge_min;
  j["edge_mean"] = s.edge_mean;
  j["edge_std"] = s.edge_std;
  j["q_min"] = s.q_min;
  j["q_mean"] = s.q_mean;
  j["q_std"] = s.q_std;
  j["dihedral_min_deg"] = s.dihedral_min_deg;
  return j;
}

}  // namespace hysim::tools
