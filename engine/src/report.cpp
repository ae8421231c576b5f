#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <vector>

#include "hysim/engine/run.hpp"

namespace hysim::engine {

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  const size_t k = std::min(values.size() - 1, static_cast<size_t>(p * static_cast<double>(values.size() - 1) + 0.5));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

std::string hashHex(std::uint64_t hash) {
  char buf[17];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(hash));
  return buf;
}

namespace {

nlohmann::ordered_json assessmentJson(const Assessment& a) {
  nlohmann::ordered_json items = nlohmann::ordered_json::array();
  for (const AssessmentItem& i : a.items) {
    items.push_back({{"name", i.name}, {"value", i.value}, {"threshold", i.threshold},
                     {"rule", i.at_least ? "at_least" : "at_most"}, {"unit", i.unit}, {"passed", i.passed},
                     {"score", i.score}, {"weight", i.weight}});
  }
  return {{"score", a.score}, {"passed", a.passed}, {"items", items}};
}

}  // namespace

RunSummary summarize(const RunReport& r) {
  RunSummary s;
  double removed = 0.0;
  std::vector<double> cut_ms;
  for (const PassRecord& p : r.passes) {
    s.myoma_resected_mm3 += p.removed_myoma_mm3;
    removed += p.removed_mm3;
    s.volume_drift_mm3 += p.volume_drift_mm3;
    s.volume_drift_myoma_mm3 += p.volume_drift_myoma_mm3;
    s.peeled_mm3 += p.peeled_mm3;
    cut_ms.push_back(p.cut_ms);
  }
  s.myoma_resected_pct = r.initial_myoma_mm3 > 0.0 ? 100.0 * s.myoma_resected_mm3 / r.initial_myoma_mm3 : 0.0;
  s.healthy_removed_mm3 = removed - s.myoma_resected_mm3;
  s.volume_drift_healthy_mm3 = s.volume_drift_mm3 - s.volume_drift_myoma_mm3;
  s.perforations = r.perforations;
  s.passes = static_cast<int>(r.passes.size());
  s.electrode_active_s = r.electrode_active_s;
  s.path_length_mm = r.path_length_mm;
  s.cut_ms_median = percentile(cut_ms, 0.5);
  s.cut_ms_max = cut_ms.empty() ? 0.0 : *std::max_element(cut_ms.begin(), cut_ms.end());
  s.assessment = assess(r.assessment_settings, AssessedOutcome{s.myoma_resected_pct, s.healthy_removed_mm3, s.perforations,
                                                               r.steps * r.dt});
  return s;
}

std::string summaryText(const RunReport& r) {
  const RunSummary s = summarize(r);
  char buf[1024];
  std::snprintf(buf, sizeof(buf),
                "myoma resected    %.0f mm3 (%.1f%% of %.0f mm3)\n"
                "healthy removed   %.0f mm3\n"
                "perforations      %d (margin %.1f mm to the serosa)\n"
                "passes            %d (cut ms median %.1f, max %.1f)\n"
                "electrode active  %.2f s\n"
                "path length       %.0f mm\n",
                s.myoma_resected_mm3, s.myoma_resected_pct, r.initial_myoma_mm3, s.healthy_removed_mm3, s.perforations,
                r.perforation_margin_mm, s.passes, s.cut_ms_median, s.cut_ms_max, s.electrode_active_s, s.path_length_mm);
  std::string text = buf;
  for (size_t k = 0; k < r.wall_behind_myoma_mm.size(); ++k) {
    char line[96];
    std::snprintf(line, sizeof line, "wall behind myoma %zu: %.1f mm to the serosa\n", k + 1, r.wall_behind_myoma_mm[k]);
    text += line;
  }
  return text + assessmentText(s.assessment);
}

