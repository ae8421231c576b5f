#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>

#include "hysim/haptics/gamepad_mapping.hpp"

namespace hysim::haptics {
namespace {

GamepadInputs withAxis(int axis, double value) {
  GamepadInputs in;
  in.axes[axis] = value;
  return in;
}

GamepadInputs withButton(int button) {
  GamepadInputs in;
  in.buttons = 1u << button;
  return in;
}

TEST(GamepadDeadZone, ZeroInsideContinuousAtTheEdgeFullAtTheEnd) {
  const double dz = 0.2;
  for (double v : {0.0, 0.05, 0.1999, 0.2, -0.2, -0.15}) EXPECT_EQ(applyDeadZone(v, dz), 0.0) << v;
  // Just past the edge the output is just past zero: no jump.
  EXPECT_NEAR(applyDeadZone(0.2 + 1e-9, dz), 0.0, 1e-8);
  EXPECT_NEAR(applyDeadZone(-0.2 - 1e-9, dz), 0.0, 1e-8);
  EXPECT_NEAR(applyDeadZone(0.6, dz), 0.5, 1e-12);  // halfway between edge and end
  EXPECT_NEAR(applyDeadZone(-0.6, dz), -0.5, 1e-12);
  EXPECT_DOUBLE_EQ(applyDeadZone(1.0, dz), 1.0);
  EXPECT_DOUBLE_EQ(applyDeadZone(-1.0, dz), -1.0);
  EXPECT_DOUBLE_EQ(applyDeadZone(3.0, dz), 1.0);  // out of range: clamped
  EXPECT_EQ(applyDeadZone(std::numeric_limits<double>::quiet_NaN(), dz), 0.0);
  EXPECT_DOUBLE_EQ(applyDeadZone(0.37, 0.0), 0.37);  // no dead zone: the input itself
}

TEST(GamepadDeadZone, MonotonicAndOddOverTheWholeRange) {
  for (double dz : {0.0, 0.1, 0.25, 0.5}) {
    double previous = -2.0;
    for (int i = -1000; i <= 1000; ++i) {
      const double v = i / 1000.0;
      const double out = applyDeadZone(v, dz);
      EXPECT_GE(out, previous) << "dz " << dz << " v " << v;
      EXPECT_DOUBLE_EQ(out, -applyDeadZone(-v, dz));
      EXPECT_LE(std::fabs(out), 1.0);
      previous = out;
    }
  }
}

TEST(GamepadMapping, DefaultControllerEachInputDrivesItsOwnOutput) {
  const GamepadMapping m = defaultControllerMapping();
  // Left stick up (SDL: negative) = forward at full speed, nothing else moves.
  ManualCommand c = commandFromInputs(withAxis(pad::kLeftY, -1.0), m);
  EXPECT_DOUBLE_EQ(c.velocity_scope_mm_s.z(), m.advance.gain);
  EXPECT_EQ(c.velocity_scope_mm_s.x(), 0.0);
  EXPECT_EQ(c.velocity_scope_mm_s.y(), 0.0);
  EXPECT_EQ(c.yaw_rad_s, 0.0);
  EXPECT_EQ(c.pitch_rad_s, 0.0);
  EXPECT_EQ(c.extension_mm_s, 0.0);
  EXPECT_FALSE(c.pedal);
  EXPECT_DOUBLE_EQ(commandFromInputs(withAxis(pad::kLeftY, 1.0), m).velocity_scope_mm_s.z(), -m.advance.gain);
  // Left stick right = pan +x (the right arrow key).
  EXPECT_DOUBLE_EQ(commandFromInputs(withAxis(pad::kLeftX, 1.0), m).velocity_scope_mm_s.x(), m.pan_x.gain);
  // D-pad up/down = pan y.
  EXPECT_DOUBLE_EQ(commandFromInputs(withButton(pad::kDpadUp), m).velocity_scope_mm_s.y(), m.pan_y.gain);
  EXPECT_DOUBLE_EQ(commandFromInputs(withButton(pad::kDpadDown), m).velocity_scope_mm_s.y(), -m.pan_y.gain);
  // Right stick right = the D key (negative yaw); right stick up = PgUp (negative pitch).
  EXPECT_DOUBLE_EQ(commandFromInputs(withAxis(pad::kRightX, 1.0), m).yaw_rad_s, -m.yaw.gain);
  EXPECT_DOUBLE_EQ(commandFromInputs(withAxis(pad::kRightY, -1.0), m).pitch_rad_s, -m.pitch.gain);
  // Triggers: right extends, left retracts, both cancel.
  EXPECT_DOUBLE_EQ(commandFromInputs(withAxis(pad::kRightTrigger, 1.0), m).extension_mm_s, m.loop_extend.gain);
  EXPECT_DOUBLE_EQ(commandFromInputs(withAxis(pad::kLeftTrigger, 1.0), m).extension_mm_s, -m.loop_retract.gain);
  GamepadInputs both = withAxis(pad::kLeftTrigger, 1.0);
  both.axes[pad::kRightTrigger] = 1.0;
  EXPECT_DOUBLE_EQ(commandFromInputs(both, m).extension_mm_s, 0.0);
  // Right shoulder = pedal; Y = lens.
  EXPECT_TRUE(commandFromInputs(withButton(pad::kRightShoulder), m).pedal);
  EXPECT_TRUE(lensPressed(withButton(pad::kY), m));
  EXPECT_FALSE(lensPressed(withButton(pad::kX), m));
  // Nothing pressed: nothing moves.
  c = commandFromInputs(GamepadInputs{}, m);
  EXPECT_EQ(c.velocity_scope_mm_s, Eigen::Vector3d::Zero());
  EXPECT_EQ(c.yaw_rad_s + c.pitch_rad_s + c.extension_mm_s, 0.0);
  EXPECT_FALSE(c.pedal);
}

TEST(GamepadMapping, EveryStandardInputMovesAtMostOneOutput) {
  const GamepadMapping m = defaultControllerMapping();
  const auto outputs = [&](const GamepadInputs& in) {
    const ManualCommand c = commandFromInputs(in, m);
    return (c.velocity_scope_mm_s.x() != 0) + (c.velocity_scope_mm_s.y() != 0) + (c.velocity_scope_mm_s.z() != 0) +
           (c.yaw_rad_s != 0) + (c.pitch_rad_s != 0) + (c.extension_mm_s != 0) + (c.pedal ? 1 : 0);
  };
  for (int a = 0; a < pad::kNumAxes; ++a) {
    EXPECT_EQ(outputs(withAxis(a, 1.0)), 1) << "axis " << a;
  }
  int bound_buttons = 0;
  for (int b = 0; b < pad::kNumButtons; ++b) {
    const int n = outputs(withButton(b));
    EXPECT_LE(n, 1) << "button " << b;
    bound_buttons += n;
  }
  EXPECT_EQ(bound_buttons, 3);  // d-pad up, d-pad down, pedal (the lens is not a rate)
}

TEST(GamepadMapping, DeadZoneGainAndInvertPerBinding) {
  GamepadMapping m = defaultControllerMapping();
  m.advance = AxisBinding{};
  m.advance.axis = pad::kLeftY;
  m.advance.dead_zone = 0.25;
  m.advance.gain = 8.0;
  EXPECT_EQ(commandFromInputs(withAxis(pad::kLeftY, 0.25), m).velocity_scope_mm_s.z(), 0.0);
  EXPECT_NEAR(commandFromInputs(withAxis(pad::kLeftY, 0.625), m).velocity_scope_mm_s.z(), 4.0, 1e-12);
  m.advance.invert = true;
  EXPECT_NEAR(commandFromInputs(withAxis(pad::kLeftY, 0.625), m).velocity_scope_mm_s.z(), -4.0, 1e-12);
  // Axis and buttons add and clamp at full deflection.
  m.advance.button_positive = pad::kA;
  GamepadInputs in = withAxis(pad::kLeftY, -1.0);  // inverted: +1
  in.buttons = 1u << pad::kA;
  EXPECT_DOUBLE_EQ(commandFromInputs(in, m).velocity_scope_mm_s.z(), 8.0);
}

TEST(GamepadMapping, PedalFromATriggerThreshold) {
  GamepadMapping m = defaultControllerMapping();
  m.pedal_button = -1;
  m.pedal_axis = pad::kLeftTrigger;
  m.pedal_threshold = 0.6;
  EXPECT_FALSE(commandFromInputs(withAxis(pad::kLeftTrigger, 0.59), m).pedal);
  EXPECT_TRUE(commandFromInputs(withAxis(pad::kLeftTrigger, 0.6), m).pedal);
  EXPECT_FALSE(commandFromInputs(withButton(pad::kRightShoulder), m).pedal);
}

TEST(GamepadMapping, DefaultJoystickUsesRawIndices) {
  const GamepadMapping m = defaultJoystickMapping();
  EXPECT_EQ(m.layout, PadLayout::Joystick);
  EXPECT_DOUBLE_EQ(commandFromInputs(withAxis(1, -1.0), m).velocity_scope_mm_s.z(), m.advance.gain);
  EXPECT_DOUBLE_EQ(commandFromInputs(withButton(5), m).extension_mm_s, m.loop_extend.gain);
  EXPECT_DOUBLE_EQ(commandFromInputs(withButton(4), m).extension_mm_s, -m.loop_retract.gain);
  EXPECT_TRUE(commandFromInputs(withButton(0), m).pedal);
  EXPECT_TRUE(lensPressed(withButton(1), m));
}

TEST(GamepadMappingFile, KeysOverrideTheDefaults) {
  auto m = parseGamepadMapping(
      "name: my pad\n"
      "advance: { gain: 20, dead_zone: 0.1 }\n"
      "pan_y: { axis: right_y, invert: true, button_positive: none, button_negative: none }\n"
      "pedal: { button: none, axis: left_trigger, threshold: 0.7 }\n"
      "lens: { button: b }\n",
      "pad.yaml");
  ASSERT_TRUE(m.ok()) << m.error();
  const GamepadMapping d = defaultControllerMapping();
  EXPECT_EQ(m->name, "my pad");
  EXPECT_EQ(m->advance.gain, 20.0);
  EXPECT_EQ(m->advance.dead_zone, 0.1);
  EXPECT_EQ(m->advance.axis, d.advance.axis);      // kept
  EXPECT_EQ(m->advance.invert, d.advance.invert);  // kept
  EXPECT_EQ(m->pan_y.axis, pad::kRightY);
  EXPECT_TRUE(m->pan_y.invert);
  EXPECT_EQ(m->pan_y.button_positive, -1);
  EXPECT_EQ(m->pedal_button, -1);
  EXPECT_EQ(m->pedal_axis, pad::kLeftTrigger);
  EXPECT_EQ(m->pedal_threshold, 0.7);
  EXPECT_EQ(m->lens_button, pad::kB);
  EXPECT_EQ(m->yaw.gain, d.yaw.gain);
}

TEST(GamepadMappingFile, JoystickLayoutTakesNumbers) {
  auto m = parseGamepadMapping("layout: joystick\nyaw: { axis: 4 }\npedal: { button: 7 }\n", "j.yaml");
  ASSERT_TRUE(m.ok()) << m.error();
  EXPECT_EQ(m->layout, PadLayout::Joystick);
  EXPECT_EQ(m->yaw.axis, 4);
  EXPECT_EQ(m->pedal_button, 7);
  EXPECT_EQ(m->lens_button, defaultJoystickMapping().lens_button);
  // Names belong to the controller layout only.
  auto bad = parseGamepadMapping("layout: joystick\nyaw: { axis: right_x }\n", "j.yaml");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find("j.yaml:2:"), std::string::npos) << bad.error();
}

TEST(GamepadMappingFile, ErrorsNameFileLineAndKey) {
  const auto error = [](const std::string& text) {
    auto m = parseGamepadMapping(text, "pad.yaml");
    EXPECT_FALSE(m.ok()) << text;
    return m.ok() ? std::string() : m.error();
  };
  std::string e = error("name: x\nadvance:\n  gian: 3\n");
  EXPECT_NE(e.find("pad.yaml:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("advance.gian"), std::string::npos) << e;
  e = error("name: x\n\nspeed: 3\n");
  EXPECT_NE(e.find("pad.yaml:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("'speed'"), std::string::npos) << e;
  e = error("yaw:\n  dead_zone: 1.5\n");
  EXPECT_NE(e.find("pad.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("yaw.dead_zone"), std::string::npos) << e;
  e = error("pitch: { gain: fast }\n");
  EXPECT_NE(e.find("pitch.gain"), std::string::npos) << e;
  e = error("lens: { button: triangle }\n");
  EXPECT_NE(e.find("lens.button"), std::string::npos) << e;
  EXPECT_NE(e.find("triangle"), std::string::npos) << e;
  e = error("advance: { invert: maybe }\n");
  EXPECT_NE(e.find("advance.invert"), std::string::npos) << e;
  e = error("layout: wheel\n");
  EXPECT_NE(e.find("layout"), std::string::npos) << e;
  e = error("pedal: { threshold: 0 }\n");
  EXPECT_NE(e.find("pedal.threshold"), std::string::npos) << e;
  e = error("advance: [1, 2]\n");
  EXPECT_NE(e.find("advance"), std::string::npos) << e;
  e = error("advance: { gain: 3\n");  // not YAML at all
  EXPECT_NE(e.find("pad.yaml:"), std::string::npos) << e;
}

TEST(GamepadMappingFile, EmptyFileIsTheDefaultsAndAMissingFileIsAnError) {
  auto m = parseGamepadMapping("", "empty.yaml");
  ASSERT_TRUE(m.ok()) << m.error();
  EXPECT_EQ(m->advance.gain, defaultControllerMapping().advance.gain);
  auto missing = loadGamepadMapping("/nonexistent/pad.yaml");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().find("/nonexistent/pad.yaml"), std::string::npos);
}

TEST(GamepadMappingFile, ShippedDefaultFileEqualsTheBuiltInDefaults) {
  auto m = loadGamepadMapping(std::string(HYSIM_SOURCE_DIR) + "/haptics/gamepad/default.yaml");
  ASSERT_TRUE(m.ok()) << m.error();
  const GamepadMapping d = defaultControllerMapping();
  const std::pair<const AxisBinding*, const AxisBinding*> pairs[] = {
      {&m->advance, &d.advance}, {&m->pan_x, &d.pan_x}, {&m->pan_y, &d.pan_y}, {&m->yaw, &d.yaw},
      {&m->pitch, &d.pitch}, {&m->loop_extend, &d.loop_extend}, {&m->loop_retract, &d.loop_retract}};
  for (const auto& [a, b] : pairs) {
    EXPECT_EQ(a->axis, b->axis);
    EXPECT_EQ(a->button_positive, b->button_positive);
    EXPECT_EQ(a->button_negative, b->button_negative);
    EXPECT_EQ(a->dead_zone, b->dead_zone);
    EXPECT_EQ(a->gain, b->gain);
    EXPECT_EQ(a->invert, b->invert);
  }
  EXPECT_EQ(m->pedal_button, d.pedal_button);
  EXPECT_EQ(m->pedal_axis, d.pedal_axis);
  EXPECT_EQ(m->lens_button, d.lens_button);
}

}  // namespace
}  // namespace hysim::haptics
