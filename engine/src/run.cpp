// engine::run: the fixed-step loop of `hysim run`, headless, as fast as possible or paced to
// the wall clock with the haptic thread alongside.
#include <algorithm>
#include <chrono>
#include <memory>
#include <vector>

#include "hysim/engine/run.hpp"
#include "hysim/haptics/clock.hpp"
#include "hysim/haptics/haptic_loop.hpp"

namespace hysim::engine {
namespace {

using Clock = std::chrono::steady_clock;

double usSince(Clock::time_point t0) { return std::chrono::duration<double, std::micro>(Clock::now() - t0).count(); }

// The scene key's spelling of each integrator.
const char* integratorName(sim::Integrator integrator) {
  switch (integrator) {
    case sim::Integrator::SymplecticEuler: return "symplectic_euler";
    case sim::Integrator::ImplicitEuler: return "implicit_euler";
    case sim::Integrator::Xpbd: return "xpbd";
  }
  return "unknown";
}

// The numbers of the run that do not change while it runs.
void describe(const Simulation& sim, RunReport& r) {
  const Scene& scene = sim.scene();
  r.scene = scene.name;
  r.assessment_settings = scene.assessment;
  r.dt = scene.sim.dt;
  r.nodes = sim.mesh().numNodes();
  r.elements = sim.mesh().numTets();
  r.deformable_elements = sim.numDeformableTets();
  r.springs = static_cast<int>(sim.model().springs.rows());
  r.anchored = sim.numAnchored();
  r.substeps = sim.model().substeps;
  r.critical_dt = sim.model().critical_dt;
  r.integrator = integratorName(scene.sim.integrator);
  r.commit_steps = scene.cut.commit_steps;
  r.cut_mode = scene.cut.mode == CutSettings::Mode::Sync ? "sync" : "async";
  const bool rigid = scene.coupling.mode == CouplingSettings::Mode::Rigid;
  r.coupling = rigid ? "rigid" : "spring";
  r.coupling_stiffness_n_per_mm = rigid ? 0.0 : sim.couplingGains().stiffness_n_per_mm;
  r.coupling_damping_n_s_per_mm = rigid ? 0.0 : sim.couplingGains().damping_n_s_per_mm;
}

// What the simulation knows at the end of the run.
void collect(const Simulation& sim, RunReport& r) {
  const Scene& scene = sim.scene();
  r.state_hash = sim.stateHash();
  r.device = sim.device().info().name;
  r.device_connected = sim.device().connected();
  r.device_counters = sim.device().counters();
  r.warnings = sim.state().warnings;
  r.passes = sim.passes();
  r.initial_myoma_mm3 = sim.initialMyomaVolume();
  r.electrode_active_s = sim.electrodeActiveSeconds();
  r.path_length_mm = sim.pathLengthMm();
  r.perforation_margin_mm = scene.safety.perforation_margin_mm;
  r.perforations = sim.perforations();
  r.perforation_events = sim.perforationEvents();
  r.serosa_faces = sim.outerWall().numFaces();
  if (scene.organ.given) r.wall_behind_myoma_mm = wallBehindMyomasMm(scene.organ, sim.mesh());
  r.stalls = sim.stalls();
  r.stall_ms = sim.stallMs();
  std::vector<double> commit_us, latency_ms;
  for (const PassRecord& p : r.passes) {
    if (p.cut_failed && p.commit_step == p.exit_step) continue;  // refused at the exit step: never committed
    commit_us.push_back(p.commit_us);
    latency_ms.push_back(p.latency_ms);
  }
  r.commit_us = spreadOf(commit_us);
  r.cut_latency_ms = spreadOf(latency_ms);
  if (const ChipWorld* chips = sim.chips(); chips != nullptr) {
    r.chips_mode = "simulate";
    r.chips_in_cavity = chips->numChips();
    r.chips_left_cavity = chips->removedOutside();
    r.chips_over_cap = chips->removedOverCap();
    r.chip_step_us_mean = sim.chipSteps() > 0 ? 1e6 * sim.chipStepSeconds() / static_cast<double>(sim.chipSteps()) : 0.0;
  }
}

// The haptic thread of a realtime run: the scene's script on a simulated device of its own
// (the simulation reads the same script at each step's time, so its input does not depend on
// the thread's timing).
std::unique_ptr<haptics::HapticLoop> startHaptics(const Simulation& sim) {
  auto device = std::make_unique<haptics::ScriptedDevice>(haptics::Trajectory(sim.scene().tool_path));
  auto loop = std::make_unique<haptics::HapticLoop>(std::move(device));
  loop->start();
  return loop;
}

void hapticsReport(haptics::HapticLoop& loop, RunReport& r) {
  loop.stop();
  const haptics::HapticStats s = loop.stats();
  r.haptic_period_us = {s.period_p50_us, s.period_p99_us, s.period_max_us};
  r.haptic_ticks = s.ticks;
  r.haptic_overruns = s.overruns;
  r.haptic_realtime_priority = loop.realtime();
}

}  // namespace

Spread spreadOf(const std::vector<double>& values) {
  Spread s;
  if (values.empty()) return s;
  s.median = percentile(values, 0.5);
  s.p99 = percentile(values, 0.99);
  s.max = *std::max_element(values.begin(), values.end());
  return s;
}

Result<RunReport> run(Simulation& sim, const RunOptions& options) {
  RunReport r;
  describe(sim, r);
  r.steps = options.steps >= 0 ? options.steps : sim.scene().steps;
  r.realtime = options.realtime;
  const int every = options.every > 0 ? options.every : sim.scene().render.every;
  std::vector<double> step_us, frame_ms, late_us;
  step_us.reserve(static_cast<size_t>(r.steps));
  if (options.realtime) late_us.reserve(static_cast<size_t>(r.steps));
  render::RenderSnapshot snapshot;
  auto frame = [&]() -> Status {
    if (!options.on_frame) return Status::Ok();
    const auto t0 = Clock::now();
    sim.fillSnapshot(snapshot);
    Status st = options.on_frame(snapshot, r.frames);
    frame_ms.push_back(usSince(t0) / 1000.0);
    ++r.frames;
    return st;
  };
  std::unique_ptr<haptics::HapticLoop> haptic = options.realtime ? startHaptics(sim) : nullptr;
  haptics::SteadyClock pace;
  const std::int64_t dt_ns = static_cast<std::int64_t>(sim.scene().sim.dt * 1e9 + 0.5);
  const auto wall0 = Clock::now();
  const std::int64_t start_ns = pace.nowNs();
  if (Status st = frame(); !st.ok()) return Error{st.error()};
  for (int i = 0; i < r.steps; ++i) {
    if (options.stop != nullptr && options.stop->load(std::memory_order_relaxed)) {
      r.steps = i;
      r.partial = true;
      break;
    }
    if (haptic) {  // step i starts at start + i dt: absolute sleeps do not drift
      const std::int64_t due = start_ns + static_cast<std::int64_t>(i) * dt_ns;
      pace.sleepUntilNs(due);
      late_us.push_back(static_cast<double>(pace.nowNs() - due) / 1000.0);
    }
    if (options.before_step) options.before_step(sim, i);
    const auto t0 = Clock::now();
    sim.step();
    step_us.push_back(usSince(t0));
    if (haptic) haptic->publishModel(sim.hapticModel());
    r.max_tool_force_n = std::max(r.max_tool_force_n, sim.toolForceN().norm());
    r.max_hand_force_n = std::max(r.max_hand_force_n, sim.handForceN().norm());
    r.max_coupling_offset_mm = std::max(r.max_coupling_offset_mm, sim.couplingOffsetMm());
    if ((i + 1) % every == 0) {
      if (Status st = frame(); !st.ok()) return Error{st.error()};
    }
  }
  sim.commitPendingCut();  // a pass that ended in the last K steps is reported too
  r.wall_s = std::chrono::duration<double>(Clock::now() - wall0).count();
  if (haptic) hapticsReport(*haptic, r);
  const Spread steps = spreadOf(step_us);
  r.step_us_median = steps.median;
  r.step_us_p99 = steps.p99;
  r.step_us_max = steps.max;
  r.step_start_late_us = spreadOf(late_us);
  r.frame_ms_median = percentile(frame_ms, 0.5);
  collect(sim, r);
  return r;
}

}  // namespace hysim::engine
