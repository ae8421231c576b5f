#include "app_input_script.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace hysim::tools {
namespace {

constexpr std::size_t kMaxScriptBytes = 1 << 20;

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string::npos) return {};
  return s.substr(first, s.find_last_not_of(" \t\r") - first + 1);
}

bool parseAction(const std::string& word, ScriptEvent::Action& action) {
  static const std::pair<const char*, ScriptEvent::Action> kActions[] = {
      {"down", ScriptEvent::Action::Down}, {"up", ScriptEvent::Action::Up},
      {"tap", ScriptEvent::Action::Tap},   {"text", ScriptEvent::Action::Text},
      {"capture", ScriptEvent::Action::Capture}};
  for (const auto& [name, value] : kActions) {
    if (word == name) {
      action = value;
      return true;
    }
  }
  return false;
}

bool knownClock(const std::string& clock) {
  if (clock == "wall" || clock == "sim") return true;
  for (const char* screen : kScriptScreens) {
    if (clock == screen) return true;
  }
  return false;
}

// One non-empty line without its comment. The error says what is wrong with it.
Result<ScriptEvent> parseLine(const std::string& line, int number) {
  std::istringstream in(line);
  std::string clock, time, action;
  in >> clock >> time >> action;
  ScriptEvent e;
  e.line = number;
  if (!knownClock(clock)) {
    return Error{"the clock must be wall, sim, start, progress, debrief or replay, not '" + clock + "'"};
  }
  e.clock = clock;
  char* end = nullptr;
  e.time_s = std::strtod(time.c_str(), &end);
  if (time.empty() || *end != '\0' || !std::isfinite(e.time_s) || e.time_s < 0.0 || e.time_s > 1e6) {
    return Error{"the time must be seconds from 0 to 1e6, not '" + time + "'"};
  }
  if (!parseAction(action, e.action)) {
    return Error{"the action must be down, up, tap, text or capture, not '" + action + "'"};
  }
  std::string rest;
  std::getline(in, rest);
  e.argument = trim(rest);
  if (e.argument.empty()) return Error{"'" + action + "' needs an argument (a key, text or file)"};
  if (e.action == ScriptEvent::Action::Text && e.argument.size() > 31) {
    return Error{"text is typed at most 31 bytes per line"};
  }
  return e;
}

}  // namespace

Result<InputScript> parseInputScript(const std::string& text, const std::string& path) {
  InputScript script;
  script.path = path;
  std::istringstream in(text);
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    line = trim(line.substr(0, line.find('#')));
    if (line.empty()) continue;
    auto event = parseLine(line, number);
    if (!event.ok()) return Error{path + ":" + std::to_string(number) + ": " + event.error()};
    (event->clock == "sim" ? script.sim : script.timed[event->clock]).push_back(*event);
  }
  const auto by_time = [](const ScriptEvent& a, const ScriptEvent& b) { return a.time_s < b.time_s; };
  std::stable_sort(script.sim.begin(), script.sim.end(), by_time);
  for (auto& [clock, events] : script.timed) std::stable_sort(events.begin(), events.end(), by_time);
  return script;
}

Result<InputScript> loadInputScript(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return Error{path + ": the input script is not a regular file"};
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{path + ": cannot open the input script"};
  std::string text(kMaxScriptBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxScriptBytes) return Error{path + ": the input script is larger than 1 MiB"};
  return parseInputScript(text, path);
}

}  // namespace hysim::tools
