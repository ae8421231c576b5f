#include <algorithm>
#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <vector>

#include "hysim/engine/run.hpp"

namespace hysim::engine {
namespace {

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  const size_t k = std::min(values.size() - 1, static_cast<size_t>(p * static_cast<double>(values.size() - 1) + 0.5));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

}  // namespace

std::string hashHex(std::uint64_t hash) {
  char buf[17];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(hash));
  return buf;
}

Result<RunReport> run(Simulation& sim, const RunOptions& options) {
  using Clock = std::chrono::steady_clock;
  const Scene& scene = sim.scene();
  RunReport r;
  r.scene = scene.name;
  r.steps = options.steps >= 0 ? options.steps : scene.steps;
  const int every = options.every > 0 ? options.every : scene.render.every;
  r.dt = scene.sim.dt;
  r.nodes = sim.mesh().numNodes();
  r.elements = sim.mesh().numTets();
  r.deformable_elements = sim.numDeformableTets();
  r.springs = static_cast<int>(sim.model().springs.rows());
  r.anchored = sim.numAnchored();
  r.substeps = sim.model().substeps;
  r.critical_dt = sim.model().critical_dt;
  r.integrator = scene.sim.integrator == sim::Integrator::ImplicitEuler ? "implicit_euler" : "symplectic_euler";

  std::vector<double> step_us;
  step_us.reserve(static_cast<size_t>(r.steps));
  std::vector<double> frame_ms;
  render::RenderSnapshot snapshot;
  const auto wall0 = Clock::now();
  auto frame = [&]() -> Status {
    if (!options.on_frame) return Status::Ok();
    const auto t0 = Clock::now();
    sim.fillSnapshot(snapshot);
    Status st = options.on_frame(snapshot, r.frames);
    frame_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    ++r.frames;
    return st;
  };
  if (Status st = frame(); !st.ok()) return Error{st.error()};
  for (int i = 0; i < r.steps; ++i) {
    const auto t0 = Clock::now();
    sim.step();
    step_us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
    r.max_tool_force_n = std::max(r.max_tool_force_n, sim.toolForceN().norm());
    if ((i + 1) % every == 0) {
      if (Status st = frame(); !st.ok()) return Error{st.error()};
    }
  }
  r.wall_s = std::chrono::duration<double>(Clock::now() - wall0).count();
  r.step_us_median = percentile(step_us, 0.5);
  r.step_us_p99 = percentile(step_us, 0.99);
  r.step_us_max = step_us.empty() ? 0.0 : *std::max_element(step_us.begin(), step_us.end());
  r.frame_ms_median = percentile(frame_ms, 0.5);
  r.state_hash = sim.stateHash();
  r.warnings = sim.state().warnings;
  r.passes = sim.passes();
  r.initial_myoma_mm3 = sim.initialMyomaVolume();
  r.electrode_active_s = sim.electrodeActiveSeconds();
  r.path_length_mm = sim.pathLengthMm();
  if (const ChipWorld* chips = sim.chips(); chips != nullptr) {
    r.chips_mode = "simulate";
    r.chips_in_cavity = chips->numChips();
    r.chips_left_cavity = chips->removedOutside();
    r.chips_over_cap = chips->removedOverCap();
    r.chip_step_us_mean = sim.chipSteps() > 0 ? 1e6 * sim.chipStepSeconds() / static_cast<double>(sim.chipSteps()) : 0.0;
  }
  return r;
}

std::string reportJson(const RunReport& r) {
  nlohmann::ordered_json j;
  j["scene"] = r.scene;
  j["integrator"] = r.integrator;
  j["steps"] = r.steps;
  j["dt"] = r.dt;
  j["nodes"] = r.nodes;
  j["elements"] = r.elements;
  j["deformable_elements"] = r.deformable_elements;
  j["springs"] = r.springs;
  j["anchored_nodes"] = r.anchored;
  j["substeps"] = r.substeps;
  j["critical_dt"] = r.critical_dt;
  j["step_us"] = {{"median", r.step_us_median}, {"p99", r.step_us_p99}, {"max", r.step_us_max}};
  j["frames"] = r.frames;
  j["frame_ms"] = {{"median", r.frame_ms_median}};
  j["state_hash"] = hashHex(r.state_hash);
  j["warnings"] = r.warnings;
  j["max_tool_force_n"] = r.max_tool_force_n;
  j["wall_s"] = r.wall_s;
  std::vector<double> cut_ms;
  nlohmann::ordered_json per_pass = nlohmann::ordered_json::array();
  for (const PassRecord& p : r.passes) {
    cut_ms.push_back(p.cut_ms);
    nlohmann::ordered_json e;
    e["time_s"] = p.time_s;
    e["elements"] = p.elements;
    e["nodes"] = p.nodes;
    e["q_min"] = p.q_min;
    e["cut_ms"] = p.cut_ms;
    e["chips"] = p.chips;
    e["removed_mm3"] = p.removed_mm3;
    e["removed_myoma_mm3"] = p.removed_myoma_mm3;
    e["sweep_area_mm2"] = p.sweep_area_mm2;
    e["crossed_edges"] = p.crossed_edges;
    e["snapped_nodes"] = p.snapped_nodes;
    e["split_edges"] = p.split_edges;
    e["duplicated_nodes"] = p.duplicated_nodes;
    e["cut_faces"] = p.cut_faces;
    e["components"] = p.components;
    e["substeps"] = p.substeps;
    e["added_mass_g"] = p.added_mass_g;
    if (p.cut_failed) e["failed"] = p.message;
    per_pass.push_back(e);
  }
  double myoma_removed = 0.0, removed = 0.0;
  for (const PassRecord& p : r.passes) {
    myoma_removed += p.removed_myoma_mm3;
    removed += p.removed_mm3;
  }
  j["myoma_resected_mm3"] = myoma_removed;
  j["myoma_resected_pct"] = r.initial_myoma_mm3 > 0.0 ? 100.0 * myoma_removed / r.initial_myoma_mm3 : 0.0;
  j["healthy_removed_mm3"] = removed - myoma_removed;
  j["electrode_active_s"] = r.electrode_active_s;
  j["path_length_mm"] = r.path_length_mm;
  j["passes"] = r.passes.size();
  j["cut_ms"] = {{"median", percentile(cut_ms, 0.5)}, {"max", cut_ms.empty() ? 0.0 : *std::max_element(cut_ms.begin(), cut_ms.end())}};
  j["chips"] = {{"mode", r.chips_mode}, {"in_cavity", r.chips_in_cavity}, {"left_cavity", r.chips_left_cavity},
                {"over_cap", r.chips_over_cap}, {"step_us_mean", r.chip_step_us_mean}};
  j["per_pass"] = per_pass;
  return j.dump(2) + "\n";
}

}  // namespace hysim::engine
