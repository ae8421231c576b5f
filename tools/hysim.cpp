// hysim: the command-line entry. `hysim run` steps a scene headless and writes PNG frames
// and a JSON report; `hysim stats` prints mesh statistics with the paper's columns.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <thread>

#include "hysim/cutting/mesh_io.hpp"
#include "hysim/cutting/mesh_stats.hpp"
#include "hysim/engine/run.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/simulation.hpp"
#include "hysim/render/renderer.hpp"
#include "tool_common.hpp"
#include "cli_accuracy.hpp"
#include "cli_cut2d.hpp"

namespace fs = std::filesystem;
using namespace hysim;

namespace {

int fail(const std::string& message) {
  std::cerr << "hysim: " << message << "\n";
  return 1;
}

// Writes through a temporary file and a rename, so an existing report is never left
// half-written.
Status writeFileAtomically(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  std::error_code dir_ec;
  const fs::path parent = fs::path(path).parent_path();
  if (!parent.empty()) fs::create_directories(parent, dir_ec);
  if (dir_ec) return Error{"cannot create folder '" + parent.string() + "': " + dir_ec.message()};
  {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) return Error{"cannot write '" + tmp + "'"};
    out << text;
    if (!out.flush()) return Error{"cannot write '" + tmp + "'"};
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) return Error{"cannot move '" + tmp + "' to '" + path + "': " + ec.message()};
  return Status::Ok();
}


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
};

int runCommand(const RunArgs& args) {
  const std::string scene_path = args.scene.empty() ? tools::defaultScenePath() : args.scene;
  auto scene = engine::loadScene(scene_path);
  if (!scene.ok()) return fail(scene.error());
  if (args.chips == "remove") scene->chips.mode = engine::ChipSettings::Mode::Remove;
  if (args.chips == "simulate") scene->chips.mode = engine::ChipSettings::Mode::Simulate;
  if (!args.mesh.empty()) scene->mesh_path = args.mesh;
  if (args.sync_cut) scene->cut.mode = engine::CutSettings::Mode::Sync;
  auto sim = engine::Simulation::create(*scene);
  if (!sim.ok()) return fail(sim.error());
  if (!args.dump_cuts.empty()) {
    std::error_code ec;
    fs::create_directories(args.dump_cuts, ec);
    if (ec) return fail("cannot create folder '" + args.dump_cuts + "': " + ec.message());
    (*sim)->setCutDumpDir(args.dump_cuts);
  }
  if (args.cut_delay_ms > 0) {  // the same random sequence every run: only the timing changes
    auto rng = std::make_shared<std::mt19937>(12345u);
    const int most = args.cut_delay_ms;
    (*sim)->setCutDelayForTesting([rng, most] {
      std::this_thread::sleep_for(std::chrono::milliseconds(std::uniform_int_distribution<int>(0, most)(*rng)));
    });
  }

  std::unique_ptr<render::OffscreenRenderer> renderer;
  engine::RunOptions options;
  options.steps = args.steps;
  options.every = args.every;
  options.realtime = args.realtime;
  if (!args.frames.empty()) {
    std::error_code ec;
    fs::create_directories(args.frames, ec);
    if (ec) return fail("cannot create frames folder '" + args.frames + "': " + ec.message());
    auto r = render::OffscreenRenderer::create(scene->render.width, scene->render.height);
    if (!r.ok()) return fail("cannot render headless: " + r.error());
    renderer = std::move(r.value());
    options.on_frame = [&](const render::RenderSnapshot& snap, int index) -> Status {
      char name[32];
      std::snprintf(name, sizeof(name), "frame_%05d.png", index);
      return renderer->renderToPng(snap, (fs::path(args.frames) / name).string());
    };
  }
  if (!args.quiet) {
    const sim::Model& m = (*sim)->model();
    std::printf("scene %s: %d nodes (%d anchored), %d tets, %d springs; dt %.3g ms, %d substeps (critical %.3g ms)\n",
                scene->name.c_str(), (*sim)->mesh().numNodes(), (*sim)->numAnchored(), (*sim)->mesh().numTets(),
                static_cast<int>(m.springs.rows()), 1e3 * m.options.dt, m.substeps, 1e3 * m.critical_dt);
  }
  auto report = engine::run(**sim, options);
  if (!report.ok()) return fail(report.error());
  const std::string json = engine::reportJson(*report);
  if (!args.report.empty()) {
    if (Status st = writeFileAtomically(args.report, json); !st.ok()) return fail(st.error());
  }
  if (!args.quiet) {
    std::printf("%d steps in %.2f s: step median %.1f us, p99 %.1f us; %d frames (median %.1f ms); "
                "state_hash %s; warnings %d\n",
                report->steps, report->wall_s, report->step_us_median, report->step_us_p99, report->frames,
                report->frame_ms_median, engine::hashHex(report->state_hash).c_str(), report->warnings);
    if (!report->passes.empty()) std::printf("last pass: q*_min %.4f\n", report->passes.back().q_min);
    std::printf("cuts (%s, commit after %d steps): latency median %.1f ms, p99 %.1f, max %.1f; commit step "
                "median %.0f us, max %.0f; stalls %d; step max %.1f us\n",
                report->cut_mode.c_str(), report->commit_steps, report->cut_latency_ms.median,
                report->cut_latency_ms.p99, report->cut_latency_ms.max, report->commit_us.median,
                report->commit_us.max, report->stalls, report->step_us_max);
    if (report->realtime) {
      std::printf("haptic thread: %ld ticks, period p50 %.1f us, p99 %.1f, max %.1f; %ld overruns; %s\n",
                  report->haptic_ticks, report->haptic_period_us.median, report->haptic_period_us.p99,
                  report->haptic_period_us.max, report->haptic_overruns,
                  report->haptic_realtime_priority ? "real-time priority" : "normal priority");
    }
    std::printf("%s", engine::summaryText(*report).c_str());
    if (!args.frames.empty()) std::printf("frames in %s\n", args.frames.c_str());
    if (!args.report.empty()) std::printf("report in %s\n", args.report.c_str());
  }
  return report->warnings == 0 ? 0 : 3;
}

