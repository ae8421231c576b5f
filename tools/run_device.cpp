#include "run_device.hpp"

#include <chrono>
#include <cstdlib>
#include <thread>

#include "hysim/haptics/filters.hpp"
#include "hysim/haptics/gamepad_mapping.hpp"
#include "hysim/haptics/sdl_gamepad.hpp"
#include "hysim/haptics/udp_device.hpp"
#include "device_filters.hpp"

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

Status RunDevice::attachNetwork(const std::string& port_text, engine::Simulation& sim) {
  char* end = nullptr;
  const long port = std::strtol(port_text.c_str(), &end, 10);
  if (port_text.empty() || *end != '\0' || port < 1 || port > 65535) {
    return Error{"--device udp:" + port_text + ": the port must be a number in 1..65535"};
  }
  DeviceFilters filters;
  if (!filters_file_.empty()) {
    auto loaded = loadDeviceFilters(filters_file_);
    if (!loaded.ok()) return Error{loaded.error()};
    filters = loaded.value();
  }
  haptics::NetworkDeviceOptions options;
  options.port = static_cast<std::uint16_t>(port);
  std::string error;
  std::unique_ptr<haptics::NetworkDevice> device = haptics::NetworkDevice::open(options, &error);
  if (!device) return Error{"--device udp:" + port_text + ": " + error};
  // The run starts with the bridge: its first state is where the tool begins.
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::duration<double>(wait_s_);
  while (!device->connected()) {
    if (std::chrono::steady_clock::now() > give_up) {
      return Error{"--device udp:" + port_text + ": no state packet from a bridge within " +
                   std::to_string(wait_s_) + " s"};
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  sim.setDevice(std::make_unique<haptics::FilteredDevice>(std::move(device), filters.scale, filters.transform,
                                                          filters.limit));
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
  const std::string udp_prefix = "udp:";
  if (spec.rfind(udp_prefix, 0) == 0) return attachNetwork(spec.substr(udp_prefix.size()), sim);
  return Error{"--device '" + spec + "': expected scripted, gamepad, virtual-pad:FILE or udp:PORT"};
}

void RunDevice::beforeStep(const engine::Simulation& sim) {
  if (pad_ && script_) script_->playUntil(sim.state().time + sim.scene().sim.dt, *pad_);
}

}  // namespace hysim::tools
