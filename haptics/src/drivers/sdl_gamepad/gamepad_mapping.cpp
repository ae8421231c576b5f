#include "hysim/haptics/gamepad_mapping.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string_view>

#include "hysim/cutting/input_file.hpp"

namespace hysim::haptics {

namespace {

// Names of the standard layout's inputs in mapping files (index = pad::Axis / pad::Button).
constexpr std::array<std::string_view, pad::kNumAxes> kAxisNames = {
    "left_x", "left_y", "right_x", "right_y", "left_trigger", "right_trigger"};
constexpr std::array<std::string_view, pad::kNumButtons> kButtonNames = {
    "a", "b", "x", "y", "back", "guide", "start", "left_stick", "right_stick", "left_shoulder",
    "right_shoulder", "dpad_up", "dpad_down", "dpad_left", "dpad_right"};

constexpr double kStickDeadZone = 0.2;    // worn sticks rest up to ~0.2 off centre
constexpr double kTriggerDeadZone = 0.1;
constexpr double kSpeedMmS = 10.0;        // the keyboard's speeds (hysim_app.cpp)
constexpr double kTurnRadS = 0.6;
constexpr double kExtendMmS = 5.0;

AxisBinding stick(int axis, double gain, bool invert) {
  AxisBinding b;
  b.axis = axis;
  b.dead_zone = kStickDeadZone;
  b.gain = gain;
  b.invert = invert;
  return b;
}

}  // namespace

int padAxisIndex(std::string_view name) {
  for (int i = 0; i < pad::kNumAxes; ++i) {
    if (kAxisNames[i] == name) return i;
  }
  return -1;
}

int padButtonIndex(std::string_view name) {
  for (int i = 0; i < pad::kNumButtons; ++i) {
    if (kButtonNames[i] == name) return i;
  }
  return -1;
}

GamepadMapping defaultControllerMapping() {
  GamepadMapping m;
  m.name = "default controller";
  m.layout = PadLayout::Controller;
  // SDL reports stick up as negative: invert where up/forward should be positive. Yaw and
  // pitch follow the keyboard (stick right = D, stick up = PgUp: the view turns that way).
  m.advance = stick(pad::kLeftY, kSpeedMmS, true);
  m.pan_x = stick(pad::kLeftX, kSpeedMmS, false);
  m.pan_y.button_positive = pad::kDpadUp;
  m.pan_y.button_negative = pad::kDpadDown;
  m.pan_y.gain = kSpeedMmS;
  m.yaw = stick(pad::kRightX, kTurnRadS, true);
  m.pitch = stick(pad::kRightY, kTurnRadS, false);
  m.loop_extend.axis = pad::kRightTrigger;
  m.loop_extend.dead_zone = kTriggerDeadZone;
  m.loop_extend.gain = kExtendMmS;
  m.loop_retract.axis = pad::kLeftTrigger;
  m.loop_retract.dead_zone = kTriggerDeadZone;
  m.loop_retract.gain = kExtendMmS;
  m.pedal_button = pad::kRightShoulder;
  m.lens_button = pad::kY;
  return m;
}

GamepadMapping defaultJoystickMapping() {
  GamepadMapping m;
  m.name = "default joystick";
  m.layout = PadLayout::Joystick;
  m.advance = stick(1, kSpeedMmS, true);
  m.pan_x = stick(0, kSpeedMmS, false);
  m.yaw = stick(2, kTurnRadS, true);
  m.pitch = stick(3, kTurnRadS, false);
  m.loop_extend.button_positive = 5;
  m.loop_extend.gain = kExtendMmS;
  m.loop_retract.button_positive = 4;
  m.loop_retract.gain = kExtendMmS;
  m.pedal_button = 0;
  m.lens_button = 1;
  return m;
}

double applyDeadZone(double value, double dead_zone) {
  if (!std::isfinite(value)) return 0.0;
  const double v = std::clamp(value, -1.0, 1.0);
  const double dz = std::clamp(dead_zone, 0.0, 0.999);
  const double a = std::fabs(v);
  if (a <= dz) return 0.0;
  return std::copysign((a - dz) / (1.0 - dz), v);
}

namespace {
bool buttonDown(const GamepadInputs& in, int button) {
  return button >= 0 && button < kMaxPadButtons && (in.buttons >> button) & 1u;
}
}  // namespace

double bindingValue(const GamepadInputs& in, const AxisBinding& b) {
  double v = 0.0;
  if (b.axis >= 0 && b.axis < kMaxPadAxes) {
    v += applyDeadZone(b.invert ? -in.axes[b.axis] : in.axes[b.axis], b.dead_zone);
  }
  if (buttonDown(in, b.button_positive)) v += 1.0;
  if (buttonDown(in, b.button_negative)) v -= 1.0;
  return b.gain * std::clamp(v, -1.0, 1.0);
}

bool pedalPressed(const GamepadInputs& in, const GamepadMapping& m) {
  if (buttonDown(in, m.pedal_button)) return true;
  return m.pedal_axis >= 0 && m.pedal_axis < kMaxPadAxes && in.axes[m.pedal_axis] >= m.pedal_threshold;
}

bool lensPressed(const GamepadInputs& in, const GamepadMapping& m) { return buttonDown(in, m.lens_button); }

ManualCommand commandFromInputs(const GamepadInputs& in, const GamepadMapping& m) {
  ManualCommand c;
  c.velocity_scope_mm_s = {bindingValue(in, m.pan_x), bindingValue(in, m.pan_y), bindingValue(in, m.advance)};
  c.yaw_rad_s = bindingValue(in, m.yaw);
  c.pitch_rad_s = bindingValue(in, m.pitch);
  c.extension_mm_s = bindingValue(in, m.loop_extend) - bindingValue(in, m.loop_retract);
  c.pedal = pedalPressed(in, m);
  return c;
}

// ---------------------------------------------------------------------------------------
// Mapping files.

namespace {

// Reads one mapping file; the first error found is kept (later checks are skipped).
class MappingReader {
 public:
  explicit MappingReader(std::string source) : source_(std::move(source)) {}
  const std::string& error() const { return error_; }

