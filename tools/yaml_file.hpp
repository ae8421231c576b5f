#pragma once
// A small YAML file of the command-line tools (pad scripts, device filters), read whole
// (a regular file of at most 16 MiB, no key twice in a mapping); the error names the file
// and the line.
#include <yaml-cpp/yaml.h>

#include <set>
#include <string>

#include "hysim/cutting/input_file.hpp"
#include "hysim/cutting/result.hpp"

namespace hysim::tools {

// The first key given twice in one mapping (YAML parsers keep one of the two silently), as
// "path:line: duplicate key 'k'", or "" when there is none. `budget` bounds the walk, which
// aliases could otherwise make revisit shared parts without end.
inline std::string duplicateYamlKey(const YAML::Node& n, const std::string& path, long& budget) {
  if (--budget < 0) return path + ": more than a million YAML nodes (aliases?)";
  if (n.IsSequence()) {
    for (const auto& item : n) {
      if (std::string e = duplicateYamlKey(item, path, budget); !e.empty()) return e;
    }
  } else if (n.IsMap()) {
    std::set<std::string> seen;
    for (const auto& kv : n) {
      if (kv.first.IsScalar() && !seen.insert(kv.first.Scalar()).second) {
        return path + ":" + std::to_string(kv.first.Mark().line + 1) + ": duplicate key '" + kv.first.Scalar() + "'";
      }
      if (std::string e = duplicateYamlKey(kv.second, path, budget); !e.empty()) return e;
    }
  }
  return {};
}

inline Result<YAML::Node> loadYamlFile(const std::string& path) {
  Result<std::string> text = readInputFile(path, kMaxYamlFileBytes, "YAML");
  if (!text.ok()) return Error{text.error()};
  try {
    YAML::Node root = YAML::Load(*text);
    long budget = 1000000;
    if (std::string e = duplicateYamlKey(root, path, budget); !e.empty()) return Error{e};
    return root;
  } catch (const YAML::Exception& e) {
    return Error{path + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg};
  }
}

}  // namespace hysim::tools
