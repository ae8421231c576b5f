#pragma once
// Plays an input script (app_input_script.hpp) into the window as SDL events: the `wall`
// events from a timer started with the player, a screen's events from a timer started when the
// screen first opens (enterScreen), whichever screen is up then; the `sim` events from the
// case's frame loop once the simulation reaches their time.
#include <SDL.h>

#include <chrono>
#include <cstddef>
#include <list>
#include <set>
#include <string>
#include <vector>

#include "app_input_script.hpp"
#include "hysim/render/sdl_window.hpp"

namespace hysim::tools {

class InputPlayer {
 public:
  InputPlayer() = default;
  ~InputPlayer();  // stops the timers
  InputPlayer(const InputPlayer&) = delete;
  InputPlayer& operator=(const InputPlayer&) = delete;

  // Checks every key name (the error names the script's line) and starts the wall clock.
  Status start(InputScript script, render::SdlWindow& window);
  // A screen opens (start, progress, debrief, replay): its clock starts the first time.
  void enterScreen(const std::string& screen);
  // From the case's frame loop: pushes the sim events due by simulated time `sim_s`.
  void pumpSim(double sim_s);

 private:
  // One clock's events, played by an SDL timer (on SDL's timer thread).
  struct Clock {
    InputPlayer* player = nullptr;
    const std::vector<ScriptEvent>* events = nullptr;
    std::size_t next = 0;
    std::chrono::steady_clock::time_point start;
    SDL_TimerID timer = 0;
  };
  void startClock(const std::string& name);
  static Uint32 onTimer(Uint32 interval_ms, void* clock);
  static Uint32 pushDue(Clock& clock);
  void push(const ScriptEvent& e);
  void pushKey(SDL_Scancode code, bool down);

  InputScript script_;
  render::SdlWindow* window_ = nullptr;
  std::list<Clock> clocks_;      // stable addresses for the timers
  std::set<std::string> started_;
  std::size_t next_sim_ = 0;     // the frame loop's
};

}  // namespace hysim::tools
