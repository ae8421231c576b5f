#include "hysim/engine/replay.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "hysim/haptics/little_endian.hpp"
#include "hysim/haptics/replay_device.hpp"

namespace hysim::engine {
namespace {

// Folds the bytes of the file at `path` into the FNV-1a hash `h`.
Status hashFile(const std::string& path, std::uint64_t& h) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return Error{path + ": not a regular file"};
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{path + ": cannot open"};
  char buffer[1 << 16];
  while (in) {
    in.read(buffer, sizeof(buffer));
    h = haptics::le::fnv1a64(h, reinterpret_cast<const unsigned char*>(buffer), static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) return Error{path + ": read error"};
  const unsigned char separator = 0xff;  // moving bytes between files changes the hash
  h = haptics::le::fnv1a64(h, &separator, 1);
  return Status::Ok();
}

std::string hexOf(std::uint64_t v) {
  char text[17];
  std::snprintf(text, sizeof(text), "%016llx", static_cast<unsigned long long>(v));
  return text;
}

// A replay attaches a device where the recorded run did: at the first record and wherever
// the recording marks one.
void attachRecordedDevices(Simulation& sim, const std::shared_ptr<haptics::ReplaySource>& source) {
  while (source->nextIsAttach()) sim.setDevice(std::make_unique<haptics::ReplayDevice>(source));
}

// One state per step, beside the attach states.
int stepsRecorded(const haptics::Recording& recording) {
  int steps = 0;
  for (const haptics::RecordedState& s : recording.states) steps += s.attached ? 0 : 1;
  return steps;
}

}  // namespace

std::string hysimVersion() { return HYSIM_VERSION_STRING; }

Result<std::uint64_t> sceneContentHash(const Scene& scene) {
  std::uint64_t h = haptics::le::kFnv64Offset;
  for (const std::string* path : {&scene.path, &scene.mesh_path, &scene.tool_mesh_path}) {
    if (path->empty()) continue;
    if (Status st = hashFile(*path, h); !st.ok()) return Error{st.error()};
  }
  return h;
}

Status applyOverrides(const RunOverrides& o, Scene& scene) {
  if (!o.mesh_path.empty()) scene.mesh_path = o.mesh_path;
  if (o.chips_mode == "remove") {
    scene.chips.mode = ChipSettings::Mode::Remove;
  } else if (o.chips_mode == "simulate") {
    scene.chips.mode = ChipSettings::Mode::Simulate;
  } else if (!o.chips_mode.empty()) {
    return Error{"chips mode '" + o.chips_mode + "' (remove or simulate)"};
  }
  return Status::Ok();
}

Result<haptics::RecordingHeader> recordingHeader(const Scene& scene, const RunOverrides& overrides,
                                                 const std::string& device_name) {
  auto hash = sceneContentHash(scene);
  if (!hash.ok()) return Error{hash.error()};
  haptics::RecordingHeader h;
  h.scene_hash = *hash;
  h.dt_s = scene.sim.dt;
  h.scene_path = std::filesystem::absolute(scene.path).lexically_normal().string();
  h.mesh_path = overrides.mesh_path.empty()
                    ? std::string()
                    : std::filesystem::absolute(overrides.mesh_path).lexically_normal().string();
  h.chips_mode = overrides.chips_mode;
  h.hysim_version = hysimVersion();
  h.device_name = device_name;
  return h;
}

Result<ReplayScene> loadReplayScene(const haptics::Recording& recording, bool force) {
  const haptics::RecordingHeader& h = recording.header;
  auto scene = loadScene(h.scene_path);
  if (!scene.ok()) return Error{"the recorded scene: " + scene.error()};
  ReplayScene out;
  out.scene = std::move(scene.value());
  if (Status st = applyOverrides({h.mesh_path, h.chips_mode}, out.scene); !st.ok()) {
    return Error{"the recording's " + st.error()};
  }
  if (out.scene.sim.dt != h.dt_s) {
    return Error{h.scene_path + ": step dt is " + std::to_string(out.scene.sim.dt) + " s now, the recording's is " +
                 std::to_string(h.dt_s) + " s: its states are one per step and cannot be replayed"};
  }
  auto hash = sceneContentHash(out.scene);
  if (!hash.ok()) return Error{hash.error()};
  out.hash_now = *hash;
  out.changed = out.hash_now != h.scene_hash;
  if (out.changed && !force) {
    return Error{h.scene_path + " changed since the recording: content hash " + hexOf(out.hash_now) +
                 " now, " + hexOf(h.scene_hash) + " recorded (the scene file or a mesh it loads); --force replays "
                 "it anyway and flags the report"};
  }
  // Another build may step differently: the states are the same only with the same code.
  out.version_changed = h.hysim_version != hysimVersion();
  if (out.version_changed && !force) {
    return Error{"recorded with hysim " + h.hysim_version + ", this is hysim " + hysimVersion() +
                 ": another build may give other states; --force replays it anyway and flags the report"};
  }
  return out;
}

Result<RunReport> replay(Simulation& sim, std::shared_ptr<const haptics::Recording> recording, RunOptions options) {
  if (recording->states.empty()) return Error{"the recording holds no states"};
  if (!recording->states.front().attached) return Error{"the recording's first state is not a device's attach"};
  auto source = std::make_shared<haptics::ReplaySource>(std::move(recording));
  attachRecordedDevices(sim, source);
  options.steps = stepsRecorded(source->recording());
  options.before_step = [source](Simulation& s, int) { attachRecordedDevices(s, source); };
  return run(sim, options);
}

}  // namespace hysim::engine
