#pragma once
// Recording a run's device input and replaying it. A recording's header names the scene and
// holds a hash of its content (the scene file and the meshes it loads), so a replay runs the
// same scene, or says what changed.
#include <cstdint>
#include <memory>
#include <string>

#include "hysim/cutting/result.hpp"
#include "hysim/engine/run.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/haptics/recording.hpp"

namespace hysim::engine {

// hysim's version and the commit it was configured from.
std::string hysimVersion();

// FNV-1a 64 over the bytes of the scene file, the tissue mesh and the tool mesh it loads.
Result<std::uint64_t> sceneContentHash(const Scene& scene);

// What a run was started with beside the scene file: its --mesh and --chips overrides.
struct RunOverrides {
  std::string mesh_path;   // empty: the scene's
  std::string chips_mode;  // "remove", "simulate" or empty: the scene's
};
// Applies the overrides to a loaded scene; an unknown chips mode is an error.
Status applyOverrides(const RunOverrides& overrides, Scene& scene);

// The header of a recording of `scene` (overrides already applied) driven by `device_name`.
Result<haptics::RecordingHeader> recordingHeader(const Scene& scene, const RunOverrides& overrides,
                                                 const std::string& device_name);

struct ReplayScene {
  Scene scene;                 // with the recorded overrides
  std::uint64_t hash_now = 0;  // of its content now
  bool changed = false;        // hash_now differs from the recording's (accepted only with force)
  bool version_changed = false;  // another hysim version or commit recorded it (only with force)
};
// Loads the scene a recording names, with the run's overrides. A scene whose content changed
// since the recording is refused with both hashes in the message, and a recording made by
// another hysim version or commit with both versions, unless `force`; a different step dt
// always is.
Result<ReplayScene> loadReplayScene(const haptics::Recording& recording, bool force);

// Steps `simulation` (made from loadReplayScene's scene) on the recorded device states, one
// per step, as many steps as were recorded; a recorded device change is replayed as one.
Result<RunReport> replay(Simulation& simulation, std::shared_ptr<const haptics::Recording> recording,
                         RunOptions options);

}  // namespace hysim::engine
