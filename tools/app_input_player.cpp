#include "app_input_player.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace hysim::tools {

InputPlayer::~InputPlayer() {
  if (timer_ != 0) SDL_RemoveTimer(timer_);
}

Status InputPlayer::start(InputScript script, render::SdlWindow& window) {
  for (const auto* events : {&script.wall, &script.sim}) {
    for (const ScriptEvent& e : *events) {
      const bool keyed = e.action == ScriptEvent::Action::Down || e.action == ScriptEvent::Action::Up ||
                         e.action == ScriptEvent::Action::Tap;
      if (keyed && SDL_GetScancodeFromName(e.argument.c_str()) == SDL_SCANCODE_UNKNOWN) {
        return Error{script.path + ":" + std::to_string(e.line) + ": unknown key '" + e.argument +
                     "' (SDL key names: W, Left Shift, Return, Escape, Up, ...)"};
      }
    }
  }
  if (SDL_InitSubSystem(SDL_INIT_TIMER) != 0) return Error{std::string("SDL timer: ") + SDL_GetError()};
  script_ = std::move(script);
  window_ = &window;
  start_ = std::chrono::steady_clock::now();
  if (!script_.wall.empty()) {
    timer_ = SDL_AddTimer(1, &InputPlayer::onTimer, this);
    if (timer_ == 0) return Error{std::string("SDL timer: ") + SDL_GetError()};
  }
  return {};
}

Uint32 InputPlayer::onTimer(Uint32 /*interval_ms*/, void* self) { return static_cast<InputPlayer*>(self)->pushWallDue(); }

// On SDL's timer thread: the wall events due now; the time to the next one (0: the last is done).
Uint32 InputPlayer::pushWallDue() {
  const double now_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  while (next_wall_ < script_.wall.size() && script_.wall[next_wall_].time_s <= now_s) push(script_.wall[next_wall_++]);
  if (next_wall_ >= script_.wall.size()) return 0;
  const double wait_ms = 1e3 * (script_.wall[next_wall_].time_s - now_s);
  return static_cast<Uint32>(std::clamp(std::ceil(wait_ms), 1.0, 1e6));
}

void InputPlayer::pumpSim(double sim_s) {
  while (next_sim_ < script_.sim.size() && script_.sim[next_sim_].time_s <= sim_s) push(script_.sim[next_sim_++]);
}

void InputPlayer::pushKey(SDL_Scancode code, bool down) {
  SDL_Event event{};
  event.type = down ? SDL_KEYDOWN : SDL_KEYUP;
  event.key.windowID = SDL_GetWindowID(window_->nativeWindow());
  event.key.state = down ? SDL_PRESSED : SDL_RELEASED;
  event.key.keysym.scancode = code;
  event.key.keysym.sym = SDL_GetKeyFromScancode(code);
  SDL_PushEvent(&event);
}

void InputPlayer::push(const ScriptEvent& e) {
  const SDL_Scancode code = SDL_GetScancodeFromName(e.argument.c_str());
  switch (e.action) {
    case ScriptEvent::Action::Down: pushKey(code, true); break;
    case ScriptEvent::Action::Up: pushKey(code, false); break;
    case ScriptEvent::Action::Tap:
      pushKey(code, true);
      pushKey(code, false);
      break;
    case ScriptEvent::Action::Text: {
      SDL_Event event{};
      event.type = SDL_TEXTINPUT;
      event.text.windowID = SDL_GetWindowID(window_->nativeWindow());
      std::strncpy(event.text.text, e.argument.c_str(), sizeof(event.text.text) - 1);
      SDL_PushEvent(&event);
      break;
    }
    case ScriptEvent::Action::Capture: window_->captureNextFrame(e.argument); break;
  }
}

}  // namespace hysim::tools
