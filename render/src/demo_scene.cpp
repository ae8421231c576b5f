// Procedural cavity-with-myoma scene. The cavity is one connected surface (as a scene's
// tissue surface would be): an ellipsoid whose radius, seen from the cavity centre, is
// smoothly replaced by the near side of a sphere where the myoma bulges in.
#include "hysim/render/demo_scene.hpp"

#include <algorithm>
#include <cmath>

namespace hysim::render {
namespace {

constexpr float kPi = 3.14159265358979323846f;

// Polynomial smooth minimum: a rounded crease of width k where myoma meets the wall.
float smoothMin(float a, float b, float k) {
  const float h = std::clamp(0.5f + 0.5f * (b - a) / k, 0.0f, 1.0f);
  return b + (a - b) * h - k * h * (1.0f - h);
}

void addCavity(const DemoSceneOptions& options, SurfaceMesh& mesh) {
  // Semi-axes (mm): a roomy distended cavity, long axis z (cervix at -z, fundus at +z).
  const float ax = 16.0f, ay = 12.0f, az = 24.0f;
  // The myoma: a sphere of radius R sunk into the posterior (-y) wall so that a cap of
  // height H stands in the cavity. Its base circle on the wall has radius `base`.
  const float radius = options.myoma_radius_mm;
  const float height = 0.75f * radius;
  const float base = std::sqrt(radius * radius - (radius - height) * (radius - height));
  const float crease = 1.5f;  // width of the rounded fold where myoma meets the wall
  float mx = 0.15f, my = -1.0f, mz = 0.35f;
  {
    const float n = std::sqrt(mx * mx + my * my + mz * mz);
    mx /= n, my /= n, mz /= n;
  }
  auto wallRadius = [&](float dx, float dy, float dz) {
    return 1.0f / std::sqrt((dx / ax) * (dx / ax) + (dy / ay) * (dy / ay) + (dz / az) * (dz / az));
  };
  const float m_wall = wallRadius(mx, my, mz);

  // Latitude-longitude grid whose pole is the myoma's centre direction: the myoma's rim
  // is then a circle of latitude, so its material border is round instead of a staircase
  // across grid cells. (e1, e2, e3) is right-handed, which keeps the triangle winding.
  const int target = std::max(options.target_triangles, 64);
  const int segments = std::max(8, static_cast<int>(std::lround(std::sqrt(float(target)))));
  const int rings = std::max(3, static_cast<int>(std::lround(float(target) / (2.0f * segments))) + 1);
  const std::array<float, 3> e1{mx, my, mz};
  std::array<float, 3> e2{1.0f - mx * mx, -mx * my, -mx * mz};  // x minus its e1 part
  {
    const float n = std::sqrt(e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]);
    for (float& v : e2) v /= n;
  }
  const std::array<float, 3> e3{e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                                e1[0] * e2[1] - e1[1] * e2[0]};

  auto surfacePoint = [&](float theta, float phi, SurfaceMaterial& material) {
    const float a = std::cos(theta), b = std::sin(theta) * std::cos(phi),
                c = std::sin(theta) * std::sin(phi);
    const float dx = a * e1[0] + b * e2[0] + c * e3[0];
    const float dy = a * e1[1] + b * e2[1] + c * e3[1];
    const float dz = a * e1[2] + b * e2[2] + c * e3[2];
    const float wall = wallRadius(dx, dy, dz);
    // Distance along the wall from the myoma's centre, measured as an arc at the pole's
    // wall radius: constant along a grid ring, so the rim follows a ring exactly.
    const float x = m_wall * theta;
    const float cap = x < radius ? std::sqrt(radius * radius - x * x) - (radius - height)
                                 : -(radius - height);
    // Smooth max(cap, 0): rounds the fold at the base of the myoma.
    const float bump = -smoothMin(-cap, 0.0f, crease);
    material = (x < base - 0.5f * crease) ? SurfaceMaterial::Myoma : SurfaceMaterial::Endometrium;
    // Gentle folds of the lining, so the light has something to play on.
    const float folds = 1.0f + 0.012f * std::sin(6.0f * dx + 1.3f) * std::sin(5.0f * dz + 0.4f);
    const float r = wall * folds - bump;
    return std::array<float, 3>{r * dx, r * dy, r * dz};
  };

