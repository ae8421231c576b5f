#include "run_device.hpp"

#include "hysim/haptics/gamepad_mapping.hpp"
#include "hysim/haptics/sdl_gamepad.hpp"

namespace hysim::tools {

Status RunDevice::attachPad(const std::string& mapping_file, engine::Simulation& sim) {
  haptics::SdlGamepadOptions options;
  if (!mapping_file.empty()) {
    auto m = haptics::loadGamepadMapping(mapping_file);
    if (!m.ok()) return Error{m.error()};
    options.mapping = std::move(m.value());
  }
  // The pad at SDL's index of the virtual one when there is one, else the first.
  if (pad_) options.device_index = pad_->deviceIndex();
  auto device = haptics::SdlGamepadDevice::open(sim.deviceState().pose, sim.state().time, options);
  if (!device.ok()) return Error{"--device: " + device.error()};
  sim.setDevice(std::move(device.value()));
  return Status::Ok();
}

Status RunDevice::attach(const std::string& spec, const std::string& mapping_file, engine::Simulation& sim) {
  if (spec.empty() || spec == "scripted") return Status::Ok();
  if (spec == "gamepad") return attachPad(mapping_file, sim);
  const std::string virtual_prefix = "virtual-pad:";
  if (spec.rfind(virtual_prefix, 0) == 0) {
    auto script = PadScript::load(spec.substr(virtual_prefix.size()));
    if (!script.ok()) return Error{script.error()};
    script_ = std::move(script.value());
    auto pad = haptics::VirtualPad::attach("hysim virtual pad");
    if (!pad.ok()) return Error{"--device virtual-pad: " + pad.error()};
    pad_ = std::move(pad.value());
    script_->playUntil(sim.state().time, *pad_);
    return attachPad(mapping_file, sim);
  }
  return Error{"--device '" + spec + "': expected scripted, gamepad or virtual-pad:FILE"};
}

void RunDevice::beforeStep(const engine::Simulation& sim) {
  if (pad_ && script_) script_->playUntil(sim.state().time + sim.scene().sim.dt, *pad_);
}

}  // namespace hysim::tools