std::string reportJson(const RunReport& r) {
  nlohmann::ordered_json j;
  j["scene"] = r.scene;
  j["integrator"] = r.integrator;
  j["steps"] = r.steps;
  j["partial"] = r.partial;
  j["dt"] = r.dt;
  j["nodes"] = r.nodes;
  j["elements"] = r.elements;
  j["deformable_elements"] = r.deformable_elements;
  j["springs"] = r.springs;
  j["anchored_nodes"] = r.anchored;
  j["substeps"] = r.substeps;
  j["critical_dt"] = r.critical_dt;
  j["step_us"] = {{"median", r.step_us_median}, {"p99", r.step_us_p99}, {"max", r.step_us_max}};
  auto spread = [](const Spread& s) { return nlohmann::ordered_json{{"median", s.median}, {"p99", s.p99}, {"max", s.max}}; };
  j["realtime"] = r.realtime;
  j["cut_mode"] = r.cut_mode;
  j["commit_steps"] = r.commit_steps;
  j["stalls"] = r.stalls;
  j["stall_ms"] = r.stall_ms;
  j["commit_us"] = spread(r.commit_us);
  j["cut_latency_ms"] = spread(r.cut_latency_ms);
  if (r.realtime) {
    j["haptic_period_us"] = {{"p50", r.haptic_period_us.median}, {"p99", r.haptic_period_us.p99},
                             {"max", r.haptic_period_us.max}};
    j["haptic_ticks"] = r.haptic_ticks;
    j["haptic_overruns"] = r.haptic_overruns;
    j["haptic_realtime_priority"] = r.haptic_realtime_priority;
    j["step_start_late_us"] = spread(r.step_start_late_us);
  }
  j["frames"] = r.frames;
  j["frame_ms"] = {{"median", r.frame_ms_median}};
  j["state_hash"] = hashHex(r.state_hash);
  j["warnings"] = r.warnings;
  j["max_tool_force_n"] = r.max_tool_force_n;
  j["coupling"] = {{"mode", r.coupling},
                   {"stiffness_n_per_mm", r.coupling_stiffness_n_per_mm},
                   {"damping_n_s_per_mm", r.coupling_damping_n_s_per_mm}};
  j["max_hand_force_n"] = r.max_hand_force_n;
  j["max_coupling_offset_mm"] = r.max_coupling_offset_mm;
  j["wall_s"] = r.wall_s;
  nlohmann::ordered_json per_pass = nlohmann::ordered_json::array();
  for (const PassRecord& p : r.passes) {
    nlohmann::ordered_json e;
    e["time_s"] = p.time_s;
    e["elements"] = p.elements;
    e["nodes"] = p.nodes;
    e["q_min"] = p.q_min;
    e["cut_ms"] = p.cut_ms;
    e["cut_parts_ms"] = {{"cut3d", p.cut3d_ms},         {"components", p.components_ms}, {"model", p.model_ms},
                         {"surface", p.surface_ms},     {"collision", p.collision_ms},   {"locator", p.locator_ms},
                         {"chips", p.chips_ms},         {"stats", p.stats_ms},           {"other", p.other_ms}};
    e["exit_step"] = p.exit_step;
    e["commit_step"] = p.commit_step;
    e["map_ms"] = p.map_ms;
    e["commit_us"] = p.commit_us;
    e["stall_ms"] = p.stall_ms;
    e["latency_ms"] = p.latency_ms;
    e["chips"] = p.chips;
    e["removed_mm3"] = p.removed_mm3;
    e["removed_myoma_mm3"] = p.removed_myoma_mm3;
    e["volume_drift_mm3"] = p.volume_drift_mm3;
    e["volume_drift_myoma_mm3"] = p.volume_drift_myoma_mm3;
    e["peeled_mm3"] = p.peeled_mm3;
    e["sweep_area_mm2"] = p.sweep_area_mm2;
    e["crossed_edges"] = p.crossed_edges;
    e["snapped_nodes"] = p.snapped_nodes;
    e["split_edges"] = p.split_edges;
    e["duplicated_nodes"] = p.duplicated_nodes;
    e["unoptimised_chip_elements"] = p.unoptimised_chip_elements;
    e["cut_faces"] = p.cut_faces;
    e["components"] = p.components;
    e["substeps"] = p.substeps;
    e["added_mass_g"] = p.added_mass_g;
    e["stability_nodes"] = p.stability_nodes;
    e["global_stability"] = p.global_stability;
    if (p.cut_failed) e["failed"] = p.message;
    per_pass.push_back(e);
  }
  const RunSummary sum = summarize(r);
  j["myoma_resected_mm3"] = sum.myoma_resected_mm3;
  j["myoma_resected_pct"] = sum.myoma_resected_pct;
  j["healthy_removed_mm3"] = sum.healthy_removed_mm3;
  j["volume_drift_mm3"] = sum.volume_drift_mm3;
  j["volume_drift_myoma_mm3"] = sum.volume_drift_myoma_mm3;
  j["volume_drift_healthy_mm3"] = sum.volume_drift_healthy_mm3;
  j["peeled_mm3"] = sum.peeled_mm3;
  j["electrode_active_s"] = r.electrode_active_s;
  j["path_length_mm"] = r.path_length_mm;
  j["passes"] = r.passes.size();
  j["cut_ms"] = {{"median", sum.cut_ms_median}, {"max", sum.cut_ms_max}};
  j["perforation_margin_mm"] = r.perforation_margin_mm;
  j["serosa_faces"] = r.serosa_faces;
  if (!r.wall_behind_myoma_mm.empty()) {
    nlohmann::ordered_json walls = nlohmann::ordered_json::array();
    for (double w : r.wall_behind_myoma_mm) walls.push_back(std::isnan(w) ? nlohmann::ordered_json() : nlohmann::ordered_json(w));
    j["wall_behind_myoma_mm"] = walls;
  }
  j["perforations"] = r.perforations;
  nlohmann::ordered_json events = nlohmann::ordered_json::array();
  for (const PerforationEvent& e : r.perforation_events) {
    events.push_back({{"time_s", e.time_s}, {"end_s", e.end_s}, {"min_distance_mm", e.min_distance_mm}});
  }
  j["perforation_events"] = events;
  j["assessment"] = assessmentJson(sum.assessment);
  j["chips"] = {{"mode", r.chips_mode}, {"in_cavity", r.chips_in_cavity}, {"left_cavity", r.chips_left_cavity},
                {"over_cap", r.chips_over_cap}, {"step_us_mean", r.chip_step_us_mean}};
  const haptics::DeviceCounters& c = r.device_counters;
  j["device"] = {{"name", r.device},
                 {"connected", r.device_connected},
                 {"packets_received", c.packets_received},
                 {"packets_lost", c.packets_lost},
                 {"packets_late", c.packets_late},
                 {"packets_malformed", c.packets_malformed},
                 {"stale_periods", c.stale_periods},
                 {"disconnects", c.disconnects},
                 {"reconnects", c.reconnects}};
  if (!r.recording.empty()) {
    j["recording"] = {{"file", r.recording}, {"states", r.recording_states}, {"replay", r.replay}};
    if (r.replay) {
      j["recording"]["scene_hash_recorded"] = hashHex(r.recorded_scene_hash);
      j["recording"]["scene_hash_now"] = hashHex(r.scene_hash_now);
      j["recording"]["scene_changed"] = r.replay_scene_changed;
      j["recording"]["recorded_by"] = r.recorded_version;
      j["recording"]["version_changed"] = r.replay_version_changed;
    }
  }
  j["per_pass"] = per_pass;
  // Names from devices and scenes may hold bytes that are not UTF-8: replaced, not fatal.
  return j.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";
}

}  // namespace hysim::engine
