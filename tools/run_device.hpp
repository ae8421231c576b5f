#pragma once
// The device `hysim run --device SPEC` puts in charge of the tool:
//   scripted          the scene's tool_path (the default)
//   gamepad           the first attached game controller or joystick (SDL2)
//   virtual-pad:FILE  a software pad playing a PadScript through the same driver
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
  // Before each step: a virtual pad's script is played up to the time the step reads.
  void beforeStep(const engine::Simulation& sim);

 private:
  Status attachPad(const std::string& mapping_file, engine::Simulation& sim);

  std::unique_ptr<haptics::VirtualPad> pad_;
  std::optional<PadScript> script_;
};

}  // namespace hysim::tools