int statsCommand(const std::string& path, bool json) {
  cutting::MeshStats s;
  auto tets = cutting::readTetMesh(path);
  if (tets.ok()) {
    if (auto v = cutting::validate(*tets); !v.ok()) return fail(path + ": invalid mesh: " + v.error());
    s = cutting::computeStats(*tets);
  } else {
    auto tris = cutting::readTriMesh(path);
    if (!tris.ok()) return fail(tets.error());
    if (auto v = cutting::validate(*tris); !v.ok()) return fail(path + ": invalid mesh: " + v.error());
    s = cutting::computeStats(*tris);
  }
  if (json) {
    const nlohmann::ordered_json j = tools::statsJson(s);
    std::cout << j.dump(2) << "\n";
  } else {
    std::printf("%-8s %8s %10s %10s %10s %10s %8s %8s %8s %7s %7s %7s %9s\n", "", "#N", "#E", "size_min", "size_mu",
                "size_sd", "E_min", "E_mu", "E_sd", "q_min", "q_mu", "q_sd", "angle_min");
    std::printf("%-8s %8d %10d %10.4g %10.4g %10.4g %8.4g %8.4g %8.4g %7.4f %7.4f %7.4f %9.2f\n", "mesh", s.nodes,
                s.elements, s.size_min, s.size_mean, s.size_std, s.edge_min, s.edge_mean, s.edge_std, s.q_min,
                s.q_mean, s.q_std, s.dihedral_min_deg);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"hysim: real-time hysteroscopy training simulator (headless tools)"};
  app.require_subcommand(1);

  RunArgs run;
  CLI::App* run_cmd = app.add_subcommand("run", "Run a scene headless: fixed-step simulation, PNG frames, JSON report");
  run_cmd->add_option("scene", run.scene, "Scene file (default: scenes/default.yaml)")->check(CLI::ExistingFile);
  run_cmd->add_option("--steps", run.steps, "Number of steps (default: the scene's)")->check(CLI::NonNegativeNumber);
  run_cmd->add_option("--frames", run.frames, "Write PNG frames into this folder");
  run_cmd->add_option("--every", run.every, "Render a frame every K steps (default: the scene's)")->check(CLI::PositiveNumber);
  run_cmd->add_option("--report", run.report, "Write the JSON report to this file");
  run_cmd->add_option("--chips", run.chips, "Override the scene's chips mode: remove or simulate")
      ->check(CLI::IsMember({"remove", "simulate"}));
  run_cmd->add_option("--mesh", run.mesh,
                      "Override the scene's tissue mesh: a tet mesh (.msh or .vtk) of the same organ with the scene's "
                      "material labels, e.g. a finer one (tests/data/cutting/uterus_20k.msh)")
      ->check(CLI::ExistingFile);
  run_cmd->add_flag("--quiet", run.quiet, "Print nothing but errors");
  run_cmd->add_flag("--realtime", run.realtime,
                    "Pace the steps to the wall clock, with the haptic thread (1 kHz) rendering forces on a simulated "
                    "device; the state sequence is the same as without");
  run_cmd->add_option("--cut-delay-ms", run.cut_delay_ms,
                      "Debugging: the cut worker sleeps a random 0..N ms before each cut (the states must not change)")
      ->check(CLI::Range(0, 10000));
  run_cmd->add_flag("--sync-cut", run.sync_cut,
                    "Reference mode: cut on the simulation thread at the pass's exit step (committed at the same "
                    "step as the worker's cut; the same state_hash)");
  run_cmd->add_option("--dump-cuts", run.dump_cuts,
                      "Debugging: write each pass's cut input into this folder (pass_NNN_mesh.msh, the rest mesh "
                      "before the cut; pass_NNN_surface.msh, the cut surface; full precision). "
                      "`hysim cut DIR/pass_NNN_mesh.msh --surface DIR/pass_NNN_surface.msh --method hybrid` repeats "
                      "the pass's cut");

  std::string stats_path;
  bool stats_json = false;
  CLI::App* stats_cmd = app.add_subcommand("stats", "Mesh statistics (#N, #E, size, edge, q = r_in/R_circ, angles)");
  stats_cmd->add_option("mesh", stats_path, "Mesh file (.msh or .vtk)")->required()->check(CLI::ExistingFile);
  stats_cmd->add_flag("--json", stats_json, "Print JSON");

  auto cut2d_commands = hysim::tools::addCut2dCommands(app);  // hysim cut, hysim tables
  auto accuracy_command = hysim::tools::addAccuracyCommand(app);

  CLI11_PARSE(app, argc, argv);
  if (auto rc = hysim::tools::runCut2dCommands(*cut2d_commands)) return *rc;
  if (auto rc = hysim::tools::runAccuracyCommand(*accuracy_command)) return *rc;
  if (*run_cmd) return runCommand(run);
  if (*stats_cmd) return statsCommand(stats_path, stats_json);
  return 1;
}
