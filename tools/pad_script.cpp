#include "pad_script.hpp"

#include "yaml_file.hpp"

#include <cmath>

#include "hysim/haptics/gamepad_mapping.hpp"

namespace hysim::tools {
namespace {

std::string where(const std::string& path, const YAML::Node& n) {
  return path + ":" + std::to_string(n.Mark().line + 1);
}

// One `name: value` of an event.
Result<PadEvent::Input> readInput(const std::string& path, const std::string& key, const YAML::Node& value) {
  PadEvent::Input in;
  if (const int axis = haptics::padAxisIndex(key); axis >= 0) {
    const bool trigger = axis == haptics::pad::kLeftTrigger || axis == haptics::pad::kRightTrigger;
    double v = 0.0;
    try {
      v = value.as<double>();
    } catch (const YAML::Exception&) {
      return Error{where(path, value) + ": '" + key + "': expected a number"};
    }
    if (!std::isfinite(v) || v < (trigger ? 0.0 : -1.0) || v > 1.0) {
      return Error{where(path, value) + ": '" + key + "': " + value.Scalar() + " is outside " +
                   (trigger ? "[0, 1]" : "[-1, 1]")};
    }
    in.index = axis;
    in.value = v;
    return in;
  }
  if (const int button = haptics::padButtonIndex(key); button >= 0) {
    try {
      in.value = value.as<bool>() ? 1.0 : 0.0;
    } catch (const YAML::Exception&) {
      return Error{where(path, value) + ": '" + key + "': expected true or false"};
    }
    in.is_axis = false;
    in.index = button;
    return in;
  }
  return Error{where(path, value) + ": unknown key '" + key +
               "' (t_s, or a standard-layout input: left_x, left_y, right_x, right_y, left_trigger, right_trigger, "
               "a, b, x, y, back, guide, start, left_stick, right_stick, left_shoulder, right_shoulder, dpad_up, "
               "dpad_down, dpad_left, dpad_right)"};
}

Result<PadEvent> readEvent(const std::string& path, const YAML::Node& n, double previous_t) {
  if (!n.IsMap()) return Error{where(path, n) + ": an event must be a map (t_s and inputs)"};
  if (!n["t_s"]) return Error{where(path, n) + ": an event needs 't_s'"};
  PadEvent e;
  try {
    e.t_s = n["t_s"].as<double>();
  } catch (const YAML::Exception&) {
    return Error{where(path, n["t_s"]) + ": 't_s': expected a number"};
  }
  if (!std::isfinite(e.t_s) || e.t_s < previous_t) {
    return Error{where(path, n["t_s"]) + ": 't_s': " + n["t_s"].Scalar() + " (events go forward in time from 0)"};
  }
  for (const auto& kv : n) {
    if (!kv.first.IsScalar()) return Error{where(path, kv.first) + ": a key must be an input name"};
    const std::string key = kv.first.Scalar();
    if (key == "t_s") continue;
    auto input = readInput(path, key, kv.second);
    if (!input.ok()) return Error{input.error()};
    e.inputs.push_back(*input);
  }
  return e;
}

}  // namespace

Result<PadScript> PadScript::load(const std::string& path) {
  auto loaded = loadYamlFile(path);
  if (!loaded.ok()) return Error{loaded.error()};
  const YAML::Node& root = *loaded;
  if (!root.IsSequence() || root.size() == 0) return Error{path + ": expected a list of events"};
  PadScript script;
  double t = 0.0;
  for (const YAML::Node& n : root) {
    auto e = readEvent(path, n, t);
    if (!e.ok()) return Error{e.error()};
    t = e->t_s;
    script.events_.push_back(std::move(e.value()));
  }
  return script;
}

void PadScript::playUntil(double t_s, haptics::VirtualPad& pad) {
  for (; next_ < events_.size() && events_[next_].t_s <= t_s; ++next_) {
    for (const PadEvent::Input& in : events_[next_].inputs) {
      if (!in.is_axis) {
        pad.setButton(in.index, in.value != 0.0);
      } else if (in.index == haptics::pad::kLeftTrigger || in.index == haptics::pad::kRightTrigger) {
        pad.setTrigger(in.index, in.value);
      } else {
        pad.setStick(in.index, in.value);
      }
    }
  }
}

}  // namespace hysim::tools
