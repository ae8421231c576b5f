// optimizeAroundCut: the optimiser's set-up and the order of its stages.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

#include "cut_optimizer.hpp"
#include "../flap_peel.hpp"
#include <functional>
#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::cutting::opt3d {

CutOptimizer::CutOptimizer(TetMesh& mesh_, const CutRegion& region_, const Optimize3DOptions& options_,
                           std::vector<std::int32_t>* moved_, std::vector<std::uint8_t>* dead_, OptimizeCounts* counts_)
    : mesh(mesh_),
      region(region_),
      options(options_),
      moved(moved_),
      dead(*dead_),
      counts(counts_),
      ed(mesh_, *dead_, region_.stars),
      N(mesh_.numNodes()),
      M(mesh_.numTets()),
      tetBits(mesh_.numTets()) {
  plane = region.surface && region.surface->isPlane();
  // The repairs for curved cut surfaces (shaving): curved boundaries and ridges move, slivers
  // are flipped, snaps and collapses measure volume against the local edge; plane cuts keep
  // the plane-cut behaviour.
  curved = region.surface != nullptr && !plane;
  onCut = region.on_cut;
  cosFlat = std::cos(options.boundary_flat_deg * M_PI / 180.0);
  cosCurved = curved ? std::cos(std::max(options.boundary_flat_deg, options.boundary_curved_deg) * M_PI / 180.0) : cosFlat;
  cosRidge = std::cos(options.ridge_deg * M_PI / 180.0);
  // Peeling and collapses change the volume; together they may change it by at most
  // volume_budget of the mesh's volume. Curved cuts: the budgets bound the net change (what
  // collapses and moves move about cancels) and, at volume_churn_factor x that, the sum of
  // the absolute changes. Plane cuts: the sum of the absolute changes.
  meshVolume = optimizeMeshVolume(mesh);
  const double churnFactor = curved ? std::max(1.0, options.volume_churn_factor) : 1.0;
  budget = VolumeBudget{meshVolume * options.volume_budget, churnFactor};
  // A collapse or snap may change its star's volume by collapse_volume_fraction of the star,
  // or of a regular tet with the local edge length where the star is smaller.
  edgeTet = region.edge_length * region.edge_length * region.edge_length / (6.0 * std::sqrt(2.0));
  // Moves on curved surfaces: each within move_volume_fraction of a regular tet of the local
  // edge, all together within move_volume_budget of the mesh's volume.
  moveBudget = VolumeBudget{meshVolume * options.move_volume_budget, churnFactor};
  refVolume = curved && options.collapse_volume_fraction_of_edge_tet ? edgeTet : 0.0;
  if (options.keep_volume && region.volume_target.empty()) volumesNow(startVolumes, &MaterialVolume::before);
  matVol.reserve(8);
  lastBelow.assign(N, -1);
  cons.localId.assign(N, -1);
  seeds.assign(region.seeds.begin(), region.seeds.end());
  ring.assign(N, -1);
  stamp.assign(N, -1);
  didMove.assign(N, 0);
  workAt.assign(N, -1);
  ringStart.assign(N, -1);
  ringLen.assign(N, 0);
  ringMark.assign(N, -1);
}

void CutOptimizer::run() {
  addRepairSeeds();
  peel();
  timed(&OptimizeCounts::late_snap_ms, [this] { snapNear(); });
  timed(&OptimizeCounts::collapse_ms, [this] { collapseEdges(); });
  flips();
  markRings();
  initialWork();
  smooth();
  // Moves may have made new short edges on the cut.
  timed(&OptimizeCounts::late_snap_ms, [this] { snapNear(); });
  timed(&OptimizeCounts::collapse_ms, [this] { collapseEdges(); });
  flips();
  peel();
  finish();
  timed(&OptimizeCounts::keep_volume_ms, [this] { keepVolume(); });
  if (moved)
    for (int n = 0; n < N; ++n)
      if (didMove[n]) moved->push_back(n);
}

// The nodes moved, then (curved cuts) the flaps peeled and the last-resort collapses.
void CutOptimizer::finish() {
  if (moved) moved->insert(moved->end(), lateSnapped.begin(), lateSnapped.end());
  if (counts) counts->onto_cut = lateSnapped;
  if (!curved) return;
  ed.refreshStars();  // the lists of the nodes around tets peeled above, as peelFlaps needs them
  const std::function<double(int)> quality = [this](int t) { return ed.quality(t); };
  peelFlaps(mesh, region, seeds, ed.stars(), options, &dead, counts, &quality);  // flap_peel.cpp
  // Tets below flap_quality that no repair removed, around a node earlier cuts left
  // non-manifold (every collapse there was refused): collapse their edges, the node staying
  // as it was.
  lastResort = true;
  timed(&OptimizeCounts::collapse_ms, [this] { collapseEdges(); });
}

}  // namespace hysim::cutting::opt3d

namespace hysim::cutting {

void optimizeAroundCut(TetMesh& mesh, const CutRegion& region, const Optimize3DOptions& options,
                       std::vector<std::int32_t>* moved, std::vector<std::uint8_t>* dead, OptimizeCounts* counts) {
  const int N = mesh.numNodes(), M = mesh.numTets();
  if (region.left_alone != nullptr && region.left_alone->size() == static_cast<size_t>(M)) {
    *dead = *region.left_alone;
  } else {
    dead->assign(M, 0);
  }
  if (region.seeds.empty() || N == 0) return;
  opt3d::CutOptimizer(mesh, region, options, moved, dead, counts).run();
}

}  // namespace hysim::cutting
