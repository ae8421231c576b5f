#pragma once
// Scripted input for the trainee window: a text file of timed key presses, text and frame
// captures, played into the window as if a trainee typed them (CI drives the app this way).
// Format (tools/README-app in render/README.md): one event per line,
//   <clock> <seconds> <action> [argument]
// clock: `wall` (seconds since the window opened), `sim` (simulated seconds of the case's
// first session), or a screen, `start`, `progress`, `debrief` or `replay` (seconds since that
// screen first opened); action: `down KEY`, `up KEY`, `tap KEY` (KEY: an SDL key name such as W,
// Left Shift, Return, Escape, Up), `text STRING` (typed text), `capture FILE.png`.
// `#` starts a comment.
#include <map>
#include <string>
#include <vector>

#include "hysim/cutting/result.hpp"

namespace hysim::tools {

struct ScriptEvent {
  enum class Action { Down, Up, Tap, Text, Capture };
  std::string clock;  // wall, sim or a screen's name
  double time_s = 0.0;
  Action action = Action::Tap;
  std::string argument;  // the key's name, the text or the file
  int line = 0;          // in the script, for errors
};

// The screens whose opening starts a clock.
inline constexpr const char* kScriptScreens[] = {"start", "progress", "debrief", "replay"};

struct InputScript {
  std::string path;
  std::vector<ScriptEvent> sim;                           // in time order
  std::map<std::string, std::vector<ScriptEvent>> timed;  // wall and the screens', each in time order
};

// Parses a script's text; errors name `path`, the line and what is wrong.
Result<InputScript> parseInputScript(const std::string& text, const std::string& path);
// Reads and parses a script file (at most 1 MiB).
Result<InputScript> loadInputScript(const std::string& path);

}  // namespace hysim::tools
