#pragma once
// `hysim run` (a scene headless: frames, report, optionally a recording of the device input)
// and `hysim replay` (a recording fed back into its scene: the same states to the last bit).
#include <CLI/CLI.hpp>
#include <memory>
#include <optional>
#include <string>

namespace hysim::tools {

struct RunArgs {
  std::string scene;
  int steps = -1;
  int every = -1;
  std::string frames;
  std::string report;
  std::string chips;  // empty: the scene's
  std::string mesh;   // empty: the scene's
  bool quiet = false;
  std::string dump_cuts;  // folder for each pass's cut input (debugging)
  bool realtime = false;  // pace to the wall clock with the haptic thread
  bool sync_cut = false;  // cut on the simulation thread (reference mode)
  int cut_delay_ms = 0;   // debugging: the worker sleeps a random 0..N ms before each cut
  std::string record;     // write the consumed device states to this file
  std::string device;     // see run_device.hpp; empty: the scene's script
  std::string gamepad_mapping;
  std::string device_filters;   // udp: scale, transform and motion limit (YAML)
  double device_wait_s = 10.0;  // udp: how long to wait for the bridge's first packet
  std::string trainee;   // store the run as this trainee's session (run_session.hpp)
  std::string data_dir;  // the sessions' data folder; empty: the default
};

struct ReplayArgs {
  std::string recording;
  std::string frames;
  int every = -1;
  std::string report;
  bool force = false;  // replay a scene whose content changed since the recording
  bool quiet = false;
};

struct RunCommands {
  CLI::App* run = nullptr;
  CLI::App* replay = nullptr;
  RunArgs run_args;
  ReplayArgs replay_args;
};

std::shared_ptr<RunCommands> addRunCommands(CLI::App& app);
// The exit status when one of the commands was given, else nothing.
std::optional<int> runRunCommands(const RunCommands& c);

}  // namespace hysim::tools
