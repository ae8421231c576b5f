#pragma once
// A small YAML file of the command-line tools (pad scripts, device filters), read whole; the
// error names the file and the line.
#include <yaml-cpp/yaml.h>

#include <string>

#include "hysim/cutting/input_file.hpp"
#include "hysim/cutting/result.hpp"

namespace hysim::tools {

inline Result<YAML::Node> loadYamlFile(const std::string& path) {
  Result<std::string> text = readInputFile(path, kMaxYamlFileBytes, "YAML");
  if (!text.ok()) return Error{text.error()};
  try {
    return YAML::Load(*text);
  } catch (const YAML::Exception& e) {
    return Error{path + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg};
  }
}

}  // namespace hysim::tools
