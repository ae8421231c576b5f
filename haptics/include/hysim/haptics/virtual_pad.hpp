#pragma once
// A game controller that exists only in software (SDL's virtual joystick, SDL 2.24+), for
// tests and demos of SdlGamepadDevice without a pad: it is seen by SDL as a standard-layout
// controller, its sticks, triggers and buttons are set from code, what SDL asks its motors to
// do is recorded, and it can be unplugged and plugged in again. Same thread as the device.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "hysim/cutting/result.hpp"
#include "hysim/haptics/gamepad_mapping.hpp"

struct _SDL_Joystick;

namespace hysim::haptics {

class VirtualPad {
 public:
  struct Rumble {
    std::uint16_t low = 0;   // low-frequency (large) motor
    std::uint16_t high = 0;  // high-frequency (small) motor
  };

  // Starts SDL's joystick and game controller subsystems (no video) and plugs the pad in.
  // Fails with SDL's message.
  static Result<std::unique_ptr<VirtualPad>> attach(std::string name = "hysim virtual pad");
  ~VirtualPad();  // unplugs it
  VirtualPad(const VirtualPad&) = delete;
  VirtualPad& operator=(const VirtualPad&) = delete;

  // Standard-layout inputs (pad::Axis, pad::Button). Sticks in [-1, 1] with SDL's sign (down
  // and right positive), triggers in [0, 1]. Seen by readers after their next SDL update.
  void setStick(int axis, double value);
  void setTrigger(int axis, double value);
  void setButton(int button, bool down);
  void releaseAll();  // sticks centred, triggers out, buttons up

  // Unplug / plug in again (the inputs set are kept and come back with the pad).
  Status unplug();
  Status plugIn();
  bool pluggedIn() const { return joystick_ != nullptr; }
  int deviceIndex() const;  // SDL's index of the pad now; -1 while unplugged

  // Every rumble SDL passed to the pad, oldest first.
  const std::vector<Rumble>& rumbles() const { return rumbles_; }
  Rumble lastRumble() const { return rumbles_.empty() ? Rumble{} : rumbles_.back(); }
  void clearRumbles() { rumbles_.clear(); }

 private:
  explicit VirtualPad(std::string name);
  void applyInputs();
  static int onRumble(void* self, std::uint16_t low, std::uint16_t high);

  std::string name_;
  _SDL_Joystick* joystick_ = nullptr;  // our own handle, for setting inputs
  std::int32_t instance_id_ = -1;
  std::int16_t axes_[pad::kNumAxes] = {};
  bool buttons_[pad::kNumButtons] = {};
  std::vector<Rumble> rumbles_;
};

}  // namespace hysim::haptics
