// Loop vs. tissue collision (FCL) on the shaving scene's mesh: refit of the tissue hierarchy
// (every step while the electrode is active), the swept wire's update, and the sweep query.
// The hierarchy holds either the boundary faces (what the step uses) or every tet face
// (interior ones too), for comparison.
#include <benchmark/benchmark.h>

#include "hysim/cutting/mesh_io.hpp"
#include "hysim/engine/collision.hpp"
#include "hysim/engine/tool.hpp"

namespace {

using namespace hysim;

enum class Faces { Boundary, All };
enum class Where { Crossing, Inside, Free };  // the loop's sweep vs. the tissue surface

struct Fixture {
  cutting::TetMesh mesh;
  sim::NodeVectors x;
  engine::TissueCollision collision;
  engine::SweptWire sweep;
  engine::LoopGeometry loop;
  engine::WirePoints previous, current;
  std::string error;

  Fixture(Faces faces, Where where, double margin_mm) {
    auto m = cutting::readTetMesh(std::string(HYSIM_SOURCE_DIR) + "/assets/uterus_myoma.msh");
    if (!m.ok()) {
      error = m.error();
      return;
    }
    mesh = std::move(*m);
    x = mesh.X;
    const cutting::Tris f = faces == Faces::All ? engine::allTetFaces(mesh) : cutting::boundaryFaces(mesh);
    if (!collision.build(f, x, margin_mm).ok()) error = "build failed";
    // The loop drawn back through the myoma as in a shaving pass (17 mm/s, 1 ms steps).
    haptics::ToolPose pose;
    pose.tip = {0, 1.78, -16.10};
    pose.rotation = haptics::frameFromAxisUp({0, 0.1111, 0.9938}, {0, 1, 0});
    pose.extension_mm = 8.0;
    if (where == Where::Inside) pose.tip.y() -= 5.0;  // the whole loop below the myoma's surface
    if (where == Where::Free) pose.tip.y() += 6.0;    // the loop in the fluid above it
    engine::loopPoints(loop, pose, previous);
    pose.extension_mm -= 0.017;
    engine::loopPoints(loop, pose, current);
    sweep.reset(static_cast<int>(current.rows()));
    sweep.update(previous, current);
  }
};

constexpr double kMargin = 0.5;  // mm, as in the simulation

void BM_Refit(benchmark::State& bm, Faces faces) {
  Fixture f(faces, Where::Crossing, kMargin);
  if (!f.error.empty()) return bm.SkipWithError(f.error.c_str());
  for (auto _ : bm) {
    f.x(0, 0) += 1e-9;  // a "deformation"
    f.collision.refit(f.x);
  }
  bm.counters["faces"] = f.collision.numFaces();
  bm.counters["vertices"] = f.collision.numVertices();
}

// Vertices moved, boxes still valid (no vertex left its margin): what most steps cost.
void BM_UpdateWithinMargin(benchmark::State& bm, Faces faces) {
  Fixture f(faces, Where::Crossing, kMargin);
  if (!f.error.empty()) return bm.SkipWithError(f.error.c_str());
  for (auto _ : bm) {
    f.x(0, 0) += 1e-9;
    benchmark::DoNotOptimize(f.collision.update(f.x));
  }
  bm.counters["refits"] = static_cast<double>(f.collision.numRefits());
}

void BM_SweptWireUpdate(benchmark::State& bm) {
  Fixture f(Faces::Boundary, Where::Crossing, kMargin);
  if (!f.error.empty()) return bm.SkipWithError(f.error.c_str());
  for (auto _ : bm) {
    f.previous(0, 0) += 1e-9;
    f.sweep.update(f.previous, f.current);
  }
  bm.counters["triangles"] = f.sweep.numTriangles();
}

void BM_Query(benchmark::State& bm, Faces faces, Where where, double margin_mm) {
  Fixture f(faces, where, margin_mm);
  if (!f.error.empty()) return bm.SkipWithError(f.error.c_str());
  bool touching = false;
  for (auto _ : bm) {
    touching = f.collision.touches(f.sweep, f.loop.wire_radius_mm);
    benchmark::DoNotOptimize(touching);
  }
  bm.counters["faces"] = f.collision.numFaces();
  bm.counters["touching"] = touching;
}

// What the step does per active step: refit, swept-wire update, query (worst case: the
// boxes refitted every step).
void BM_ActiveStep(benchmark::State& bm, Faces faces) {
  Fixture f(faces, Where::Crossing, kMargin);
  if (!f.error.empty()) return bm.SkipWithError(f.error.c_str());
  bool touching = false;
  for (auto _ : bm) {
    f.x(0, 0) += 1e-9;
    f.collision.refit(f.x);
    f.sweep.update(f.previous, f.current);
    touching = f.collision.touches(f.sweep, f.loop.wire_radius_mm);
    benchmark::DoNotOptimize(touching);
  }
  bm.counters["touching"] = touching;
}

#define HYSIM_BENCH(...) \
  BENCHMARK_CAPTURE(__VA_ARGS__)->Unit(benchmark::kMicrosecond)->Repetitions(5)->ReportAggregatesOnly(true)

HYSIM_BENCH(BM_Refit, boundary, Faces::Boundary);
HYSIM_BENCH(BM_Refit, all_faces, Faces::All);
HYSIM_BENCH(BM_UpdateWithinMargin, boundary, Faces::Boundary);
BENCHMARK(BM_SweptWireUpdate)->Unit(benchmark::kMicrosecond)->Repetitions(5)->ReportAggregatesOnly(true);
HYSIM_BENCH(BM_Query, boundary_crossing, Faces::Boundary, Where::Crossing, kMargin);
HYSIM_BENCH(BM_Query, boundary_inside, Faces::Boundary, Where::Inside, kMargin);
HYSIM_BENCH(BM_Query, boundary_free, Faces::Boundary, Where::Free, kMargin);
HYSIM_BENCH(BM_Query, boundary_crossing_exact_boxes, Faces::Boundary, Where::Crossing, 0.0);
HYSIM_BENCH(BM_Query, boundary_inside_exact_boxes, Faces::Boundary, Where::Inside, 0.0);
HYSIM_BENCH(BM_Query, all_faces_crossing, Faces::All, Where::Crossing, kMargin);
HYSIM_BENCH(BM_Query, all_faces_inside, Faces::All, Where::Inside, kMargin);
HYSIM_BENCH(BM_ActiveStep, boundary, Faces::Boundary);
HYSIM_BENCH(BM_ActiveStep, all_faces, Faces::All);

}  // namespace

BENCHMARK_MAIN();
