#include "app_input_player.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace hysim::tools {

InputPlayer::~InputPlayer() {
  for (Clock& clock : clocks_) {
    if (clock.timer != 0) SDL_RemoveTimer(clock.timer);
  }
}

Status InputPlayer::start(InputScript script, render::SdlWindow& window) {
  std::vector<const ScriptEvent*> all;
  for (const ScriptEvent& e : script.sim) all.push_back(&e);
  for (const auto& [clock, events] : script.timed) {
    for (const ScriptEvent& e : events) all.push_back(&e);
  }
  for (const ScriptEvent* e : all) {
    const bool keyed = e->action == ScriptEvent::Action::Down || e->action == ScriptEvent::Action::Up ||
                       e->action == ScriptEvent::Action::Tap;
    if (keyed && SDL_GetScancodeFromName(e->argument.c_str()) == SDL_SCANCODE_UNKNOWN) {
      return Error{script.path + ":" + std::to_string(e->line) + ": unknown key '" + e->argument +
                   "' (SDL key names: W, Left Shift, Return, Escape, Up, ...)"};
    }
  }
  if (SDL_InitSubSystem(SDL_INIT_TIMER) != 0) return Error{std::string("SDL timer: ") + SDL_GetError()};
  script_ = std::move(script);
  window_ = &window;
  startClock("wall");
  return {};
}

void InputPlayer::enterScreen(const std::string& screen) {
  if (window_ != nullptr) startClock(screen);
}

void InputPlayer::startClock(const std::string& name) {
  const auto events = script_.timed.find(name);
  if (events == script_.timed.end() || !started_.insert(name).second) return;
  Clock& clock = clocks_.emplace_back();
  clock.player = this;
  clock.events = &events->second;
  clock.start = std::chrono::steady_clock::now();
  clock.timer = SDL_AddTimer(1, &InputPlayer::onTimer, &clock);
  if (clock.timer == 0) std::fprintf(stderr, "hysim-app: SDL timer: %s\n", SDL_GetError());
}

Uint32 InputPlayer::onTimer(Uint32 /*interval_ms*/, void* clock) { return pushDue(*static_cast<Clock*>(clock)); }

// On SDL's timer thread: the clock's events due now; the time to its next one (0: done).
Uint32 InputPlayer::pushDue(Clock& clock) {
  const std::vector<ScriptEvent>& events = *clock.events;
  const double now_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock.start).count();
  while (clock.next < events.size() && events[clock.next].time_s <= now_s) clock.player->push(events[clock.next++]);
  if (clock.next >= events.size()) return 0;
  const double wait_ms = 1e3 * (events[clock.next].time_s - now_s);
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
