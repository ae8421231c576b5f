#include "cli_run.hpp"

#include <signal.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <thread>

#include "hysim/engine/replay.hpp"
#include "hysim/engine/run.hpp"
#include "hysim/engine/simulation.hpp"
#include "hysim/haptics/recording.hpp"
#include "hysim/render/renderer.hpp"
#include "run_device.hpp"
#include "run_session.hpp"
#include "tool_common.hpp"

namespace fs = std::filesystem;

namespace hysim::tools {
namespace {

// Set by SIGINT and SIGTERM: the run stops before its next step and writes a partial report
// (a lock-free atomic store is all a signal handler may do here).
std::atomic<bool> g_stop_requested{false};

extern "C" void requestStop(int) { g_stop_requested.store(true); }

void stopOnInterrupt(engine::RunOptions& options) {
  struct sigaction action {};
  action.sa_handler = requestStop;
  action.sa_flags = SA_RESETHAND | SA_RESTART;  // a second Ctrl-C ends a run that does not stop
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  options.stop = &g_stop_requested;
}

int fail(const std::string& message) {
  std::cerr << "hysim: " << message << "\n";
  return 1;
}

// A report path must name a file. Checked before a run, so that a long run does not end in
// this error, and again before writing.
Status checkReportPath(const std::string& path) {
  if (path.empty()) return Status::Ok();
  std::error_code ec;
  if (!fs::path(path).has_filename() || fs::is_directory(path, ec)) {
    return Error{"--report '" + path + "' names a folder; give a file, e.g. '" +
                 (fs::path(path) / "report.json").lexically_normal().string() + "'"};
  }
  return Status::Ok();
}

// Frames into `folder` (PNG through the headless renderer); nothing when `folder` is empty.
Status setUpFrames(const engine::Scene& scene, const std::string& folder,
                   std::unique_ptr<render::OffscreenRenderer>& renderer, engine::RunOptions& options) {
  if (folder.empty()) return Status::Ok();
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) return Error{"cannot create frames folder '" + folder + "': " + ec.message()};
  auto r = render::OffscreenRenderer::create(scene.render.width, scene.render.height);
  if (!r.ok()) return Error{"cannot render headless: " + r.error()};
  renderer = std::move(r.value());
  render::OffscreenRenderer* out = renderer.get();
  options.on_frame = [out, folder](const render::RenderSnapshot& snap, int index) -> Status {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%05d.png", index);
    return out->renderToPng(snap, (fs::path(folder) / name).string());
  };
  return Status::Ok();
}

// The debugging hooks of `hysim run`.
Status setUpDebugging(const RunArgs& args, engine::Simulation& sim) {
  if (!args.dump_cuts.empty()) {
    std::error_code ec;
    fs::create_directories(args.dump_cuts, ec);
    if (ec) return Error{"cannot create folder '" + args.dump_cuts + "': " + ec.message()};
    sim.setCutDumpDir(args.dump_cuts);
  }
  if (args.cut_delay_ms > 0) {  // the same random sequence every run: only the timing changes
    auto rng = std::make_shared<std::mt19937>(12345u);
    const int most = args.cut_delay_ms;
    sim.setCutDelayForTesting([rng, most] {
      std::this_thread::sleep_for(std::chrono::milliseconds(std::uniform_int_distribution<int>(0, most)(*rng)));
    });
  }
  return Status::Ok();
}

void printModel(const engine::Scene& scene, const engine::Simulation& sim) {
  const sim::Model& m = sim.model();
  std::printf("scene %s: %d nodes (%d anchored), %d tets, %d springs; dt %.3g ms, %d substeps (critical %.3g ms)\n",
              scene.name.c_str(), sim.mesh().numNodes(), sim.numAnchored(), sim.mesh().numTets(),
              static_cast<int>(m.springs.rows()), 1e3 * m.options.dt, m.substeps, 1e3 * m.critical_dt);
}

void printReport(const engine::RunReport& r, const std::string& frames, const std::string& report) {
  std::printf("%d steps in %.2f s: step median %.1f us, p99 %.1f us; %d frames (median %.1f ms); "
              "state_hash %s; warnings %d\n",
              r.steps, r.wall_s, r.step_us_median, r.step_us_p99, r.frames, r.frame_ms_median,
              engine::hashHex(r.state_hash).c_str(), r.warnings);
  if (!r.passes.empty()) std::printf("last pass: q*_min %.4f\n", r.passes.back().q_min);
  std::printf("cuts (%s, commit after %d steps): latency median %.1f ms, p99 %.1f, max %.1f; commit step "
              "median %.0f us, max %.0f; stalls %d; step max %.1f us\n",
              r.cut_mode.c_str(), r.commit_steps, r.cut_latency_ms.median, r.cut_latency_ms.p99,
              r.cut_latency_ms.max, r.commit_us.median, r.commit_us.max, r.stalls, r.step_us_max);
  if (r.realtime) {
    std::printf("haptic thread: %ld ticks, period p50 %.1f us, p99 %.1f, max %.1f; %ld overruns; %s\n", r.haptic_ticks,
                r.haptic_period_us.median, r.haptic_period_us.p99, r.haptic_period_us.max, r.haptic_overruns,
                r.haptic_realtime_priority ? "real-time priority" : "normal priority");
  }
  std::printf("%s", engine::summaryText(r).c_str());
  if (!r.recording.empty()) {
    std::printf("%s %s: %llu device states\n", r.replay ? "replayed" : "recording in", r.recording.c_str(),
                static_cast<unsigned long long>(r.recording_states));
  }
  if (r.replay_scene_changed) std::printf("warning: the scene changed since the recording (--force)\n");
  if (r.replay_version_changed) {
    std::printf("warning: recorded by hysim %s, replayed by another build (--force)\n", r.recorded_version.c_str());
  }
  if (!frames.empty()) std::printf("frames in %s\n", frames.c_str());
  if (!report.empty()) std::printf("report in %s\n", report.c_str());
}

// Writes the report (when asked), prints it (unless quiet); the exit status of the run.
int finishRun(const engine::RunReport& r, const std::string& frames, const std::string& report, bool quiet) {
  if (!report.empty()) {
    if (Status st = checkReportPath(report); !st.ok()) return fail(st.error());
    if (Status st = writeFileAtomically(report, engine::reportJson(r)); !st.ok()) return fail(st.error());
  }
  if (!quiet) printReport(r, frames, report);
  if (r.partial) {
    std::fprintf(stderr, "hysim: stopped by a signal after %d steps; the report is partial\n", r.steps);
    return 4;
  }
  return r.warnings == 0 ? 0 : 3;
}

int runCommand(const RunArgs& args) {
  if (Status st = checkReportPath(args.report); !st.ok()) return fail(st.error());
  const std::string scene_path = args.scene.empty() ? tools::defaultScenePath() : args.scene;
  auto scene = engine::loadScene(scene_path);
  if (!scene.ok()) return fail(scene.error());
  const engine::RunOverrides overrides{args.mesh, args.chips};
  if (Status st = engine::applyOverrides(overrides, *scene); !st.ok()) return fail(st.error());
  if (args.sync_cut) scene->cut.mode = engine::CutSettings::Mode::Sync;
  RunDevice device;  // outlives the simulation, which holds the device's driver
  auto sim = engine::Simulation::create(*scene);
  if (!sim.ok()) return fail(sim.error());
  if (Status st = setUpDebugging(args, **sim); !st.ok()) return fail(st.error());
  device.setWaitSeconds(args.device_wait_s);
  device.setFiltersFile(args.device_filters);
  if (Status st = device.attach(args.device, args.gamepad_mapping, **sim); !st.ok()) return fail(st.error());
  std::unique_ptr<render::OffscreenRenderer> renderer;
  engine::RunOptions options;
  options.steps = args.steps;
  options.every = args.every;
  options.realtime = args.realtime;
  options.before_step = [&device](engine::Simulation& s, int) { device.beforeStep(s); };
  stopOnInterrupt(options);
  if (Status st = setUpFrames(*scene, args.frames, renderer, options); !st.ok()) return fail(st.error());
  haptics::RecordingWriter recorder;
  if (!args.record.empty()) {
    auto header = engine::recordingHeader(*scene, overrides, (*sim)->device().info().name);
    if (!header.ok()) return fail(header.error());
    std::string error;
    if (!recorder.open(args.record, *header, error)) return fail(error);
    if (Status st = (*sim)->recordInputTo(&recorder); !st.ok()) {
      recorder.discard();
      return fail(st.error());
    }
  }
  RunSession session;
  if (!args.trainee.empty()) {
    const std::string mode = args.device.empty() || args.device == "scripted" ? "demo" : "hands-on";
    if (Status st = beginRunSession(args.data_dir, args.trainee, mode, *scene, args.record, session); !st.ok()) {
      recorder.discard();
      return fail(st.error());
    }
  }
  if (!args.quiet) printModel(*scene, **sim);
  auto report = engine::run(**sim, options);
  if (!report.ok()) {
    recorder.discard();
    return fail(report.error());
  }
  finishRunSession(*report, session);
  if (recorder.isOpen()) {
    std::string error;
    if (!recorder.finish(error)) return fail(error);
    report->recording = args.record;
    report->recording_states = recorder.records();
  }
  return finishRun(*report, args.frames, args.report, args.quiet);
}

int replayCommand(const ReplayArgs& args) {
  if (Status st = checkReportPath(args.report); !st.ok()) return fail(st.error());
  auto recording = std::make_shared<haptics::Recording>();
  std::string error;
  if (!haptics::readRecording(args.recording, *recording, error)) return fail(error);
  auto scene = engine::loadReplayScene(*recording, args.force);
  if (!scene.ok()) return fail(args.recording + ": " + scene.error());
  auto sim = engine::Simulation::create(scene->scene);
  if (!sim.ok()) return fail(sim.error());
  std::unique_ptr<render::OffscreenRenderer> renderer;
  engine::RunOptions options;
  options.every = args.every;
  stopOnInterrupt(options);
  if (Status st = setUpFrames(scene->scene, args.frames, renderer, options); !st.ok()) return fail(st.error());
  if (!args.quiet) printModel(scene->scene, **sim);
  auto report = engine::replay(**sim, recording, options);
  if (!report.ok()) return fail(args.recording + ": " + report.error());
  report->recording = args.recording;
  report->recording_states = recording->states.size();
  report->replay = true;
  report->recorded_scene_hash = recording->header.scene_hash;
  report->scene_hash_now = scene->hash_now;
  report->replay_scene_changed = scene->changed;
  report->recorded_version = recording->header.hysim_version;
  report->replay_version_changed = scene->version_changed;
  return finishRun(*report, args.frames, args.report, args.quiet);
}

// What run and replay write, and how much they say.
void addOutputOptions(CLI::App& cmd, std::string& frames, int& every, std::string& report, bool& quiet) {
  cmd.add_option("--frames", frames, "Write PNG frames into this folder");
  cmd.add_option("--every", every, "Render a frame every K steps (default: the scene's)")->check(finiteRange(1, 1e6));
  cmd.add_option("--report", report, "Write the JSON report to this file");
  cmd.add_flag("--quiet", quiet, "Print nothing but errors");
}

void addRunOptions(CLI::App& cmd, RunArgs& run) {
  cmd.add_option("scene", run.scene, "Scene file (default: scenes/default.yaml)")->check(CLI::ExistingFile);
  cmd.add_option("--steps", run.steps, "Number of steps (default: the scene's)")->check(finiteRange(0, 1e8));
  addOutputOptions(cmd, run.frames, run.every, run.report, run.quiet);
  cmd.add_option("--chips", run.chips, "Override the scene's chips mode: remove or simulate")
      ->check(CLI::IsMember({"remove", "simulate"}));
  cmd.add_option("--mesh", run.mesh,
                 "Override the scene's tissue mesh: a tet mesh (.msh or .vtk) of the same organ with the scene's "
                 "material labels, e.g. a finer one (tests/data/cutting/uterus_20k.msh)")
      ->check(CLI::ExistingFile);
  cmd.add_option("--record", run.record,
                 "Record the device states the simulation consumes (one per step) into this file, for "
                 "`hysim replay`");
  cmd.add_option("--device", run.device,
                 "What drives the tool: scripted (the scene's tool_path, default), gamepad (the first game "
                 "controller), virtual-pad:FILE (a software pad playing a timed input script, e.g. "
                 "scenes/pad/default-course.yaml), udp:PORT (a device bridge on 127.0.0.1:PORT, e.g. hysim-udp-peer)");
  cmd.add_option("--device-filters", run.device_filters,
                 "udp: the bridge's motion scale, device-to-world transform and motion limit (YAML, see "
                 "haptics/README.md)")
      ->check(CLI::ExistingFile);
  cmd.add_option("--device-wait-s", run.device_wait_s, "udp: seconds to wait for the bridge's first packet")
      ->check(finiteRange(0.0, 3600.0));
  cmd.add_option("--gamepad-mapping", run.gamepad_mapping, "Game controller mapping file (haptics/README.md)")
      ->check(CLI::ExistingFile);
  cmd.add_option("--trainee", run.trainee,
                 "Store the run as this trainee's session (hysim sessions list; a killed run shows as incomplete)");
  cmd.add_option("--data-dir", run.data_dir,
                 "The sessions' data folder (default: $HYSIM_DATA_DIR, $XDG_DATA_HOME/hysim or ~/.local/share/hysim)");
  cmd.add_flag("--realtime", run.realtime,
               "Pace the steps to the wall clock, with the haptic thread (1 kHz) rendering forces on a simulated "
               "device; the state sequence is the same as without");
  cmd.add_option("--cut-delay-ms", run.cut_delay_ms,
                 "Debugging: the cut worker sleeps a random 0..N ms before each cut (the states must not change)")
      ->check(CLI::Range(0, 10000));
  cmd.add_flag("--sync-cut", run.sync_cut,
               "Reference mode: cut on the simulation thread at the pass's exit step (committed at the same "
               "step as the worker's cut; the same state_hash)");
  cmd.add_option("--dump-cuts", run.dump_cuts,
                 "Debugging: write each pass's cut input into this folder (pass_NNN_mesh.msh, the rest mesh "
                 "before the cut; pass_NNN_surface.msh, the cut surface; full precision). "
                 "`hysim cut DIR/pass_NNN_mesh.msh --surface DIR/pass_NNN_surface.msh --method hybrid` repeats "
                 "the pass's cut");
}

void addReplayOptions(CLI::App& cmd, ReplayArgs& replay) {
  cmd.add_option("recording", replay.recording, "Recording file (hysim run --record, or the trainee app's)")
      ->required();
  addOutputOptions(cmd, replay.frames, replay.every, replay.report, replay.quiet);
  cmd.add_flag("--force", replay.force,
               "Replay even though the scene's content or the hysim build changed since the recording (the report says "
               "so)");
}

}  // namespace

std::shared_ptr<RunCommands> addRunCommands(CLI::App& app) {
  auto c = std::make_shared<RunCommands>();
  c->run = app.add_subcommand("run", "Run a scene headless: fixed-step simulation, PNG frames, JSON report");
  addRunOptions(*c->run, c->run_args);
  c->replay = app.add_subcommand(
      "replay", "Re-run a recorded session from the scene its header names: the same states to the last bit");
  addReplayOptions(*c->replay, c->replay_args);
  return c;
}

std::optional<int> runRunCommands(const RunCommands& c) {
  if (*c.run) return runCommand(c.run_args);
  if (*c.replay) return replayCommand(c.replay_args);
  return std::nullopt;
}

}  // namespace hysim::tools
