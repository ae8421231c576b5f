#pragma once
// Pictures of tetrahedral meshes (hysim tables --table 2 --pictures): the boundary triangles
// seen from a fixed oblique direction, orthographic, flat shaded with a z-buffer and the
// triangle edges drawn, rasterised on the CPU (no display or GPU needed, same pixels on every
// machine). After a cut, each connected piece is moved `gap` mm away from the cut plane along
// its normal so that the cut surface shows; faces lying in the cut plane are drawn in a
// second colour.
#include <Eigen/Core>

#include "hysim/cutting/mesh.hpp"
#include "hysim/render/image.hpp"

namespace hysim::tools {

struct TetPictureOptions {
  int width = 640, height = 480;
  Eigen::Vector3d view_from{0.9, -1.4, 0.8};  // direction from the mesh to the eye
  Eigen::Vector3d up{0, 0, 1};
  bool has_plane = false;          // a cut plane: separate the pieces, colour the cut faces
  Eigen::Vector3d plane_point = Eigen::Vector3d::Zero();
  Eigen::Vector3d plane_normal = Eigen::Vector3d::UnitZ();
  double gap = 3.0;                // mm each piece is moved away from the plane
  // The world box that fills the picture (so that pictures of one mesh share a scale); empty
  // (min > max): the picture's own vertices.
  Eigen::Vector3d frame_min{1, 1, 1}, frame_max{0, 0, 0};
};

render::Image drawTetMesh(const cutting::TetMesh& mesh, const TetPictureOptions& options = {});

}  // namespace hysim::tools
