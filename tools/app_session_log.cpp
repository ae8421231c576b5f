#include "app_session_log.hpp"

#include <cerrno>
#include <cstring>

namespace hysim::tools {

std::string sessionLogPath(const std::string& recording_path) {
  const std::string ext = ".hyrec";
  const bool has_ext = recording_path.size() > ext.size() &&
                       recording_path.compare(recording_path.size() - ext.size(), ext.size(), ext) == 0;
  return (has_ext ? recording_path.substr(0, recording_path.size() - ext.size()) : recording_path) + ".events.jsonl";
}

bool SessionLog::open(const std::string& path) {
  close();
  path_ = path;
  problem_.clear();
  out_.open(path, std::ios::out | std::ios::trunc);
  if (!out_.is_open()) {
    problem_ = "cannot write the session log " + path + ": " + std::strerror(errno);
    return false;
  }
  return true;
}

void SessionLog::close() {
  if (out_.is_open()) out_.close();
}

void SessionLog::write(double time_s, const std::string& event, const nlohmann::json& details) {
  if (!out_.is_open()) return;
  nlohmann::json line = {{"t_s", time_s}, {"event", event}};
  for (auto it = details.begin(); it != details.end(); ++it) line[it.key()] = it.value();
  out_ << line.dump() << '\n';
  out_.flush();
}

}  // namespace hysim::tools
