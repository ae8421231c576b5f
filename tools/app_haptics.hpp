#pragma once
// The trainee app's haptic thread. With no hardware device attached it renders to a
// MirroredDevice that follows the simulation's input (keyboard or script), so the force
// pipeline (local model, watchdog, safety gate) runs and its state is on screen: a latched
// fault or an emergency stop is shown until the trainee resets it.
#include <cstdint>
#include <memory>

#include "hysim/engine/simulation.hpp"
#include "hysim/haptics/haptic_loop.hpp"
#include "hysim/haptics/mirrored_device.hpp"

namespace hysim::tools {

class AppHaptics {
 public:
  AppHaptics();   // starts the hysim-haptic thread
  ~AppHaptics();  // stops it

  // After a frame's steps: the input's state and the simulation's newest local model (only
  // when the simulation stepped; a paused or slow simulation lets the watchdog fade F0).
  void publish(const engine::Simulation& sim);
  void eStop() { loop_->eStop(); }
  void resetSafety() { loop_->resetSafety(); }
  // The panel's force feedback section: the gate's state (red when latched), the rendered
  // force, a note when F0 faded, and the E-stop / reset buttons.
  void drawPanel();

 private:
  haptics::MirroredDevice* device_ = nullptr;  // owned by loop_
  std::unique_ptr<haptics::HapticLoop> loop_;
  std::int64_t last_step_ = -1;
};

}  // namespace hysim::tools
