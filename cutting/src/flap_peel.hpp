#pragma once
// Flap peeling after a curved cut (flap_peel.cpp): thin pieces of tissue near the cut whose
// tets are all poor are removed as a group, so that the mesh stays manifold.
#include <cstdint>
#include <functional>
#include <vector>

#include "optimize3d_internal.hpp"

namespace hysim::cutting {

// See Optimize3DOptions::flap_quality. `seeds`: the nodes the cut touched (and the repair
// region's); *dead (#T) marks removed tets, in and out (the caller removes them).
// The shape of node v's star (`around`: tets that all have v): `pieces`, its tets connected
// through faces at v; `loops`, the closed loops of boundary edges around v (0: interior).
// A manifold star is one piece with at most one loop. `valid` is false where a face at v is
// used by more than two tets or a boundary edge (v, w) has more than one fan (the link is no
// set of simple loops); then pieces and loops say nothing.
struct StarShape {
  bool valid = false;
  int pieces = 0, loops = 0;
  bool manifold() const { return valid && pieces <= 1 && loops <= 1; }
  // No more pieces and no more loops than `before` (both valid).
  bool noWorseThan(const StarShape& before) const {
    return valid && before.valid && pieces <= before.pieces && loops <= before.loops;
  }
};
StarShape starShape(const TetMesh& mesh, int v, const std::vector<std::int32_t>& around);

// `stars` must list the live tets (those not *dead) when called; removed tets are only
// marked in *dead.
// `quality(t)` (optional) returns radiusRatio of tet t's four positions in its node order
// (the optimiser's cached q*): the same value as computing it here.
void peelFlaps(const TetMesh& mesh, const CutRegion& region, const std::vector<std::int32_t>& seeds,
               const NodeStars& stars, const Optimize3DOptions& options, std::vector<std::uint8_t>* dead,
               OptimizeCounts* counts, const std::function<double(int)>* quality = nullptr);

}  // namespace hysim::cutting
