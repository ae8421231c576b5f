#include "hysim/haptics/sdl_gamepad.hpp"

#include <SDL.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace hysim::haptics {

// The mapping's standard-layout indices are SDL's own.
constexpr bool sameIndex(int ours, int sdl) { return ours == sdl; }
static_assert(sameIndex(pad::kLeftY, SDL_CONTROLLER_AXIS_LEFTY) &&
              sameIndex(pad::kRightTrigger, SDL_CONTROLLER_AXIS_TRIGGERRIGHT) &&
              sameIndex(pad::kNumAxes, SDL_CONTROLLER_AXIS_MAX));
static_assert(sameIndex(pad::kY, SDL_CONTROLLER_BUTTON_Y) &&
              sameIndex(pad::kRightShoulder, SDL_CONTROLLER_BUTTON_RIGHTSHOULDER) &&
              sameIndex(pad::kDpadRight, SDL_CONTROLLER_BUTTON_DPAD_RIGHT));

namespace {

constexpr Uint32 kSubsystems = SDL_INIT_JOYSTICK | SDL_INIT_GAMECONTROLLER;

double stickValue(Sint16 raw) { return std::clamp(raw / 32767.0, -1.0, 1.0); }

}  // namespace

DeviceInfo SdlGamepadOptions::defaultInfo() {
  DeviceInfo info = ManualDevice::defaultInfo();
  info.name = "game controller (SDL)";
  info.num_buttons = 2;  // 0: cut pedal, 1: lens button
  info.rate_hz = 1000.0; // read as often as the simulation steps
  return info;
}

Result<std::unique_ptr<SdlGamepadDevice>> SdlGamepadDevice::open(const ToolPose& start, double start_time_s,
                                                                  SdlGamepadOptions options) {
  if (SDL_InitSubSystem(kSubsystems) != 0) {
    return Error{std::string("SDL joystick/game controller subsystem: ") + SDL_GetError()};
  }
  // The haptic subsystem is optional (it needs /dev/input): without it, rumble only.
  const bool haptic_subsystem = SDL_InitSubSystem(SDL_INIT_HAPTIC) == 0;
  const int index = options.device_index;
  // From here on the device's destructor gives the subsystems back, on error paths too.
  std::unique_ptr<SdlGamepadDevice> device(
      new SdlGamepadDevice(start, start_time_s, std::move(options), haptic_subsystem));
  if (index < 0 || index >= SDL_NumJoysticks()) {
    return Error{"no game controller or joystick at index " + std::to_string(index) + " (" +
                 std::to_string(SDL_NumJoysticks()) + " attached)"};
  }
  if (!device->openPad(index)) return Error{std::string("cannot open the game controller: ") + SDL_GetError()};
  return device;
}

SdlGamepadDevice::SdlGamepadDevice(const ToolPose& start, double start_time_s, SdlGamepadOptions options,
                                   bool haptic_subsystem)
    : manual_(start, start_time_s, options.info),
      info_(std::move(options.info)),
      user_mapping_(std::move(options.mapping)),
      haptic_subsystem_(haptic_subsystem),
      scope_rotation_(start.rotation),
      last_read_s_(start_time_s) {}

SdlGamepadDevice::~SdlGamepadDevice() {
  // A pad must never keep rumbling after its device is gone.
  if (SDL_WasInit(SDL_INIT_JOYSTICK) != 0) {
    if (connected()) {
      if (controller_ != nullptr) SDL_GameControllerRumble(controller_, 0, 0, 0);
      else if (joystick_ != nullptr) SDL_JoystickRumble(joystick_, 0, 0, 0);
    }
    closePad();
    if (haptic_subsystem_) SDL_QuitSubSystem(SDL_INIT_HAPTIC);
    SDL_QuitSubSystem(kSubsystems);
  }
}

