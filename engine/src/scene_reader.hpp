#pragma once
// The scene parser's reader: typed access to YAML values whose errors name the file, the
// line and the key. Shared by the parts of the scene parser (scene.cpp, scene_organ.cpp).
#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>
#include <string>

#include "hysim/cutting/input_file.hpp"
#include "hysim/engine/scene.hpp"

namespace hysim::engine::scene_detail {

// Every number in a scene is a physical quantity in mm, g, s or kPa, or a count; none comes
// near 1e9 (1000 km as a position), and products of a few values of at most 1e9 stay far
// from overflow in the model.
constexpr double kMaxSceneNumber = 1e9;
// A walk over a document with aliases can revisit shared parts many times (a "billion laughs"
// file); past this many nodes the scene is refused.
constexpr long kMaxSceneNodes = 1000000;
constexpr int kMaxSceneDepth = 64;

// Thrown inside the parser only and turned into a Result at the boundary: the parser is a
// deep recursive walk and an early exit from every level would hide its logic.
struct SceneError {
  std::string message;
};

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const YAML::Node& at, const std::string& what) const {
    std::ostringstream out;
    out << file_;
    if (at.IsDefined() && at.Mark().line >= 0) out << ":" << at.Mark().line + 1;
    out << ": " << what;
    throw SceneError{out.str()};
  }

  // Every key of `map` must be in `allowed`.
  void checkKeys(const YAML::Node& map, const std::string& where, const std::set<std::string>& allowed) const {
    if (!map.IsMap()) fail(map, "'" + where + "' must be a mapping");
    for (const auto& kv : map) {
      const std::string key = kv.first.as<std::string>();
      if (!allowed.count(key)) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
        fail(kv.first, "unknown key '" + key + "' in '" + where + "' (allowed: " + list + ")");
      }
    }
  }

  YAML::Node require(const YAML::Node& map, const std::string& key, const std::string& where) const {
    YAML::Node n = map[key];
    if (!n.IsDefined() || n.IsNull()) fail(map, "missing required key '" + key + "' in '" + where + "'");
    return n;
  }

  double number(const YAML::Node& n, const std::string& key) const {
    if (!n.IsScalar()) fail(n, "'" + key + "' must be a number");
    double value = 0.0;
    if (!YAML::convert<double>::decode(n, value)) fail(n, "'" + key + "' must be a number, got '" + n.Scalar() + "'");
    if (!std::isfinite(value)) fail(n, "'" + key + "' must be finite, got '" + n.Scalar() + "'");
    if (std::abs(value) > kMaxSceneNumber) {
      fail(n, "'" + key + "' must be between -1e9 and 1e9, got '" + n.Scalar() + "'");
    }
    return value;
  }
  double positive(const YAML::Node& n, const std::string& key) const {
    const double v = number(n, key);
    if (!(v > 0.0)) fail(n, "'" + key + "' must be positive, got " + n.Scalar());
    return v;
  }
  double nonNegative(const YAML::Node& n, const std::string& key) const {
    const double v = number(n, key);
    if (v < 0.0) fail(n, "'" + key + "' must not be negative, got " + n.Scalar());
    return v;
  }
  int integer(const YAML::Node& n, const std::string& key, int lo, int hi) const {
    if (!n.IsScalar()) fail(n, "'" + key + "' must be an integer");
    long long value = 0;
    if (!YAML::convert<long long>::decode(n, value)) fail(n, "'" + key + "' must be an integer, got '" + n.Scalar() + "'");
    if (value < lo || value > hi) {
      fail(n, "'" + key + "' must be between " + std::to_string(lo) + " and " + std::to_string(hi) + ", got " + n.Scalar());
    }
    return static_cast<int>(value);
  }
  bool boolean(const YAML::Node& n, const std::string& key) const {
    bool value = false;
    if (!n.IsScalar() || !YAML::convert<bool>::decode(n, value)) fail(n, "'" + key + "' must be true or false");
    return value;
  }
  std::string string(const YAML::Node& n, const std::string& key) const {
    if (!n.IsScalar()) fail(n, "'" + key + "' must be a string");
    return n.Scalar();
  }
  Eigen::Vector3d vec3(const YAML::Node& n, const std::string& key) const {
    if (!n.IsSequence() || n.size() != 3) fail(n, "'" + key + "' must be a list of 3 numbers [x, y, z]");
    return {number(n[0], key), number(n[1], key), number(n[2], key)};
  }
  Eigen::Vector3d unitVec3(const YAML::Node& n, const std::string& key) const {
    const Eigen::Vector3d v = vec3(n, key);
    if (v.norm() < 1e-9) fail(n, "'" + key + "' must be a non-zero direction");
    return v.normalized();
  }

  // Before any value is read: no mapping holds a key twice (YAML parsers keep one of them
  // silently) and every scalar, keys included, is UTF-8 (names and paths go into the JSON
  // report, whose writer refuses anything else). `where` is the path of `n` for messages.
  void checkDocument(const YAML::Node& n, const std::string& where, int depth, long& visited) const {
    if (++visited > kMaxSceneNodes) {
      fail(n, "the scene expands to more than " + std::to_string(kMaxSceneNodes) + " YAML nodes (aliases?)");
    }
    if (depth > kMaxSceneDepth) {
      fail(n, "'" + where + "' is nested more than " + std::to_string(kMaxSceneDepth) + " levels deep");
    }
    if (n.IsScalar()) {
      checkUtf8(n, "'" + where + "'");
    } else if (n.IsSequence()) {
      for (std::size_t i = 0; i < n.size(); ++i) {
        checkDocument(n[i], where + "[" + std::to_string(i) + "]", depth + 1, visited);
      }
    } else if (n.IsMap()) {
      std::set<std::string> seen;
      for (const auto& kv : n) {
        if (!kv.first.IsScalar()) fail(kv.first, "a key in '" + where + "' is not a plain name");
        checkUtf8(kv.first, "a key in '" + where + "'");
        const std::string key = kv.first.Scalar();
        if (!seen.insert(key).second) fail(kv.first, "duplicate key '" + key + "' in '" + where + "'");
        checkDocument(kv.second, where == "scene" ? key : where + "." + key, depth + 1, visited);
      }
    }
  }

 private:
  void checkUtf8(const YAML::Node& n, const std::string& what) const {
    const std::string& text = n.Scalar();
    const std::size_t bad = firstInvalidUtf8(text);
    if (bad == std::string::npos) return;
    char byte[8];
    std::snprintf(byte, sizeof byte, "0x%02x", static_cast<unsigned>(static_cast<unsigned char>(text[bad])));
    fail(n, what + " is not valid UTF-8: byte " + byte + " at offset " + std::to_string(bad) +
                " of the value (save the file as UTF-8)");
  }

  std::string file_;
};

// The `organ:` section (scene_organ.cpp): the organ, its materials and anchors.
void parseOrgan(const Reader& r, const YAML::Node& n, Scene& scene);

}  // namespace hysim::engine::scene_detail
