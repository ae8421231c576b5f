#pragma once
// `hysim sessions list|export`: the trainee sessions stored in the data folder (session_store.hpp).
#include <CLI/CLI.hpp>
#include <memory>
#include <optional>
#include <string>

namespace hysim::tools {

struct SessionsArgs {
  std::string data_dir;  // empty: defaultDataFolder()
  std::string trainee;   // empty: everyone's
  bool csv = false, json = false;
  std::string out;       // export: this file instead of standard output
};

struct SessionsCommands {
  CLI::App* sessions = nullptr;
  CLI::App* list = nullptr;
  CLI::App* export_ = nullptr;
  SessionsArgs args;
};

std::shared_ptr<SessionsCommands> addSessionsCommands(CLI::App& app);
// The exit status when one of the commands was given, else nothing.
std::optional<int> runSessionsCommands(const SessionsCommands& c);

}  // namespace hysim::tools
