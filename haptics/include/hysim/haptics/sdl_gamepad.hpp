#pragma once
// A game controller or joystick (SDL2) as the scope's input device. Sticks and triggers are
// rate commands for a ManualDevice (the same kinematics as the keyboard), a button is the cut
// pedal, another steps the lens angle. Force cues go back as a constant force where the pad
// has one (SDL_HAPTIC_CONSTANT), else as rumble following the contact force, with a pulsing
// second motor near the serosa. Unplugging freezes the tool and zeroes the force; plugging a
// pad in again resumes from where the tool stood.
//
// Part of the haptics_sdl library: `haptics` itself needs only Eigen. All calls from the
// thread that owns the simulation (SDL's joystick API is not for concurrent use), except
// connected() and counters(), which any thread may call.
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "hysim/cutting/result.hpp"
#include "hysim/haptics/device.hpp"
#include "hysim/haptics/gamepad_mapping.hpp"

struct _SDL_Joystick;
struct _SDL_GameController;
struct _SDL_Haptic;

namespace hysim::haptics {

struct SdlGamepadOptions {
  int device_index = 0;                   // SDL joystick index opened first
  std::optional<GamepadMapping> mapping;  // none: defaultControllerMapping() or defaultJoystickMapping()
  DeviceInfo info = defaultInfo();
  static DeviceInfo defaultInfo();
};

class SdlGamepadDevice final : public Device {
 public:
  static constexpr std::array<int, 3> kLensDeg = {0, 12, 30};
  // Rumble: the low-frequency motor follows |F| / max_force; it is re-sent only when the
  // level moved by kRumbleStep or more (or reached 0 or full), and refreshed every
  // kRumbleRefreshS of read time with a kRumbleHoldMs duration, so a stalled or paused
  // simulation lets the pad fall silent by itself.
  static constexpr std::uint16_t kRumbleStep = 0x0400;
  static constexpr std::uint32_t kRumbleHoldMs = 500;
  static constexpr double kRumbleRefreshS = 0.1;
  // Near the serosa the high-frequency motor pulses: on for the first kSerosaOnS of every
  // kSerosaPeriodS of read time.
  static constexpr std::uint16_t kSerosaPulse = 0xFFFF;
  static constexpr double kSerosaOnS = 0.1;
  static constexpr double kSerosaPeriodS = 0.2;

  // Initialises SDL's joystick and game controller subsystems (reference-counted by SDL; the
  // haptic subsystem only if available) and opens the pad at options.device_index. Fails
  // with SDL's message when SDL cannot start or no pad is attached.
  static Result<std::unique_ptr<SdlGamepadDevice>> open(const ToolPose& start, double start_time_s,
                                                         SdlGamepadOptions options = {});
  ~SdlGamepadDevice() override;
  SdlGamepadDevice(const SdlGamepadDevice&) = delete;
  SdlGamepadDevice& operator=(const SdlGamepadDevice&) = delete;

  const DeviceInfo& info() const override { return info_; }
  // Polls the pad, handles unplug / replug, integrates the command up to time_s. Allocates
  // nothing, except SDL's own handles when a pad is plugged in again.
  DeviceState read(double time_s) override;
  void commandForce(const Eigen::Vector3d& force_n) override;
  const Eigen::Vector3d& lastForce() const override { return last_force_; }
  bool connected() const override { return connected_.load(std::memory_order_relaxed); }
  DeviceCounters counters() const override;

  // The serosa cue (the app sets it from the wire's clearance); takes effect at the next read.
  void setSerosaWarning(bool on) { serosa_warning_ = on; }
  int lensIndex() const { return lens_index_; }
  int lensDeg() const { return kLensDeg[lens_index_]; }
  void setLensIndex(int index) { lens_index_ = ((index % 3) + 3) % 3; }

  const std::string& padName() const { return pad_name_; }      // the last pad opened
  bool isController() const { return using_controller_; }  // else a raw joystick
  bool hasConstantForce() const { return haptic_ != nullptr; }
  const GamepadMapping& mapping() const { return mapping_; }
  std::uint16_t rumbleLow() const { return sent_low_; }   // the values last sent
  std::uint16_t rumbleHigh() const { return sent_high_; }

 private:
  SdlGamepadDevice(const ToolPose& start, double start_time_s, SdlGamepadOptions options, bool haptic_subsystem);
  bool openPad(int index);   // stage: SDL handles for the pad at `index`
  void closePad();
  void pollInputs(GamepadInputs& in) const;
  void handleDetach();
  void tryReconnect();
  void updateRumble(double time_s);
  void updateConstantForce(const Eigen::Vector3d& force_n);

  ManualDevice manual_;
  DeviceInfo info_;
  std::optional<GamepadMapping> user_mapping_;
  bool haptic_subsystem_ = false;             // this device holds a reference on SDL's haptic subsystem
  GamepadMapping mapping_;
  _SDL_Joystick* joystick_ = nullptr;         // owned (a controller holds its own reference too)
  _SDL_GameController* controller_ = nullptr; // set when SDL knows the pad as a controller
  _SDL_Haptic* haptic_ = nullptr;             // set when the pad renders SDL_HAPTIC_CONSTANT
  int effect_id_ = -1;
  bool using_controller_ = false;             // the last pad opened was a controller
  bool has_rumble_ = false;
  std::string pad_name_;
  std::array<std::uint8_t, 16> guid_{};       // to prefer the same pad on reconnect

  std::atomic<bool> connected_{false};
  std::atomic<long> disconnects_{0};
  std::atomic<long> reconnects_{0};
  bool pedal_locked_ = false;   // after a reconnect: no cut until the pedal was seen released
  bool lens_was_down_ = false;
  int lens_index_ = 2;          // 30 degrees: the usual operative lens
  bool serosa_warning_ = false;
  Eigen::Vector3d last_force_{0, 0, 0};
  Eigen::Matrix3d scope_rotation_ = Eigen::Matrix3d::Identity();  // for the constant force's direction
  std::uint16_t low_target_ = 0, high_target_ = 0;
  std::uint16_t sent_low_ = 0, sent_high_ = 0;
  double last_rumble_s_ = -1e300;
  double last_read_s_ = 0.0;
  std::int16_t sent_level_ = 0;
};

}  // namespace hysim::haptics
