#pragma once
// Pictures of planar triangle meshes (like the paper's Fig. 1): triangles filled by quality
// (green q = 1/2 ... red q = 0), edges in grey, the cut in black, rasterised on the CPU.
#include <string>
#include <vector>

#include "hysim/cutting/mesh.hpp"
#include "hysim/render/image.hpp"

namespace hysim::tools {

struct MeshPictureBox {
  double x0 = 0, y0 = 0, x1 = 1, y1 = 1;  // world rectangle shown
};
MeshPictureBox pictureBox(const cutting::TriMesh& mesh, double margin_fraction = 0.05);

// `cut_edges`: node pairs drawn thick black (may be empty).
render::Image drawMesh(const cutting::TriMesh& mesh, const MeshPictureBox& box, int width,
                       const std::vector<std::array<int, 2>>& cut_edges = {});

}  // namespace hysim::tools
