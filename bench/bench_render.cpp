// Headless frame time: 640x480 of the procedural cavity + myoma (~10k triangles) on
// whatever EGL offers (Mesa llvmpipe in CI). The budget is 16 ms median (DESIGN.md).
// Each frame includes what a real frame pays: normals recomputed, vertex buffers
// refilled, draw, MSAA resolve and read-back into an Image.
//   ./bench_render --benchmark_repetitions=20
#include <benchmark/benchmark.h>

#include <cmath>

#include "hysim/render/demo_scene.hpp"
#include "hysim/render/renderer.hpp"

namespace hr = hysim::render;

namespace {

void renderFrames(benchmark::State& state, int width, int height, int samples, bool tool) {
  hr::RendererOptions options;
  options.samples = samples;
  auto renderer = hr::OffscreenRenderer::create(width, height, options);
  if (!renderer.ok()) {
    state.SkipWithError(renderer.error().c_str());
    return;
  }
  hr::RenderSnapshot snapshot = hr::makeDemoSnapshot({.target_triangles = 10000, .with_tool = tool});
  const std::vector<float> rest = snapshot.tissue.positions;
  hr::Image image;
  (*renderer)->render(snapshot, image);  // warm-up: shader JIT, buffer allocation
  int frame = 0;
  for (auto _ : state) {
    // A breathing deformation, so every frame really has new positions to upload.
    const float s = 1.0f + 0.02f * std::sin(0.1f * static_cast<float>(++frame));
    for (std::size_t i = 0; i < rest.size(); ++i) snapshot.tissue.positions[i] = s * rest[i];
    (*renderer)->render(snapshot, image);
    benchmark::DoNotOptimize(image.rgba.data());
  }
  state.counters["triangles"] = static_cast<double>((*renderer)->renderer().lastTriangleCount());
  state.counters["msaa"] = (*renderer)->renderer().samples();
  state.SetLabel((*renderer)->context().description());
}

void BM_Frame640x480(benchmark::State& state) {
  renderFrames(state, 640, 480, static_cast<int>(state.range(0)), true);
}
// Arg = MSAA samples (0 = none, the default; 4 = 4x, about 3x slower on llvmpipe).
BENCHMARK(BM_Frame640x480)
    ->Arg(0)
    ->Arg(4)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond)
    ->MinTime(0.5)
    ->Repetitions(10)
    ->ReportAggregatesOnly(true);

// The fixed part of a frame: clear, (empty) draw, read-back and row flip.
void BM_EmptyFrame640x480(benchmark::State& state) {
  auto renderer = hr::OffscreenRenderer::create(640, 480, {.samples = 0});
  if (!renderer.ok()) {
    state.SkipWithError(renderer.error().c_str());
    return;
  }
  const hr::RenderSnapshot empty;
  hr::Image image;
  (*renderer)->render(empty, image);
  for (auto _ : state) {
    (*renderer)->render(empty, image);
    benchmark::DoNotOptimize(image.rgba.data());
  }
}
BENCHMARK(BM_EmptyFrame640x480)->UseRealTime()->Unit(benchmark::kMillisecond)->Repetitions(5)
    ->ReportAggregatesOnly(true);

// The CPU part of a frame: smooth normals of the ~10k-triangle surface.
void BM_VertexNormals10k(benchmark::State& state) {
  const hr::RenderSnapshot snapshot = hr::makeDemoSnapshot({.target_triangles = 10000});
  std::vector<float> normals;
  for (auto _ : state) {
    hr::computeVertexNormals(snapshot.tissue.positions, snapshot.tissue.triangles, normals);
    benchmark::DoNotOptimize(normals.data());
  }
}
BENCHMARK(BM_VertexNormals10k)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
