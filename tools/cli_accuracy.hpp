#pragma once
// `hysim accuracy`: the speed-against-error study (engine/accuracy) from the command line.
#include <CLI/CLI.hpp>
#include <memory>
#include <optional>
#include <string>

namespace hysim::tools {

struct AccuracyCommand {
  CLI::App* cmd = nullptr;
  std::string out;
  std::string scene;
  std::string refined_mesh;
  bool quick = false;
  bool quiet = false;
};

std::shared_ptr<AccuracyCommand> addAccuracyCommand(CLI::App& app);
// The exit status when the command was given, else nothing.
std::optional<int> runAccuracyCommand(const AccuracyCommand& c);

}  // namespace hysim::tools
