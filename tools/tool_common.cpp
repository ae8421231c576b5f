#include "tool_common.hpp"

#include <filesystem>
#include <fstream>

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

// (A crash or kill between the write and the rename leaves only the temporary file.)
Status writeFileAtomically(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  std::error_code dir_ec;
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent, dir_ec);
  if (dir_ec) return Error{"cannot create folder '" + parent.string() + "': " + dir_ec.message()};
  bool written = false;
  {
    std::ofstream out(tmp, std::ios::binary);
    out << text;
    written = static_cast<bool>(out.flush());
  }
  std::error_code ec;
  if (!written) {
    std::filesystem::remove(tmp, ec);
    return Error{"cannot write '" + tmp + "'"};
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    return Error{"cannot move '" + tmp + "' to '" + path + "': " + ec.message()};
  }
  return Status::Ok();
}

}  // namespace hysim::tools