// Opens the pad as a controller when SDL knows it as one and the mapping (if given) uses the
// standard layout; as a raw joystick otherwise. Picks the mapping that matches.
bool SdlGamepadDevice::openPad(int index) {
  const bool want_controller =
      SDL_IsGameController(index) && (!user_mapping_ || user_mapping_->layout == PadLayout::Controller);
  if (want_controller) {
    controller_ = SDL_GameControllerOpen(index);
    if (controller_ == nullptr) return false;
    joystick_ = SDL_GameControllerGetJoystick(controller_);
    pad_name_ = SDL_GameControllerName(controller_) ? SDL_GameControllerName(controller_) : "controller";
    has_rumble_ = SDL_GameControllerHasRumble(controller_) == SDL_TRUE;
  } else {
    joystick_ = SDL_JoystickOpen(index);
    if (joystick_ == nullptr) return false;
    pad_name_ = SDL_JoystickName(joystick_) ? SDL_JoystickName(joystick_) : "joystick";
    has_rumble_ = SDL_JoystickHasRumble(joystick_) == SDL_TRUE;
  }
  using_controller_ = want_controller;
  const SDL_JoystickGUID guid = SDL_JoystickGetGUID(joystick_);
  std::memcpy(guid_.data(), guid.data, guid_.size());
  if (user_mapping_ && user_mapping_->layout == (want_controller ? PadLayout::Controller : PadLayout::Joystick)) {
    mapping_ = *user_mapping_;
  } else {
    mapping_ = want_controller ? defaultControllerMapping() : defaultJoystickMapping();
  }
  // A real force channel where the pad has one.
  if (SDL_WasInit(SDL_INIT_HAPTIC) != 0 && SDL_JoystickIsHaptic(joystick_) == SDL_TRUE) {
    haptic_ = SDL_HapticOpenFromJoystick(joystick_);
    if (haptic_ != nullptr && (SDL_HapticQuery(haptic_) & SDL_HAPTIC_CONSTANT) == 0) {
      SDL_HapticClose(haptic_);
      haptic_ = nullptr;
    }
  }
  connected_.store(true, std::memory_order_relaxed);
  return true;
}

void SdlGamepadDevice::closePad() {
  if (haptic_ != nullptr) {
    if (effect_id_ >= 0) SDL_HapticDestroyEffect(haptic_, effect_id_);
    SDL_HapticClose(haptic_);
  }
  haptic_ = nullptr;
  effect_id_ = -1;
  sent_level_ = 0;
  if (controller_ != nullptr) SDL_GameControllerClose(controller_);
  else if (joystick_ != nullptr) SDL_JoystickClose(joystick_);
  controller_ = nullptr;
  joystick_ = nullptr;
  has_rumble_ = false;
}

DeviceCounters SdlGamepadDevice::counters() const {
  DeviceCounters c;
  c.disconnects = disconnects_.load(std::memory_order_relaxed);
  c.reconnects = reconnects_.load(std::memory_order_relaxed);
  return c;
}

// Standard-layout values from a controller (triggers 0..1), the joystick's own otherwise.
void SdlGamepadDevice::pollInputs(GamepadInputs& in) const {
  in = GamepadInputs{};
  if (controller_ != nullptr) {
    for (int a = 0; a < pad::kNumAxes; ++a) {
      in.axes[a] = stickValue(SDL_GameControllerGetAxis(controller_, static_cast<SDL_GameControllerAxis>(a)));
    }
    for (int b = 0; b < SDL_CONTROLLER_BUTTON_MAX && b < kMaxPadButtons; ++b) {
      if (SDL_GameControllerGetButton(controller_, static_cast<SDL_GameControllerButton>(b))) in.buttons |= 1u << b;
    }
    return;
  }
  const int axes = std::min(SDL_JoystickNumAxes(joystick_), kMaxPadAxes);
  for (int a = 0; a < axes; ++a) in.axes[a] = stickValue(SDL_JoystickGetAxis(joystick_, a));
  const int buttons = std::min(SDL_JoystickNumButtons(joystick_), kMaxPadButtons);
  for (int b = 0; b < buttons; ++b) {
    if (SDL_JoystickGetButton(joystick_, b)) in.buttons |= 1u << b;
  }
}

// Unplugged: the tool stops where it is, the pedal lets go, no force is rendered.
void SdlGamepadDevice::handleDetach() {
  connected_.store(false, std::memory_order_relaxed);
  disconnects_.fetch_add(1, std::memory_order_relaxed);
  manual_.setCommand(ManualCommand{});
  last_force_.setZero();
  low_target_ = high_target_ = sent_low_ = sent_high_ = 0;
  closePad();
  lens_was_down_ = false;
}

// A pad is there again: the one unplugged if present (same GUID), else the first.
void SdlGamepadDevice::tryReconnect() {
  const int n = SDL_NumJoysticks();
  if (n <= 0) return;
  int index = 0;
  for (int i = 0; i < n; ++i) {
    const SDL_JoystickGUID g = SDL_JoystickGetDeviceGUID(i);
    if (std::memcmp(g.data, guid_.data(), guid_.size()) == 0) {
      index = i;
      break;
    }
  }
  if (!openPad(index)) return;
  reconnects_.fetch_add(1, std::memory_order_relaxed);
  pedal_locked_ = true;  // a pedal held while plugging in must not start a cut
  lens_was_down_ = true; // nor does a held lens button count as a press
}