  auto addVertex = [&](float theta, float phi) {
    SurfaceMaterial m;
    const auto p = surfacePoint(theta, phi, m);
    for (float coordinate : p) mesh.positions.push_back(coordinate);
    mesh.material.push_back(m);
  };
  addVertex(0.0f, 0.0f);  // pole at the myoma's top: index 0
  for (int i = 1; i < rings; ++i) {
    const float theta = kPi * float(i) / float(rings);
    for (int j = 0; j < segments; ++j) addVertex(theta, 2.0f * kPi * float(j) / float(segments));
  }
  addVertex(kPi, 0.0f);  // opposite pole
  const auto south = static_cast<std::uint32_t>(mesh.positions.size() / 3 - 1);
  auto ring = [&](int i, int j) {
    return static_cast<std::uint32_t>(1 + (i - 1) * segments + (j % segments));
  };
  auto& f = mesh.triangles;
  // Counter-clockwise seen from outside (outside = away from the cavity centre).
  for (int j = 0; j < segments; ++j) f.insert(f.end(), {0u, ring(1, j), ring(1, j + 1)});
  for (int i = 1; i + 1 < rings; ++i) {
    for (int j = 0; j < segments; ++j) {
      f.insert(f.end(), {ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      f.insert(f.end(), {ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
  }
  for (int j = 0; j < segments; ++j) {
    f.insert(f.end(), {ring(rings - 1, j), south, ring(rings - 1, j + 1)});
  }
}

// A loop-electrode stand-in: a thin rod with a rounded end, along the body z axis.
void addTool(SurfaceMesh& mesh) {
  const int segments = 20;
  const float radius = 0.4f, length = 10.0f;
  for (int k = 0; k < 2; ++k) {
    for (int j = 0; j < segments; ++j) {
      const float phi = 2.0f * kPi * float(j) / float(segments);
      mesh.positions.insert(mesh.positions.end(),
                            {radius * std::cos(phi), radius * std::sin(phi), k * length});
    }
  }
  mesh.positions.insert(mesh.positions.end(), {0.0f, 0.0f, length + radius});
  const auto tip = static_cast<std::uint32_t>(2 * segments);
  auto& f = mesh.triangles;
  for (int j = 0; j < segments; ++j) {
    const auto a = static_cast<std::uint32_t>(j);
    const auto b = static_cast<std::uint32_t>((j + 1) % segments);
    const auto c = b + segments, d = a + segments;
    f.insert(f.end(), {a, b, c, a, c, d, d, c, tip});
  }
  mesh.material.assign(mesh.positions.size() / 3, SurfaceMaterial::Tool);
}

}  // namespace

RenderSnapshot makeDemoSnapshot(const DemoSceneOptions& options) {
  RenderSnapshot s;
  addCavity(options, s.tissue);

  Camera& c = s.camera;
  c.tip = {0.0f, 2.0f, -8.0f};
  c.axis = {0.0f, 0.0f, 1.0f};
  c.up = {0.0f, 1.0f, 0.0f};
  c.lens_deg = 30.0f;
  c.fov_deg = 90.0f;
  c.near_mm = 0.5f;
  c.far_mm = 200.0f;

  if (options.with_tool) {
    addTool(s.tool);
    // Out of the working channel below the optic, entering the circle from below and
    // reaching towards the middle of the view (the tip is 13 mm along the view line).
    const float px = 1.5f, py = c.tip[1] - 3.5f, pz = c.tip[2] + 0.5f;
    float zx = 0.0f - px, zy = (c.tip[1] - 6.5f) - py, zz = (c.tip[2] + 11.26f) - pz;
    const float n = std::sqrt(zx * zx + zy * zy + zz * zz);
    zx /= n, zy /= n, zz /= n;
    // Body frame: z along the rod, x to the side, y = z cross x.
    const float xx = zz, xz = -zx;  // (zz, 0, -zx): horizontal, orthogonal to z
    const float xn = std::sqrt(xx * xx + xz * xz);
    const std::array<float, 3> bx{xx / xn, 0.0f, xz / xn};
    const std::array<float, 3> by{zy * bx[2] - zz * bx[1], zz * bx[0] - zx * bx[2],
                                  zx * bx[1] - zy * bx[0]};
    s.tool_pose.rotation = {bx[0], bx[1], bx[2], by[0], by[1], by[2], zx, zy, zz};
    s.tool_pose.position = {px, py, pz};
    s.tool_visible = true;
  }
  return s;
}

}  // namespace hysim::render
