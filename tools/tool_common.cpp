#include "tool_common.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string_view>

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

namespace {

std::string numberText(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

}  // namespace

CLI::Validator finiteRange(double lo, double hi) {
  const std::string range = "[" + numberText(lo) + ", " + numberText(hi) + "]";
  return CLI::Validator(
      [lo, hi, range](std::string& input) -> std::string {
        double value = 0.0;
        const char* end = input.data() + input.size();
        const auto [stop, ec] = std::from_chars(input.data(), end, value);
        if (ec != std::errc() || stop != end || !std::isfinite(value)) {
          return "'" + input + "' is not a finite number";
        }
        if (value < lo || value > hi) return "'" + input + "' is not in " + range;
        return {};
      },
      "NUMBER in " + range);
}

Result<std::vector<double>> parseNumberList(const std::string& option, const std::string& text, int count,
                                            const std::string& expected, double max_abs) {
  // Commas or spaces separate the values, as the option's help and older scripts write them.
  std::vector<std::string> items;
  std::string item;
  for (const char c : text + ",") {
    if (c == ',' || std::isspace(static_cast<unsigned char>(c))) {
      if (!item.empty()) items.push_back(item);
      item.clear();
    } else {
      item += c;
    }
  }
  if (static_cast<int>(items.size()) != count) return Error{option + ": expected " + expected + ", got '" + text + "'"};
  std::vector<double> values;
  for (const std::string& token : items) {
    const std::string_view digits = token.front() == '+' ? std::string_view(token).substr(1) : std::string_view(token);
    double v = 0.0;
    const auto [stop, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
    if (digits.empty() || ec == std::errc::invalid_argument || stop != digits.data() + digits.size()) {
      return Error{option + ": expected " + expected + ", got '" + text + "' ('" + token + "' is not a number)"};
    }
    if (ec == std::errc::result_out_of_range || !std::isfinite(v)) {
      return Error{option + ": value '" + token + "' in '" + text + "' is not a finite number in double range"};
    }
    if (std::abs(v) > max_abs) {
      return Error{option + ": value '" + token + "' in '" + text + "' is beyond +-" + numberText(max_abs)};
    }
    values.push_back(v);
  }
  return values;
}

}  // namespace hysim::tools
