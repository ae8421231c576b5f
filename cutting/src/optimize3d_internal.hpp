#pragma once
// Shared between cut3d.cpp and optimize3d.cpp: what the local optimisation after a cut needs
// to know about the cut (which nodes lie on it, the surface for side checks) and where to
// start (the nodes the cut touched).
#include <cstdint>
#include <vector>

#include "hysim/cutting/cut3d.hpp"

namespace hysim::cutting {

struct CutRegion {
  const CutSurface* surface = nullptr;
  double eps = 0;                       // on-surface tolerance (absolute)
  std::vector<std::int32_t> seeds;      // nodes the cut created, moved or separated
  std::vector<std::uint8_t> on_cut;     // #N of the output mesh: node lies on the cut
  double edge_length = 0;               // mean length of the crossed edges (the local mesh size)
};

struct OptimizeCounts {
  int iterations = 0;
  int peeled = 0;
  int collapsed = 0;
  int late_snaps = 0;
  int flips = 0;
  int flap_peeled = 0;  // of peeled: in flaps (flap_peel.cpp)
  std::vector<std::int32_t> onto_cut;  // the nodes late snapping moved onto the cut
  double peeled_volume = 0;
};

// See Optimize3DOptions. Appends the nodes it moved to *moved; *dead (#T) marks the slivers
// it peeled (the caller removes them).
void optimizeAroundCut(TetMesh& mesh, const CutRegion& region, const Optimize3DOptions& options,
                       std::vector<std::int32_t>* moved, std::vector<std::uint8_t>* dead, OptimizeCounts* counts);

}  // namespace hysim::cutting
