#pragma once
// Shared between cut3d.cpp and optimize3d.cpp: the stars of the nodes the local optimisation
// may move, built by the cut from what it touched (no whole-mesh adjacency).
#include <cstdint>
#include <vector>

#include "hysim/cutting/cut3d.hpp"

namespace hysim::cutting {

struct LocalStars {
  std::vector<std::int32_t> nodes;   // movable nodes (interior, off the cut)
  std::vector<std::int32_t> offset;  // #nodes + 1, CSR into tets
  std::vector<std::int32_t> tets;    // every tet around each node (new mesh indices)
};

void optimizeLocal3D(TetMesh& mesh, const LocalStars& stars, const Optimize3DOptions& options,
                     std::vector<std::int32_t>* moved, int* iterations);

}  // namespace hysim::cutting
