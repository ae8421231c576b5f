#pragma once
// What the renderer gets: plain arrays, never simulator internals. The engine fills a
// RenderSnapshot every k steps; the renderer draws it (off-screen EGL or an SDL2 window).
#include <array>
#include <cstdint>
#include <vector>

namespace hysim::render {

// Material of a surface vertex; the renderer picks the colour.
enum class SurfaceMaterial : std::uint8_t {
  Endometrium = 0,  // healthy cavity lining / myometrium: pink-red
  Myoma = 1,        // fibroid: paler, whitish pink
  Cut = 2,          // fresh cut surface (later issues)
  Tool = 3,         // metal
};

// One triangle surface. Normals are computed by the renderer from positions and
// triangles (smooth, area-weighted), so they follow the deformation.
struct SurfaceMesh {
  std::vector<float> positions;            // #V*3, mm, world frame
  std::vector<std::uint32_t> triangles;    // #F*3, counter-clockwise seen from outside
  std::vector<SurfaceMaterial> material;   // #V
};

// A rigid pose: position (mm) and a rotation matrix, column-major 3x3 (columns are the
// body's x, y, z axes in world coordinates).
struct Pose {
  std::array<float, 3> position{0, 0, 0};
  std::array<float, 9> rotation{1, 0, 0, 0, 1, 0, 0, 0, 1};
};

// Hysteroscope camera. The scope's tip is at `tip`, its shaft axis is `axis` (unit),
// `up` is the scope's reference direction (unit, orthogonal to axis). The lens looks
// `lens_deg` (0, 12 or 30 degrees in practice) away from the axis, tilted towards -up
// (the usual fore-oblique lens, light post up). The light sits at the tip.
struct Camera {
  std::array<float, 3> tip{0, 0, 0};
  std::array<float, 3> axis{0, 0, 1};
  std::array<float, 3> up{0, 1, 0};
  float lens_deg = 30.0f;
  float fov_deg = 90.0f;          // full field of view of the circular image
  float near_mm = 0.5f;
  float far_mm = 200.0f;
  float light_intensity = 1.0f;   // tip light, 1 = nominal; falls off with distance squared
};

// A free piece of tissue (a chip) moving as a rigid body: its surface in its body frame
// and its pose.
struct Chip {
  SurfaceMesh surface;  // body frame
  Pose pose;            // body -> world
};

struct RenderSnapshot {
  SurfaceMesh tissue;              // deformable tissue surface (and static cavity, if any)
  SurfaceMesh tool;                // tool surface in the tool's body frame
  Pose tool_pose;                  // body -> world
  bool tool_visible = false;
  Camera camera;
  std::vector<Chip> chips;         // simulated chips (empty when chips are removed)
  int chips_version = -1;          // changes when chips are added or removed
  std::uint64_t step = 0;          // simulation step this snapshot was taken at
  int topology_version = -1;       // changes when the tissue's triangles change (a cut)
  double time_s = 0.0;
};

}  // namespace hysim::render
