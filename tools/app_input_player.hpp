#pragma once
// Plays an input script (app_input_script.hpp) into the window as SDL events: the `wall`
// events from a timer at their time since start(), whichever screen is up; the `sim` events
// from the case's frame loop once the simulation reaches their time.
#include <SDL.h>

#include <chrono>
#include <cstddef>

#include "app_input_script.hpp"
#include "hysim/render/sdl_window.hpp"

namespace hysim::tools {

class InputPlayer {
 public:
  InputPlayer() = default;
  ~InputPlayer();  // stops the timer
  InputPlayer(const InputPlayer&) = delete;
  InputPlayer& operator=(const InputPlayer&) = delete;

  // Checks every key name (the error names the script's line) and starts the wall clock.
  Status start(InputScript script, render::SdlWindow& window);
  // From the case's frame loop: pushes the sim events due by simulated time `sim_s`.
  void pumpSim(double sim_s);

 private:
  static Uint32 onTimer(Uint32 interval_ms, void* self);
  Uint32 pushWallDue();
  void push(const ScriptEvent& e);
  void pushKey(SDL_Scancode code, bool down);

  InputScript script_;
  render::SdlWindow* window_ = nullptr;
  SDL_TimerID timer_ = 0;
  std::chrono::steady_clock::time_point start_;
  std::size_t next_wall_ = 0;  // the timer thread's
  std::size_t next_sim_ = 0;   // the frame loop's
};

}  // namespace hysim::tools
