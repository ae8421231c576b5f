// CPU side of the renderer: normals, camera matrices, the demo scene. No GL needed.
#include <gtest/gtest.h>

#include <cmath>

#include "hysim/render/demo_scene.hpp"
#include "hysim/render/renderer.hpp"

namespace hr = hysim::render;

namespace {
// Applies a column-major 4x4 to a point, returns clip coordinates.
std::array<float, 4> apply(const std::array<float, 16>& m, std::array<float, 4> p) {
  std::array<float, 4> r{};
  for (int row = 0; row < 4; ++row) {
    for (int k = 0; k < 4; ++k) r[row] += m[k * 4 + row] * p[k];
  }
  return r;
}
}  // namespace

TEST(VertexNormals, AreaWeightedAndNormalised) {
  // Two triangles sharing vertex 0: a big one in the z=0 plane (normal +z) and a small
  // one in the x=0 plane (normal +x). The shared normal leans towards the big one.
  const std::vector<float> positions = {0, 0, 0, 10, 0, 0, 0, 10, 0,   // big, z = 0
                                        0, 1, 0, 0, 0, 1};             // small, x = 0
  const std::vector<std::uint32_t> triangles = {0, 1, 2, 0, 3, 4};
  std::vector<float> normals;
  hr::computeVertexNormals(positions, triangles, normals);
  ASSERT_EQ(normals.size(), positions.size());
  // Face normals (unnormalised): big = (0,0,100), small = (1,0,0).
  const float len = std::sqrt(1.0f + 100.0f * 100.0f);
  EXPECT_NEAR(normals[0], 1.0f / len, 1e-6f);
  EXPECT_NEAR(normals[2], 100.0f / len, 1e-6f);
  EXPECT_NEAR(normals[5], 1.0f, 1e-6f);   // vertex 1: only the big triangle
  EXPECT_NEAR(normals[9], 1.0f, 1e-6f);   // vertex 3: only the small one, +x
}

TEST(VertexNormals, IgnoresBadTrianglesAndIsolatedVertices) {
  const std::vector<float> positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 5, 5};
  const std::vector<std::uint32_t> triangles = {0, 1, 2, 0, 1, 99};
  std::vector<float> normals(1, 42.0f);  // stale contents must be overwritten
  hr::computeVertexNormals(positions, triangles, normals);
  ASSERT_EQ(normals.size(), 12u);
  EXPECT_FLOAT_EQ(normals[2], 1.0f);
  EXPECT_FLOAT_EQ(normals[9], 0.0f);
  EXPECT_FLOAT_EQ(normals[10], 0.0f);
  EXPECT_FLOAT_EQ(normals[11], 0.0f);
}

TEST(CameraMatrices, ForeObliqueLensLooksTowardsMinusUp) {
  hr::Camera camera;
  camera.tip = {1, 2, 3};
  camera.axis = {0, 0, 1};
  camera.up = {0, 1, 0};
  camera.lens_deg = 30.0f;
  const auto m = hr::cameraMatrices(camera, 640, 480);
  EXPECT_NEAR(m.view_dir[0], 0.0f, 1e-6f);
  EXPECT_NEAR(m.view_dir[1], -0.5f, 1e-6f);
  EXPECT_NEAR(m.view_dir[2], std::sqrt(3.0f) / 2.0f, 1e-6f);
  // A point along the view direction projects to the image centre...
  const std::array<float, 4> ahead = {1 + 10 * m.view_dir[0], 2 + 10 * m.view_dir[1],
                                      3 + 10 * m.view_dir[2], 1};
  auto clip = apply(m.projection, apply(m.view, ahead));
  EXPECT_NEAR(clip[0] / clip[3], 0.0f, 1e-5f);
  EXPECT_NEAR(clip[1] / clip[3], 0.0f, 1e-5f);
  // ...and a point along the shaft axis appears above the centre (the lens looks down).
  clip = apply(m.projection, apply(m.view, {1, 2, 13, 1}));
  EXPECT_GT(clip[1] / clip[3], 0.1f);
  // The circle (diameter = image height) spans fov_deg: a point 45 degrees off the view
  // direction towards image-up lands on the top edge (NDC y = 1) for fov 90.
  const float c = std::cos(0.25f * 3.14159265f), s = std::sin(0.25f * 3.14159265f);
  const std::array<float, 4> edge = {1 + 10 * (c * m.view_dir[0] + s * m.image_up[0]),
                                     2 + 10 * (c * m.view_dir[1] + s * m.image_up[1]),
                                     3 + 10 * (c * m.view_dir[2] + s * m.image_up[2]), 1};
  clip = apply(m.projection, apply(m.view, edge));
  EXPECT_NEAR(clip[1] / clip[3], 1.0f, 1e-4f);
}

TEST(DemoScene, HasRequestedSizeAndBothMaterials) {
  const hr::RenderSnapshot s = hr::makeDemoSnapshot({});
  const std::size_t nt = s.tissue.triangles.size() / 3;
  EXPECT_GT(nt, 9000u);
  EXPECT_LT(nt, 11000u);
  EXPECT_EQ(s.tissue.material.size(), s.tissue.positions.size() / 3);
  int myoma = 0;
  for (auto m : s.tissue.material) myoma += m == hr::SurfaceMaterial::Myoma;
  EXPECT_GT(myoma, 50);
  EXPECT_TRUE(s.tool_visible);
  // Outward (counter-clockwise from outside) orientation: normals point away from the
  // cavity centre on the ellipsoid part.
  std::vector<float> normals;
  hr::computeVertexNormals(s.tissue.positions, s.tissue.triangles, normals);
  int outward = 0, total = 0;
  for (std::size_t v = 0; v < normals.size() / 3; ++v) {
    if (s.tissue.material[v] != hr::SurfaceMaterial::Endometrium) continue;
    float d = 0;
    for (int k = 0; k < 3; ++k) d += normals[3 * v + k] * s.tissue.positions[3 * v + k];
    outward += d > 0;
    ++total;
  }
  EXPECT_GT(outward, total * 99 / 100);
}
