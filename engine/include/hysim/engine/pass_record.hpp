#pragma once
// What one shaving pass did and what it cost: the report's per-pass entry.
#include <cstdint>
#include <string>

namespace hysim::engine {

// One shaving pass: the loop entered the tissue with the pedal down and left it (or the
// pedal was released); the accumulated sweep was cut with the hybrid method on the cut
// worker and the result committed a fixed number of steps later.
struct PassRecord {
  double time_s = 0.0;       // simulation time of the exit step
  std::int64_t exit_step = 0;    // state steps when the loop left the tissue
  std::int64_t commit_step = 0;  // state steps when the result replaced the tissue
  int elements = 0;          // after the pass (chips removed)
  int nodes = 0;
  double q_min = 0.0;        // q* = r_in / R_circ of the worst tet after the pass
  // Wall times (measurement only; nothing simulated depends on them). cut_ms: the worker's
  // whole job (cut, optimisation, model update, surface, collision, locator, chips); its
  // parts: cutting::cut3d, the free pieces and the compacted mesh, the tissue model
  // (masses, springs, stability), boundary and render surface, the FCL hierarchy, the tet
  // locator and lookups, chip shapes, mesh statistics, and what is left (other_ms).
  // map_ms: carrying the sweep's last rows to the rest shape on the exit step (simulation
  // thread). commit_us: the commit step's remap and swap; stall_ms: how long that step
  // waited for the worker (0 when the result was ready); latency_ms: exit step to commit
  // step in wall time.
  double cut_ms = 0.0;
  double map_ms = 0.0, cut3d_ms = 0.0, components_ms = 0.0, model_ms = 0.0, surface_ms = 0.0,
         collision_ms = 0.0, locator_ms = 0.0, chips_ms = 0.0, stats_ms = 0.0, other_ms = 0.0;
  double commit_us = 0.0, stall_ms = 0.0, latency_ms = 0.0;
  bool stalled = false;      // the commit step had to wait for the worker
  int chips = 0;             // free pieces removed
  double removed_mm3 = 0.0;  // volume of the removed chips
  double removed_myoma_mm3 = 0.0;
  // Volume the cut lost (Cut3DReport::volume_drift: its input less its output, chips
  // included, so they are no drift; peeled slivers and flaps are); positive: lost.
  double volume_drift_mm3 = 0.0, volume_drift_myoma_mm3 = 0.0;
  double peeled_mm3 = 0.0;  // of the drift: slivers and flaps the optimisation removed (Cut3DReport::peeled_volume)
  double sweep_area_mm2 = 0.0;  // area of the cut surface (the loop's sweep)
  int crossed_edges = 0, snapped_nodes = 0, split_edges = 0, duplicated_nodes = 0, cut_faces = 0;
  int unoptimised_chip_elements = 0;  // chips.optimize false: the tets the cut left as cut
  int components = 0;        // pieces of the cut mesh (chips included); -1: not counted
  int substeps = 0;          // of the rebuilt model
  double added_mass_g = 0.0; // mass scaling needed to keep substeps within the cap (since the start)
  int stability_nodes = 0;   // free nodes of the model update's frequency estimate
  bool global_stability = false;  // that estimate covered the whole mesh (the highest mode was near the cut)
  bool cut_failed = false;   // the cut was refused (the mesh is left as it was)
  std::string message;
};

}  // namespace hysim::engine