  void read(const YAML::Node& root, GamepadMapping& m);

 private:
  bool failed() const { return !error_.empty(); }
  void fail(const YAML::Node& at, const std::string& what) {
    if (failed()) return;
    error_ = source_ + ":" + std::to_string(at.Mark().line + 1) + ": " + what;
  }
  void checkKeys(const YAML::Node& map, const std::string& where, std::initializer_list<std::string_view> keys);
  int input(const YAML::Node& n, const std::string& key, bool is_axis, PadLayout layout);
  double number(const YAML::Node& n, const std::string& key, double lo, double hi, bool hi_open);
  bool flag(const YAML::Node& n, const std::string& key);
  void binding(const YAML::Node& n, const std::string& key, PadLayout layout, AxisBinding& b);
  void pedal(const YAML::Node& n, PadLayout layout, GamepadMapping& m);

  std::string source_;
  std::string error_;
};

void MappingReader::checkKeys(const YAML::Node& map, const std::string& where,
                              std::initializer_list<std::string_view> keys) {
  if (!map.IsMap()) {
    fail(map, "'" + where + "' must be a map of keys");
    return;
  }
  for (const auto& kv : map) {
    if (!kv.first.IsScalar()) {
      fail(kv.first, "'" + where + "': a key must be a name");
      return;
    }
    const std::string k = kv.first.Scalar();
    if (std::find(keys.begin(), keys.end(), k) != keys.end()) continue;
    std::string expected;
    for (std::string_view e : keys) expected += (expected.empty() ? "" : ", ") + std::string(e);
    fail(kv.first, "unknown key '" + (where.empty() ? k : where + "." + k) + "' (expected " + expected + ")");
  }
}

// An axis or button: a standard-layout name ("left_y", "a"), an index, or "none" (-1).
int MappingReader::input(const YAML::Node& n, const std::string& key, bool is_axis, PadLayout layout) {
  const std::string kind = is_axis ? "axis" : "button";
  if (!n.IsScalar()) {
    fail(n, "'" + key + "': expected an " + kind + " name or number");
    return -1;
  }
  const std::string s = n.Scalar();
  if (s == "none") return -1;
  if (layout == PadLayout::Controller) {
    if (is_axis) {
      if (const int i = padAxisIndex(s); i >= 0) return i;
    } else {
      if (const int i = padButtonIndex(s); i >= 0) return i;
    }
  }
  const int limit = is_axis ? kMaxPadAxes : kMaxPadButtons;
  char* end = nullptr;
  const long v = std::strtol(s.c_str(), &end, 10);
  if (s.empty() || *end != '\0' || v < 0 || v >= limit) {
    fail(n, "'" + key + "': bad " + kind + " '" + s + "' (" +
                (layout == PadLayout::Controller ? "a standard-layout name, " : "") + "0.." +
                std::to_string(limit - 1) + " or none)");
    return -1;
  }
  return static_cast<int>(v);
}

double MappingReader::number(const YAML::Node& n, const std::string& key, double lo, double hi, bool hi_open) {
  double v = 0.0;
  try {
    v = n.as<double>();
  } catch (const YAML::Exception&) {
    fail(n, "'" + key + "': expected a number");
    return 0.0;
  }
  if (!std::isfinite(v) || v < lo || v > hi || (hi_open && v == hi)) {
    std::ostringstream range;
    range << "[" << lo << ", " << hi << (hi_open ? ")" : "]");
    fail(n, "'" + key + "': " + n.Scalar() + " is outside " + range.str());
  }
  return v;
}

bool MappingReader::flag(const YAML::Node& n, const std::string& key) {
  try {
    return n.as<bool>();
  } catch (const YAML::Exception&) {
    fail(n, "'" + key + "': expected true or false");
    return false;
  }
}

// The keys given replace those of the default binding; the rest stays.
void MappingReader::binding(const YAML::Node& n, const std::string& key, PadLayout layout, AxisBinding& b) {
  checkKeys(n, key, {"axis", "button_positive", "button_negative", "dead_zone", "gain", "invert"});
  if (failed()) return;
  if (n["axis"]) b.axis = input(n["axis"], key + ".axis", true, layout);
  if (n["button_positive"]) b.button_positive = input(n["button_positive"], key + ".button_positive", false, layout);
  if (n["button_negative"]) b.button_negative = input(n["button_negative"], key + ".button_negative", false, layout);
  if (n["dead_zone"]) b.dead_zone = number(n["dead_zone"], key + ".dead_zone", 0.0, 1.0, true);
  if (n["gain"]) b.gain = number(n["gain"], key + ".gain", 0.0, 1e3, false);
  if (n["invert"]) b.invert = flag(n["invert"], key + ".invert");
}

void MappingReader::pedal(const YAML::Node& n, PadLayout layout, GamepadMapping& m) {
  checkKeys(n, "pedal", {"button", "axis", "threshold"});
  if (failed()) return;
  if (n["button"]) m.pedal_button = input(n["button"], "pedal.button", false, layout);
  if (n["axis"]) m.pedal_axis = input(n["axis"], "pedal.axis", true, layout);
  if (n["threshold"]) m.pedal_threshold = number(n["threshold"], "pedal.threshold", 0.01, 1.0, false);
}

void MappingReader::read(const YAML::Node& root, GamepadMapping& m) {
  if (!root.IsMap()) {
    fail(root, "a mapping file is a map of keys (name, layout, advance, ...)");
    return;
  }
  checkKeys(root, "", {"name", "layout", "advance", "pan_x", "pan_y", "yaw", "pitch", "loop_extend",
                       "loop_retract", "pedal", "lens"});
  if (failed()) return;
  // The layout first: it picks the defaults the other keys override.
  if (const YAML::Node l = root["layout"]) {
    const std::string s = l.IsScalar() ? l.Scalar() : "";
    if (s == "controller") m = defaultControllerMapping();
    else if (s == "joystick") m = defaultJoystickMapping();
    else return fail(l, "'layout': expected controller or joystick");
  }
  if (const YAML::Node name = root["name"]) {
    if (!name.IsScalar()) return fail(name, "'name': expected text");
    m.name = name.Scalar();
  }
  const std::pair<const char*, AxisBinding*> bindings[] = {
      {"advance", &m.advance}, {"pan_x", &m.pan_x},       {"pan_y", &m.pan_y},
      {"yaw", &m.yaw},         {"pitch", &m.pitch},       {"loop_extend", &m.loop_extend},
      {"loop_retract", &m.loop_retract}};
  for (const auto& [key, b] : bindings) {
    if (root[key]) binding(root[key], key, m.layout, *b);
  }
  if (root["pedal"]) pedal(root["pedal"], m.layout, m);
  if (const YAML::Node lens = root["lens"]) {
    checkKeys(lens, "lens", {"button"});
    if (!failed() && lens["button"]) m.lens_button = input(lens["button"], "lens.button", false, m.layout);
  }
}

}  // namespace

Result<GamepadMapping> parseGamepadMapping(const std::string& yaml_text, const std::string& source_name) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    return Error{source_name + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg};
  }
  GamepadMapping m = defaultControllerMapping();
  if (root.IsNull()) return m;  // an empty file: the defaults
  MappingReader reader(source_name);
  reader.read(root, m);
  if (!reader.error().empty()) return Error{reader.error()};
  return m;
}

Result<GamepadMapping> loadGamepadMapping(const std::string& path) {
  Result<std::string> text = readInputFile(path, kMaxYamlFileBytes, "gamepad mapping");
  if (!text.ok()) return Error{text.error()};
  return parseGamepadMapping(*text, path);
}

}  // namespace hysim::haptics
