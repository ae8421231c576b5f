#pragma once
// Flap peeling after a curved cut (flap_peel.cpp): thin pieces of tissue near the cut whose
// tets are all poor are removed as a group, so that the mesh stays manifold.
#include <cstdint>
#include <vector>

#include "optimize3d_internal.hpp"

namespace hysim::cutting {

// See Optimize3DOptions::flap_quality. `seeds`: the nodes the cut touched (and the repair
// region's); *dead (#T) marks removed tets, in and out (the caller removes them).
void peelFlaps(const TetMesh& mesh, const CutRegion& region, const std::vector<std::int32_t>& seeds,
               const Optimize3DOptions& options, std::vector<std::uint8_t>* dead, OptimizeCounts* counts);

}  // namespace hysim::cutting
