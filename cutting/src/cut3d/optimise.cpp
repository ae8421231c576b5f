// Stage 6, local optimisation (hybrid), from the nodes the cut created, moved or separated.
#include <algorithm>
#include <chrono>
#include <cstdlib>

#include "cut3d_stages.hpp"

namespace hysim::cutting::cut3d_detail {

// (Also when the surface split edges but made no cut face, e.g. a sweep's edge grazing the
// tissue: the splits may leave slivers; then the new nodes are the seeds.)
void Cut3D::optimise() {
  if (options.method == CutMethod::Hybrid && options.optimize.enabled && (!cutNodes.empty() || N1 > N0))
    runOptimisation();
  mark = Clock::now();  // (the optimisation is optimize_ms)
}

void Cut3D::runOptimisation() {
  const auto optStart = Clock::now();
  CutRegion region = makeRegion();
  // The input's lists, patched to the output mesh (the rows the cut wrote, the appended
  // tets); the optimisation takes them over.
  patchStarLists(input.T, result.mesh.T, N1, std::move(w.changedTets), &stars);
#ifdef HYSIM_CHECK_EXACT
  checkPatchedStars();
#endif
  region.stars = &stars;
  inputVolumes = materialVolumes(input);
  region.volume_target = inputVolumes;
  // The pieces cut off (options.anchored_nodes) are left as they are: no seeds there, and
  // their tets are dead to the optimisation (unmarked in `peeled` after it).
  std::vector<std::uint8_t> cutOffTets, cutOffNodes;
  if (options.anchored_nodes != nullptr) markCutOffPieces(&region, &cutOffTets, &cutOffNodes);
  const size_t before = moved.size();
  OptimizeCounts counts;
  optimizeAroundCut(result.mesh, region, options.optimize, &moved, &peeled, &counts);
  if (region.left_alone != nullptr)
    for (size_t t = 0; t < cutOffTets.size(); ++t)
      if (cutOffTets[t]) {
        peeled[t] = 0;
        result.report.cut_off_volume += tetVolume(result.mesh, t);
      }
  reportOptimisation(counts, before);
  result.report.optimize_ms = std::chrono::duration<double, std::milli>(Clock::now() - optStart).count();
}

CutRegion Cut3D::makeRegion() {
  CutRegion region;
  region.surface = &surface;
  region.eps = eps;
  region.on_cut.assign(on.begin(), on.end());
  region.on_cut.resize(N1, 1);
  region.seeds = cutNodes;
  if (cutNodes.empty())
    for (int i = N0; i < N1; ++i) region.seeds.push_back(i);
  for (const auto& ce : crossed)
    region.edge_length += (input.X.row(ce.a) - input.X.row(ce.b)).norm() / static_cast<double>(crossed.size());
  region.seeds.insert(region.seeds.end(), moved.begin(), moved.end());
  return region;
}

#ifdef HYSIM_CHECK_EXACT
void Cut3D::checkPatchedStars() const {
  StarLists full;
  buildStarLists(result.mesh.T, N1, &full);
  for (int i = 0; i < N1; ++i) {
    const std::int32_t* b = stars.pool_start[i] >= 0 ? stars.pool.data() + stars.pool_start[i] : stars.star.data() + stars.off[i];
    const size_t len = stars.pool_start[i] >= 0 ? stars.pool_len[i] : stars.off[i + 1] - stars.off[i];
    if (len != static_cast<size_t>(full.off[i + 1] - full.off[i]) || !std::equal(b, b + len, full.star.data() + full.off[i]))
      std::abort();
  }
}
#endif

// Anchored: input nodes by their flag; the nodes the cut made, moved or put on the cut by
// their position (anchored_at).
void Cut3D::markCutOffPieces(CutRegion* region, std::vector<std::uint8_t>* tets, std::vector<std::uint8_t>* nodes) {
  IndexBits repositioned(N1);
  for (const int n : moved) repositioned.mark(n);
  for (const int n : cutNodes) repositioned.mark(n);
  const std::vector<std::uint8_t>& flags = *options.anchored_nodes;
  const TetMesh& out = result.mesh;
  const std::function<bool(int)> anchored = [&](int n) {
    if (n >= N0 || repositioned.has(n)) return options.anchored_at ? options.anchored_at(out.X.row(n).transpose()) : false;
    return n < static_cast<int>(flags.size()) && flags[n] != 0;
  };
  Cut3DReport& report = result.report;
  report.cut_off_pieces =
      cutOffPieces(out, stars, region->seeds, anchored, options.free_piece_search_limit, tets, nodes);
  if (report.cut_off_pieces == 0) return;
  region->seeds.erase(
      std::remove_if(region->seeds.begin(), region->seeds.end(), [&](int n) { return (*nodes)[n] != 0; }),
      region->seeds.end());
  region->left_alone = tets;
  for (const std::uint8_t f : *tets) report.cut_off_elements += f;
}

void Cut3D::reportOptimisation(const OptimizeCounts& counts, size_t movedBefore) {
  Cut3DReport& report = result.report;
  report.optimize_iterations = counts.iterations;
  report.peeled_elements = counts.peeled;
  report.flap_peeled = counts.flap_peeled;
  report.collapsed_edges = counts.collapsed;
  report.late_snaps = counts.late_snaps;
  // (cutNodes is sorted: the added nodes sorted and merged in, as a sort of the whole.)
  const auto mid = static_cast<std::ptrdiff_t>(cutNodes.size());
  cutNodes.insert(cutNodes.end(), counts.onto_cut.begin(), counts.onto_cut.end());
  std::sort(cutNodes.begin() + mid, cutNodes.end());
  std::inplace_merge(cutNodes.begin(), cutNodes.begin() + mid, cutNodes.end());
  report.peeled_volume = counts.peeled_volume;
  report.volume_restored = counts.volume_restored;
  report.volume_moves = counts.volume_moves;
  report.optimized_nodes = static_cast<int>(moved.size() - movedBefore);
  report.collapse_ms = counts.collapse_ms;
  report.late_snap_ms = counts.late_snap_ms;
  report.move_ms = counts.move_ms;
  report.keep_volume_ms = counts.keep_volume_ms;
}

}  // namespace hysim::cutting::cut3d_detail
