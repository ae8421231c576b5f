#pragma once
// The trainee app records every session: the device states the simulation consumed, one per
// step, into the user's data folder (hysim replay FILE plays it back). A folder that cannot be
// written is said once, on the panel and on stderr; the session runs on unrecorded.
#include <memory>
#include <string>

#include "hysim/engine/scene.hpp"
#include "hysim/engine/simulation.hpp"
#include "hysim/haptics/recording.hpp"

namespace hysim::tools {

// $HYSIM_DATA_DIR, else $XDG_DATA_HOME/hysim, else ~/.local/share/hysim; plus "/recordings".
std::string recordingsFolder();

class AppRecording {
 public:
  ~AppRecording() { finish(); }
  // Starts recording `sim` (before its first step) into `path`, or, when `path` is empty, into
  // recordingsFolder()/<date>-<time>-<scene>.hyrec.
  void start(const engine::Scene& scene, engine::Simulation& sim, const std::string& path = "");
  // Ends the recording (the file gets its end marker and its final name). Call before the
  // simulation it records goes away, and at the end of the session.
  void finish();
  bool recording() const { return writer_ != nullptr; }
  const std::string& path() const { return path_; }
  const std::string& problem() const { return problem_; }  // why nothing is recorded, or ""
  void drawPanel() const;

 private:
  std::unique_ptr<haptics::RecordingWriter> writer_;
  engine::Simulation* sim_ = nullptr;
  std::string path_;
  std::string problem_;
};

}  // namespace hysim::tools
