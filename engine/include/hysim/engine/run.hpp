#pragma once
// The fixed-step loop: steps a Simulation for a number of steps, hands a snapshot to a
// frame callback every k steps, and measures. As fast as possible, or (realtime) paced to
// the wall clock with the haptic thread rendering the published local force model on a
// simulated device; the state sequence is the same either way.
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "hysim/engine/assessment.hpp"
#include "hysim/engine/simulation.hpp"

namespace hysim::engine {

struct RunOptions {
  int steps = -1;  // -1: the scene's
  int every = -1;  // -1: the scene's render.every
  // Called with the snapshot every `every` steps (and at step 0); an error stops the run.
  std::function<Status(const render::RenderSnapshot&, int frame_index)> on_frame;
  // Pace each step to start dt after the previous one on the wall clock (absolute sleeps),
  // with a HapticLoop at 1 kHz driving a simulated device (the scene's script).
  bool realtime = false;
  // Called before each step (step counts from 0): a replay attaches recorded devices here.
  std::function<void(Simulation&, int step)> before_step;
  // Checked before each step: when it becomes true (e.g. on SIGINT) the run stops there and
  // the report covers the steps done, marked partial.
  const std::atomic<bool>* stop = nullptr;
};

// Median, 99th percentile and maximum of a set of samples (0 when empty).
struct Spread {
  double median = 0.0, p99 = 0.0, max = 0.0;
};
Spread spreadOf(const std::vector<double>& values);
double percentile(std::vector<double> values, double p);

struct RunReport {
  std::string scene;
  AssessmentSettings assessment_settings;  // the scene's
  std::string integrator;
  int steps = 0;               // the steps done (fewer than asked when partial)
  bool partial = false;        // stopped early (RunOptions::stop)
  double dt = 0.0;             // s
  int nodes = 0, elements = 0, deformable_elements = 0, springs = 0, anchored = 0;
  int substeps = 1;
  double critical_dt = 0.0;    // s
  double step_us_median = 0.0, step_us_p99 = 0.0, step_us_max = 0.0;
  // The cut worker: commit steps that waited for it (and the whole wait), the commit
  // step's own work, the wall time from a pass's exit step to its commit step.
  int stalls = 0;
  double stall_ms = 0.0;
  Spread commit_us, cut_latency_ms;
  int commit_steps = 0;        // the scene's K
  std::string cut_mode;        // async or sync
  bool realtime = false;
  // Realtime runs: the haptic thread's periods between tick starts, its overruns (> 1.5x
  // the period), whether it got real-time priority, and how late steps started (us).
  Spread haptic_period_us;
  long haptic_ticks = 0, haptic_overruns = 0;
  bool haptic_realtime_priority = false;
  Spread step_start_late_us;
  int frames = 0;
  double frame_ms_median = 0.0;  // time spent in the frame callback (render + PNG)
  std::uint64_t state_hash = 0;
  int warnings = 0;
  double max_tool_force_n = 0.0;
  std::string coupling = "spring";
  double coupling_stiffness_n_per_mm = 0.0, coupling_damping_n_s_per_mm = 0.0;
  double max_hand_force_n = 0.0;        // the force asked of the device (before its clamp)
  double max_coupling_offset_mm = 0.0;  // simulated tool tip behind the device's tip
  double wall_s = 0.0;
  // The device that drove the tool at the end of the run, and what its driver counted.
  std::string device;
  bool device_connected = true;
  haptics::DeviceCounters device_counters;
  // Recording (hysim run --record) or replay (hysim replay): the file, its states, and for a
  // replay the scene's content hash then and now (they differ only when forced).
  std::string recording;
  std::uint64_t recording_states = 0;
  bool replay = false;
  std::uint64_t recorded_scene_hash = 0, scene_hash_now = 0;
  bool replay_scene_changed = false;
  std::string recorded_version;  // replay: the hysim that recorded it
  bool replay_version_changed = false;
  std::vector<PassRecord> passes;  // shaving passes (cuts), in order
  double initial_myoma_mm3 = 0.0;
  double electrode_active_s = 0.0;
  double path_length_mm = 0.0;
  double perforation_margin_mm = 0.0;
  int perforations = 0;                            // events (see PerforationEvent)
  std::vector<PerforationEvent> perforation_events;  // the first Simulation::kMaxPerforationEvents
  std::vector<double> wall_behind_myoma_mm;        // generated organs: organ.hpp's wallBehindMyomasMm at the end
  int serosa_faces = 0;                            // outer-surface faces the check measures against
  // Chips (scene `chips`): mode, simulated chips in the cavity at the end, chips that left
  // it, chips dropped over the cap, and the mean wall time of a chip step (Bullet), us.
  std::string chips_mode = "remove";
  int chips_in_cavity = 0, chips_left_cavity = 0, chips_over_cap = 0;
  double chip_step_us_mean = 0.0;
};

// Numbers a trainee or instructor reads after a run (also in the JSON report).
struct RunSummary {
  double myoma_resected_mm3 = 0.0;
  double myoma_resected_pct = 0.0;  // of the initial myoma volume
  double healthy_removed_mm3 = 0.0;
  double volume_drift_mm3 = 0.0, volume_drift_myoma_mm3 = 0.0;  // sums of the passes' (PassRecord)
  double volume_drift_healthy_mm3 = 0.0;                        // the non-myoma part
  double peeled_mm3 = 0.0;                                      // of the drift: peeled (PassRecord)
  int perforations = 0;
  int passes = 0;
  double electrode_active_s = 0.0;
  double path_length_mm = 0.0;
  double cut_ms_median = 0.0, cut_ms_max = 0.0;
  Assessment assessment;  // of the run's outcome, its duration the simulated time
};
RunSummary summarize(const RunReport& report);
// A few lines of text with the summary's numbers.
std::string summaryText(const RunReport& report);

Result<RunReport> run(Simulation& simulation, const RunOptions& options);

// JSON text of the report (keys documented in scenes/README.md).
std::string reportJson(const RunReport& report);
std::string hashHex(std::uint64_t hash);

}  // namespace hysim::engine