DeviceState SdlGamepadDevice::read(double t) {
  if (controller_ != nullptr) SDL_GameControllerUpdate();
  else SDL_JoystickUpdate();
  if (connected() && SDL_JoystickGetAttached(joystick_) == SDL_FALSE) handleDetach();
  if (!connected()) tryReconnect();

  std::uint32_t extra_buttons = 0;
  if (connected()) {
    GamepadInputs in;
    pollInputs(in);
    ManualCommand c = commandFromInputs(in, mapping_);
    if (pedal_locked_ && !c.pedal) pedal_locked_ = false;
    if (pedal_locked_) c.pedal = false;
    manual_.setCommand(c);
    const bool lens_down = lensPressed(in, mapping_);
    if (lens_down && !lens_was_down_) setLensIndex(lens_index_ + 1);
    lens_was_down_ = lens_down;
    if (lens_down) extra_buttons |= 2u;  // bit 1: the lens button
  }
  DeviceState s = manual_.read(t);
  s.buttons |= extra_buttons;
  scope_rotation_ = s.pose.rotation;
  last_read_s_ = s.time_s;
  // The serosa cue runs on read time so that it is the same on every run.
  const bool pulse_on = serosa_warning_ && std::fmod(std::max(t, 0.0), kSerosaPeriodS) < kSerosaOnS;
  high_target_ = pulse_on ? kSerosaPulse : 0;
  updateRumble(t);
  return s;
}

void SdlGamepadDevice::commandForce(const Eigen::Vector3d& force_n) {
  if (!connected()) {
    last_force_.setZero();
    return;
  }
  last_force_ = safeForce(force_n, info_.max_force_n);
  if (haptic_ != nullptr) {
    updateConstantForce(last_force_);
    return;
  }
  const double fraction = std::clamp(last_force_.norm() / info_.max_force_n, 0.0, 1.0);
  low_target_ = static_cast<std::uint16_t>(std::lround(fraction * 0xFFFF));
  updateRumble(last_read_s_);
}

// Sends the motors' targets when they changed noticeably, reached 0 or full, or are due a
// refresh; SDL drops a repeat of the same values itself, so a refresh costs no USB traffic.
void SdlGamepadDevice::updateRumble(double time_s) {
  if (!connected() || !has_rumble_) return;
  const auto moved = [](std::uint16_t target, std::uint16_t sent) {
    if (target == sent) return false;
    if (target == 0 || target == 0xFFFF) return true;
    return std::abs(static_cast<int>(target) - static_cast<int>(sent)) >= kRumbleStep;
  };
  const bool due = time_s - last_rumble_s_ >= kRumbleRefreshS && (low_target_ != 0 || high_target_ != 0);
  if (!due && !moved(low_target_, sent_low_) && !moved(high_target_, sent_high_)) return;
  const std::uint16_t low = moved(low_target_, sent_low_) ? low_target_ : sent_low_;
  const std::uint16_t high = moved(high_target_, sent_high_) ? high_target_ : sent_high_;
  const int rc = controller_ != nullptr ? SDL_GameControllerRumble(controller_, low, high, kRumbleHoldMs)
                                        : SDL_JoystickRumble(joystick_, low, high, kRumbleHoldMs);
  if (rc != 0) return;  // not sent (the pad went away): retried at the next change
  sent_low_ = low;
  sent_high_ = high;
  last_rumble_s_ = time_s;
}

// A constant effect pushing the stick the way the tissue pushes the scope: the advance stick's
// axis (SDL y, south = towards the user) carries the force along the scope's axis, x the
// sideways part. SDL's direction is where the force comes from, hence the minus signs.
void SdlGamepadDevice::updateConstantForce(const Eigen::Vector3d& force_n) {
  const Eigen::Vector3d f = scope_rotation_.transpose() * force_n;  // scope frame
  const double push_x = f.x(), push_y = -f.z();
  const auto level = static_cast<Sint16>(
      std::lround(32767.0 * std::clamp(std::hypot(push_x, push_y) / info_.max_force_n, 0.0, 1.0)));
  // Small changes are not worth a USB packet; reaching zero always is, once.
  if (effect_id_ >= 0 && (level == sent_level_ || (level != 0 && std::abs(level - sent_level_) < 256))) return;
  SDL_HapticEffect e;
  std::memset(&e, 0, sizeof(e));
  e.type = SDL_HAPTIC_CONSTANT;
  e.constant.direction.type = SDL_HAPTIC_CARTESIAN;
  e.constant.direction.dir[0] = static_cast<Sint32>(std::lround(-1e4 * push_x));
  e.constant.direction.dir[1] = static_cast<Sint32>(std::lround(-1e4 * push_y));
  e.constant.length = SDL_HAPTIC_INFINITY;
  e.constant.level = level;
  if (effect_id_ < 0) {
    effect_id_ = SDL_HapticNewEffect(haptic_, &e);
    if (effect_id_ >= 0) SDL_HapticRunEffect(haptic_, effect_id_, 1);
  } else {
    SDL_HapticUpdateEffect(haptic_, effect_id_, &e);
  }
  sent_level_ = level;
}

}  // namespace hysim::haptics
