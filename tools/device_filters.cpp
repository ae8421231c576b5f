#include "device_filters.hpp"

#include "yaml_file.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

namespace hysim::tools {
namespace {

std::string at(const std::string& path, const YAML::Node& n, const std::string& key) {
  return path + ":" + std::to_string(n.Mark().line + 1) + ": '" + key + "'";
}

Result<double> number(const std::string& path, const YAML::Node& n, const std::string& key, double lo, double hi) {
  double v = 0.0;
  try {
    v = n.as<double>();
  } catch (const YAML::Exception&) {
    return Error{at(path, n, key) + ": expected a number"};
  }
  if (!std::isfinite(v) || v < lo || v > hi) {
    return Error{at(path, n, key) + ": " + n.Scalar() + " is outside [" + std::to_string(lo) + ", " +
                 std::to_string(hi) + "]"};
  }
  return v;
}

Result<Eigen::Vector3d> vector3(const std::string& path, const YAML::Node& n, const std::string& key, double limit) {
  if (!n.IsSequence() || n.size() != 3) return Error{at(path, n, key) + ": expected [x, y, z]"};
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    auto c = number(path, n[i], key, -limit, limit);
    if (!c.ok()) return Error{c.error()};
    v[i] = *c;
  }
  return v;
}

// Rotations about x, then y, then z (fixed axes), degrees.
Eigen::Matrix3d rotationFromDegrees(const Eigen::Vector3d& deg) {
  const Eigen::Vector3d r = deg * (std::numbers::pi / 180.0);
  return (Eigen::AngleAxisd(r.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(r.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(r.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

struct Limits {
  double speed = 500.0, turn = 6.0, extension = 100.0;
};

// One key of the file into `out`.
Status readKey(const std::string& path, const std::string& key, const YAML::Node& v, DeviceFilters& out,
               Limits& limits) {
  Result<double> x = 0.0;
  Result<Eigen::Vector3d> vec = Eigen::Vector3d(Eigen::Vector3d::Zero());
  if (key == "scale") {
    if (!(x = number(path, v, key, 0.01, 100.0)).ok()) return Error{x.error()};
    out.scale.scale = *x;
  } else if (key == "scale_center_mm" || key == "translation_mm" || key == "rotation_deg") {
    if (!(vec = vector3(path, v, key, key == "rotation_deg" ? 360.0 : 1e4)).ok()) return Error{vec.error()};
    if (key == "scale_center_mm") out.scale.center_mm = *vec;
    if (key == "translation_mm") out.transform.translation_mm = *vec;
    if (key == "rotation_deg") out.transform.rotation = rotationFromDegrees(*vec);
  } else if (key == "max_speed_mm_s" || key == "max_turn_rad_s" || key == "max_extension_mm_s") {
    if (!(x = number(path, v, key, 1e-3, 1e5)).ok()) return Error{x.error()};
    double& slot = key == "max_speed_mm_s" ? limits.speed : key == "max_turn_rad_s" ? limits.turn : limits.extension;
    slot = *x;
  } else {
    return Error{at(path, v, key) + ": unknown key (scale, scale_center_mm, rotation_deg, translation_mm, "
                                    "max_speed_mm_s, max_turn_rad_s, max_extension_mm_s)"};
  }
  return Status::Ok();
}

}  // namespace

Result<DeviceFilters> loadDeviceFilters(const std::string& path) {
  auto loaded = loadYamlFile(path);
  if (!loaded.ok()) return Error{loaded.error()};
  const YAML::Node& root = *loaded;
  if (!root.IsMap()) return Error{path + ": expected a map of keys"};
  DeviceFilters out;
  Limits limits;
  for (const auto& kv : root) {
    if (!kv.first.IsScalar()) return Error{at(path, kv.first, "?") + ": a key must be a name"};
    if (Status st = readKey(path, kv.first.Scalar(), kv.second, out, limits); !st.ok()) {
      return Error{st.error()};
    }
  }
  out.limit = haptics::MotionLimit(limits.speed, limits.turn, limits.extension);
  return out;
}

}  // namespace hysim::tools
