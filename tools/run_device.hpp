#pragma once
// The device `hysim run --device SPEC` puts in charge of the tool:
//   scripted          the scene's tool_path (the default)
//   gamepad           the first attached game controller or joystick (SDL2)
//   virtual-pad:FILE  a software pad playing a PadScript through the same driver
//   udp:PORT          a device bridge sending state packets to 127.0.0.1:PORT (NetworkDevice),
//                     seen through a motion limit; the run starts at its first packet
#include <memory>
#include <optional>
#include <string>

#include "hysim/cutting/result.hpp"
#include "hysim/engine/simulation.hpp"
#include "hysim/haptics/virtual_pad.hpp"
#include "pad_script.hpp"

namespace hysim::tools {

class RunDevice {
 public:
  // Sets the device up and attaches it to `sim` (before its first step). `mapping_file`: a
  // gamepad mapping (empty: the defaults). Errors name the spec or the file.
  Status attach(const std::string& spec, const std::string& mapping_file, engine::Simulation& sim);
  // A filters file for udp:PORT (device_filters.hpp); empty: the default motion limit only.
  void setFiltersFile(std::string path) { filters_file_ = std::move(path); }
  // How long udp:PORT waits for the bridge's first packet before it gives up.
  void setWaitSeconds(double seconds) { wait_s_ = seconds; }
  // Before each step: a virtual pad's script is played up to the time the step reads.
  void beforeStep(const engine::Simulation& sim);

 private:
  Status attachPad(const std::string& mapping_file, engine::Simulation& sim);
  Status attachNetwork(const std::string& port, engine::Simulation& sim);

  std::unique_ptr<haptics::VirtualPad> pad_;
  std::optional<PadScript> script_;
  double wait_s_ = 10.0;
  std::string filters_file_;
};

}  // namespace hysim::tools
