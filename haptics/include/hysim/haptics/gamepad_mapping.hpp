#pragma once
// How a game controller's sticks, triggers and buttons drive the scope: which input does
// what, dead zones, gains and signs. Free of SDL: the driver (sdl_gamepad.hpp) turns SDL's
// readings into GamepadInputs, and commandFromInputs() turns those into the ManualDevice's
// rate command, so the mapping is testable without a pad.
#include <array>
#include <cstdint>
#include <string>
#include <string_view>

#include "hysim/cutting/result.hpp"
#include "hysim/haptics/device.hpp"

namespace hysim::haptics {

// Input indices of SDL's GameController standard layout (Xbox, PlayStation and Switch pads
// are all mapped onto it by position: `a` is the bottom face button). For a raw joystick the
// indices are the joystick's own axis and button numbers.
namespace pad {
enum Axis : int { kLeftX = 0, kLeftY, kRightX, kRightY, kLeftTrigger, kRightTrigger, kNumAxes };
enum Button : int {
  kA = 0, kB, kX, kY, kBack, kGuide, kStart, kLeftStick, kRightStick, kLeftShoulder, kRightShoulder,
  kDpadUp, kDpadDown, kDpadLeft, kDpadRight, kNumButtons
};
}  // namespace pad

// The standard layout's input names ("left_y", "right_trigger"; "a", "right_shoulder"), as
// mapping files write them: the index, or -1 for a name that is not one.
int padAxisIndex(std::string_view name);
int padButtonIndex(std::string_view name);

inline constexpr int kMaxPadAxes = 16;     // raw joysticks beyond this are read up to it
inline constexpr int kMaxPadButtons = 32;  // buttons fit one bit each

// One sample of the pad: sticks in [-1, 1] (SDL's sign: right and down positive), triggers
// in [0, 1] (at rest 0), button i pressed = bit i.
struct GamepadInputs {
  std::array<double, kMaxPadAxes> axes{};
  std::uint32_t buttons = 0;
};

// One output (a velocity component, a turn rate, a loop speed): an analogue axis and/or a
// pair of buttons. value = gain * clamp(rescaled axis + button_positive - button_negative).
struct AxisBinding {
  int axis = -1;             // input axis; -1: none
  int button_positive = -1;  // held: full deflection one way; -1: none
  int button_negative = -1;  // held: full deflection the other way
  double dead_zone = 0.0;    // fraction of full deflection read as zero, [0, 1)
  double gain = 0.0;         // output at full deflection: mm/s or rad/s
  bool invert = false;       // flips the axis (not the buttons)
};

enum class PadLayout { Controller, Joystick };

struct GamepadMapping {
  std::string name = "default controller";
  PadLayout layout = PadLayout::Controller;  // which index space the bindings use
  AxisBinding advance;       // along the scope axis, + forward (mm/s)
  AxisBinding pan_x;         // scope x, the keyboard's right arrow (mm/s)
  AxisBinding pan_y;         // scope up (mm/s)
  AxisBinding yaw;           // about the scope's up direction (rad/s), keyboard A = +
  AxisBinding pitch;         // about the scope's x direction (rad/s), keyboard PgDn = +
  AxisBinding loop_extend;   // loop out (mm/s); a trigger
  AxisBinding loop_retract;  // loop in (mm/s); a trigger
  int pedal_button = -1;     // cut pedal while held; -1: none
  int pedal_axis = -1;       // or: cut pedal while this axis reads >= pedal_threshold
  double pedal_threshold = 0.5;
  int lens_button = -1;      // a press steps the lens angle 0 -> 12 -> 30 -> 0 degrees
};

// SDL GameController layout (Xbox/PlayStation/Switch): left stick advance (up = forward) and
// pan x, d-pad up/down pan y, right stick yaw and pitch, right trigger extends the loop, left
// trigger retracts it, right shoulder is the cut pedal, Y (triangle) steps the lens angle.
GamepadMapping defaultControllerMapping();
// A joystick SDL does not know as a controller: axes 0/1 left stick, 2/3 right stick,
// buttons 0 pedal, 1 lens, 4/5 loop in/out (no triggers assumed).
GamepadMapping defaultJoystickMapping();

// Reads a mapping file (YAML, documented in haptics/README.md): the keys given override the
// defaults of its `layout`. Errors name the file, line and key.
Result<GamepadMapping> loadGamepadMapping(const std::string& path);
// Same, from YAML text (`source_name` stands for the file in messages).
Result<GamepadMapping> parseGamepadMapping(const std::string& yaml_text, const std::string& source_name);

// The dead zone taken out and the rest stretched back to [0, 1], so the output starts at 0 at
// the zone's edge (continuous) and reaches full at full deflection. Input clamped to [-1, 1].
double applyDeadZone(double value, double dead_zone);
// One binding's output: gain * clamp(axis + buttons, -1, 1).
double bindingValue(const GamepadInputs& in, const AxisBinding& b);
bool pedalPressed(const GamepadInputs& in, const GamepadMapping& m);
bool lensPressed(const GamepadInputs& in, const GamepadMapping& m);

// The scope's rate command for one sample of the pad (pedal included).
ManualCommand commandFromInputs(const GamepadInputs& in, const GamepadMapping& m);

}  // namespace hysim::haptics
