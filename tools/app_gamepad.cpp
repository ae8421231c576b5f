#include "app_gamepad.hpp"

#include <SDL.h>
#include <imgui.h>

#include <cstdio>
#include <memory>

namespace hysim::tools {

Status AppGamepad::configure(const GamepadArgs& args) {
  if (!args.mapping_file.empty()) {
    auto m = haptics::loadGamepadMapping(args.mapping_file);
    if (!m.ok()) return Error{m.error()};
    mapping_ = std::move(m.value());
  }
  if (args.virtual_pad) {
    auto pad = haptics::VirtualPad::attach("hysim virtual pad");
    if (!pad.ok()) return Error{"--virtual-pad: " + pad.error()};
    virtual_pad_ = std::move(pad.value());
  }
  const bool asked = args.force || args.virtual_pad || mapping_.has_value();
  if (args.disable && !asked) return {};
  // Only to look: SDL counts the pads once its joystick subsystem runs.
  if (SDL_InitSubSystem(SDL_INIT_JOYSTICK | SDL_INIT_GAMECONTROLLER) != 0) {
    if (asked) return Error{std::string("game controller: SDL cannot start its joystick subsystem: ") + SDL_GetError()};
    return {};
  }
  const int pads = SDL_NumJoysticks();
  SDL_QuitSubSystem(SDL_INIT_JOYSTICK | SDL_INIT_GAMECONTROLLER);
  if (pads <= 0) {
    if (asked) return Error{"--gamepad: no game controller or joystick is attached"};
    return {};
  }
  enabled_ = true;
  return {};
}

bool AppGamepad::attach(engine::Simulation& sim) {
  haptics::SdlGamepadOptions options;
  options.mapping = mapping_;
  auto device = haptics::SdlGamepadDevice::open(sim.deviceState().pose, sim.state().time, options);
  if (!device.ok()) {
    std::fprintf(stderr, "hysim-app: game controller: %s (keyboard instead)\n", device.error().c_str());
    return false;
  }
  device_ = device.value().get();
  std::printf("hysim-app: game controller '%s' (%s, %s)\n", device_->padName().c_str(),
              device_->isController() ? "standard layout" : "raw joystick",
              device_->hasConstantForce() ? "constant force" : "rumble");
  sim.setDevice(std::move(device.value()));
  last_lens_index_ = -1;  // the panel's lens wins at the first update
  return true;
}

void AppGamepad::update(const engine::Simulation& sim, double perforation_margin_mm, int& lens_index, bool alarm) {
  if (device_ == nullptr) return;
  device_->setSerosaWarning(alarm || (sim.deviceState().pose.pedal && sim.serosaClearanceMm() < perforation_margin_mm));
  if (last_lens_index_ >= 0 && device_->lensIndex() != last_lens_index_) {
    lens_index = device_->lensIndex();  // the pad's button was pressed
  } else {
    device_->setLensIndex(lens_index);  // the panel or the L key, or nothing changed
  }
  last_lens_index_ = lens_index;
}

void AppGamepad::drawPanel() const {
  if (device_ == nullptr) return;
  const ImVec4 red(1.0f, 0.35f, 0.3f, 1.0f);
  ImGui::Text("controller   %s", device_->padName().c_str());
  if (!device_->connected()) {
    ImGui::TextColored(red, "controller disconnected: tool frozen");
    ImGui::TextColored(red, "plug it in again to go on");
  }
  const haptics::DeviceCounters c = device_->counters();
  if (c.disconnects > 0) ImGui::Text("unplugged    %8ld x", c.disconnects);
  if (device_->hasConstantForce()) {
    ImGui::Text("pad force    %8.3f N", device_->lastForce().norm());
  } else {
    ImGui::Text("rumble       %5.0f %%  %s", 100.0 * device_->rumbleLow() / 65535.0,
                device_->rumbleHigh() > 0 ? "(serosa)" : "");
  }
  ImGui::TextDisabled("L stick: forward/back, sideways");
  ImGui::TextDisabled("D-pad up/down: up/down");
  ImGui::TextDisabled("R stick: yaw/pitch; triggers: loop");
  ImGui::TextDisabled("R shoulder: cut pedal; Y: lens");
}

}  // namespace hysim::tools
