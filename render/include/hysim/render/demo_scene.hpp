#pragma once
// A procedural hysteroscopy scene for tests, benchmarks and "does rendering work" checks:
// the inside of an ellipsoidal cavity with a spherical myoma bulging in from the wall,
// seen by a 30-degree hysteroscope, optionally with a loop-electrode-like tool.
#include "hysim/render/snapshot.hpp"

namespace hysim::render {

struct DemoSceneOptions {
  int target_triangles = 10000;  // cavity surface triangles (approximately)
  bool with_tool = true;
  float myoma_radius_mm = 8.0f;
};

RenderSnapshot makeDemoSnapshot(const DemoSceneOptions& options = {});

}  // namespace hysim::render
