#pragma once
// The session's event log: one JSON object per line (time, event, details) next to the
// session's recording, flushed line by line so that a session that dies keeps its events.
// A log that cannot be opened is said once; the session runs on without it.
#include <nlohmann/json.hpp>
#include <fstream>
#include <string>

namespace hysim::tools {

// The log's path for a recording: X.hyrec -> X.events.jsonl (anything else: + .events.jsonl).
std::string sessionLogPath(const std::string& recording_path);

class SessionLog {
 public:
  // Opens (truncates) `path`. False, with problem() saying why, when it cannot be written.
  bool open(const std::string& path);
  void close();
  bool isOpen() const { return out_.is_open(); }
  const std::string& path() const { return path_; }
  const std::string& problem() const { return problem_; }
  // One line: {"t_s": time, "event": name, ...details}.
  void write(double time_s, const std::string& event, const nlohmann::json& details = nlohmann::json::object());

 private:
  std::ofstream out_;
  std::string path_;
  std::string problem_;
};

}  // namespace hysim::tools
