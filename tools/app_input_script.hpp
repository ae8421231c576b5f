#pragma once
// Scripted input for the trainee window: a text file of timed key presses, text and frame
// captures, played into the window as if a trainee typed them (CI drives the app this way).
// Format (tools/README-app in render/README.md): one event per line,
//   <clock> <seconds> <action> [argument]
// clock: `wall` (seconds since the window opened) or `sim` (simulated seconds of the case's
// first session); action: `down KEY`, `up KEY`, `tap KEY` (KEY: an SDL key name such as W,
// Left Shift, Return, Escape, Up), `text STRING` (typed text), `capture FILE.png`.
// `#` starts a comment.
#include <string>
#include <vector>

#include "hysim/cutting/result.hpp"

namespace hysim::tools {

struct ScriptEvent {
  enum class Clock { Wall, Sim };
  enum class Action { Down, Up, Tap, Text, Capture };
  Clock clock = Clock::Wall;
  double time_s = 0.0;
  Action action = Action::Tap;
  std::string argument;  // the key's name, the text or the file
  int line = 0;          // in the script, for errors
};

struct InputScript {
  std::string path;
  std::vector<ScriptEvent> wall;  // in time order
  std::vector<ScriptEvent> sim;   // in time order
};

// Parses a script's text; errors name `path`, the line and what is wrong.
Result<InputScript> parseInputScript(const std::string& text, const std::string& path);
// Reads and parses a script file (at most 1 MiB).
Result<InputScript> loadInputScript(const std::string& path);

}  // namespace hysim::tools
