#pragma once
// The trainee app's game controller: when a pad is attached at start (or asked for with
// --gamepad / --gamepad-mapping), an SdlGamepadDevice drives the tool instead of the
// keyboard. The simulation owns the device and sends it the hand force every step; this
// class keeps a view of it for the serosa cue, the lens button and the panel.
#include <memory>
#include <optional>
#include <string>

#include "hysim/cutting/result.hpp"
#include "hysim/engine/simulation.hpp"
#include "hysim/haptics/gamepad_mapping.hpp"
#include "hysim/haptics/sdl_gamepad.hpp"
#include "hysim/haptics/virtual_pad.hpp"

namespace hysim::tools {

struct GamepadArgs {
  bool force = false;        // --gamepad: a pad is required
  bool disable = false;      // --no-gamepad: the keyboard even when a pad is attached
  std::string mapping_file;  // --gamepad-mapping FILE (implies --gamepad)
  bool virtual_pad = false;  // --virtual-pad: a software pad (demo, smoke test; implies --gamepad)
};

class AppGamepad {
 public:
  // Decides whether a pad is used (reads the mapping file, looks for a pad). An error when a
  // pad was asked for and none is there, or the mapping file is bad.
  Status configure(const GamepadArgs& args);
  bool enabled() const { return enabled_; }

  // Puts a pad device in charge of the simulation's tool, starting from its current pose.
  // False (with the reason printed) if the pad cannot be opened now.
  bool attach(engine::Simulation& sim);
  // The simulation's device is about to be replaced (script, keyboard, reset).
  void release() { device_ = nullptr; }
  bool active() const { return device_ != nullptr; }

  // Before a frame's steps: the serosa cue (the active wire within the perforation margin, or
  // the perforation alarm on: the force cue) and the lens angle, which the pad's button and the
  // panel both change.
  void update(const engine::Simulation& sim, double perforation_margin_mm, int& lens_index, bool alarm);
  // The panel's controller section: name, a red warning while unplugged, the cues.
  void drawPanel() const;

 private:
  bool enabled_ = false;
  std::optional<haptics::GamepadMapping> mapping_;
  std::unique_ptr<haptics::VirtualPad> virtual_pad_;  // --virtual-pad only
  haptics::SdlGamepadDevice* device_ = nullptr;  // owned by the simulation while active
  int last_lens_index_ = -1;
};

}  // namespace hysim::tools
