#pragma once
// A JSON file the test's command wrote; a missing or broken file gives a discarded value (a
// failed expectation in the test, not an exception).
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

namespace hysim::testing {

inline nlohmann::json readJson(const std::string& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in, nullptr, false);
}

}  // namespace hysim::testing
