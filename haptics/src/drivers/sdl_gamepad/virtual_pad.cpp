#include "hysim/haptics/virtual_pad.hpp"

#include <SDL.h>

#include <algorithm>
#include <cmath>

namespace hysim::haptics {

namespace {
constexpr Uint32 kSubsystems = SDL_INIT_JOYSTICK | SDL_INIT_GAMECONTROLLER;
constexpr Sint16 kTriggerOut = -32768;  // a full-range axis read by SDL as trigger 0
}  // namespace

Result<std::unique_ptr<VirtualPad>> VirtualPad::attach(std::string name) {
  if (SDL_InitSubSystem(kSubsystems) != 0) {
    return Error{std::string("SDL joystick/game controller subsystem: ") + SDL_GetError()};
  }
  std::unique_ptr<VirtualPad> pad(new VirtualPad(std::move(name)));  // its destructor quits SDL again
  if (Status s = pad->plugIn(); !s.ok()) return Error{s.error()};
  return pad;
}

VirtualPad::VirtualPad(std::string name) : name_(std::move(name)) { releaseAll(); }

VirtualPad::~VirtualPad() {
  if (SDL_WasInit(SDL_INIT_JOYSTICK) == 0) return;  // SDL_Quit came first: nothing left to free
  (void)unplug();
  SDL_QuitSubSystem(kSubsystems);
}

int VirtualPad::onRumble(void* self, std::uint16_t low, std::uint16_t high) {
  static_cast<VirtualPad*>(self)->rumbles_.push_back({low, high});
  return 0;
}

Status VirtualPad::plugIn() {
  if (pluggedIn()) return {};
  SDL_VirtualJoystickDesc desc;
  SDL_zero(desc);  // SDL requires the unused fields zero
  desc.version = SDL_VIRTUAL_JOYSTICK_DESC_VERSION;
  desc.type = SDL_JOYSTICK_TYPE_GAMECONTROLLER;
  desc.naxes = SDL_CONTROLLER_AXIS_MAX;        // axis i = standard axis i
  desc.nbuttons = SDL_CONTROLLER_BUTTON_MAX;   // button i = standard button i
  desc.name = name_.c_str();
  desc.userdata = this;
  desc.Rumble = &VirtualPad::onRumble;
  const int index = SDL_JoystickAttachVirtualEx(&desc);
  if (index < 0) return Error{std::string("SDL_JoystickAttachVirtualEx: ") + SDL_GetError()};
  joystick_ = SDL_JoystickOpen(index);
  if (joystick_ == nullptr) {
    const std::string why = SDL_GetError();
    SDL_JoystickDetachVirtual(index);
    return Error{"cannot open the virtual pad: " + why};
  }
  instance_id_ = SDL_JoystickInstanceID(joystick_);
  applyInputs();
  return {};
}

int VirtualPad::deviceIndex() const {
  if (!pluggedIn()) return -1;
  for (int i = 0; i < SDL_NumJoysticks(); ++i) {
    if (SDL_JoystickGetDeviceInstanceID(i) == instance_id_) return i;
  }
  return -1;
}

Status VirtualPad::unplug() {
  if (!pluggedIn()) return {};
  const int index = deviceIndex();
  SDL_JoystickClose(joystick_);
  joystick_ = nullptr;
  if (index < 0 || SDL_JoystickDetachVirtual(index) != 0) {
    return Error{std::string("SDL_JoystickDetachVirtual: ") + SDL_GetError()};
  }
  return {};
}

void VirtualPad::setStick(int axis, double value) {
  if (axis < 0 || axis >= pad::kNumAxes) return;
  axes_[axis] = static_cast<Sint16>(std::lround(32767.0 * std::clamp(value, -1.0, 1.0)));
  applyInputs();
}

void VirtualPad::setTrigger(int axis, double value) {
  if (axis < 0 || axis >= pad::kNumAxes) return;
  axes_[axis] = static_cast<Sint16>(std::lround(-32768.0 + 65535.0 * std::clamp(value, 0.0, 1.0)));
  applyInputs();
}

void VirtualPad::setButton(int button, bool down) {
  if (button < 0 || button >= pad::kNumButtons) return;
  buttons_[button] = down;
  applyInputs();
}

void VirtualPad::releaseAll() {
  std::fill(std::begin(axes_), std::end(axes_), Sint16{0});
  axes_[pad::kLeftTrigger] = axes_[pad::kRightTrigger] = kTriggerOut;
  std::fill(std::begin(buttons_), std::end(buttons_), false);
  applyInputs();
}

// SDL keeps the values and hands them to readers at their next SDL_JoystickUpdate.
void VirtualPad::applyInputs() {
  if (!pluggedIn()) return;
  for (int a = 0; a < pad::kNumAxes; ++a) SDL_JoystickSetVirtualAxis(joystick_, a, axes_[a]);
  for (int b = 0; b < pad::kNumButtons; ++b) SDL_JoystickSetVirtualButton(joystick_, b, buttons_[b] ? 1 : 0);
}

}  // namespace hysim::haptics
