// Loop vs. tissue collision (FCL) on the shaving scene's mesh: refit of the tissue hierarchy
// (every step while the electrode is active), the swept wire's update, and the sweep query.
// The hierarchy holds either the boundary faces (what the step uses) or every tet face
// (interior ones too), for comparison.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <vector>

#include "hysim/cutting/mesh_io.hpp"
#include "hysim/engine/collision.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/simulation.hpp"
#include "hysim/engine/tet_locator.hpp"
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

// Real active steps: the shaving scene's first pass (pedal down at 1.35 s, the loop enters the
// myoma at ~1.68 s), 300 steps from the entry recorded (tissue positions, wire) and replayed,
// so local refits happen as often as the tissue really moves. Reported per step; median, p99
// and max over all replayed steps as counters.
struct PassRecording {
  cutting::TetMesh mesh;
  std::vector<sim::NodeVectors> x;
  std::vector<engine::WirePoints> wire;
  engine::LoopGeometry loop;
  int in_tissue = 0;  // steps the simulation saw the loop in the tissue
  std::string error;
};

const PassRecording& passRecording() {
  static const PassRecording rec = [] {
    PassRecording r;
    auto scene = engine::loadScene(std::string(HYSIM_SOURCE_DIR) + "/scenes/shaving.yaml");
    if (!scene.ok()) {
      r.error = scene.error();
      return r;
    }
    auto sim = engine::Simulation::create(*scene);
    if (!sim.ok()) {
      r.error = sim.error();
      return r;
    }
    while (!(*sim)->loopInTissue() && (*sim)->state().time < 2.0) (*sim)->step();
    r.mesh = (*sim)->mesh();
    r.loop = (*sim)->loop();
    for (int i = 0; i < 300; ++i) {
      (*sim)->step();
      r.x.push_back((*sim)->state().x);
      r.wire.emplace_back();
      engine::loopPoints(r.loop, (*sim)->toolPose(), r.wire.back());
      r.in_tissue += (*sim)->loopInTissue() ? 1 : 0;
    }
    if (!(*sim)->passes().empty()) r.error = "the pass ended inside the recording";
    return r;
  }();
  return rec;
}

// The step's positions are hot in the cache (sim::step just wrote them): each recorded step is
// copied into one working buffer, untimed, before the timed work reads it.
template <typename StartFn, typename StepFn>
void replay(benchmark::State& bm, const PassRecording& r, sim::NodeVectors& x, StartFn&& startFn, StepFn&& stepFn) {
  using Clock = std::chrono::steady_clock;
  std::vector<double> us(r.x.size());
  std::vector<double> all;
  for (auto _ : bm) {
    startFn();  // untimed: back to the recording's first step
    double total = 0.0;
    for (size_t k = 1; k < r.x.size(); ++k) {
      x = r.x[k];
      const auto a = Clock::now();
      stepFn(k);
      us[k] = std::chrono::duration<double, std::micro>(Clock::now() - a).count();
      total += us[k];
    }
    bm.SetIterationTime(1e-6 * total / static_cast<double>(r.x.size() - 1));
    all.insert(all.end(), us.begin() + 1, us.end());
  }
  std::sort(all.begin(), all.end());
  if (!all.empty()) {
    bm.counters["median_us"] = all[all.size() / 2];
    bm.counters["p99_us"] = all[all.size() * 99 / 100];
    bm.counters["max_us"] = all.back();
  }
}

void BM_ShavingPassSweep(benchmark::State& bm) {
  const PassRecording& r = passRecording();
  if (!r.error.empty()) return bm.SkipWithError(r.error.c_str());
  engine::TissueCollision collision;
  if (!collision.build(cutting::boundaryFaces(r.mesh), r.x[0], kMargin).ok()) return bm.SkipWithError("build");
  engine::SweptWire sweep;
  sweep.reset(static_cast<int>(r.wire[0].rows()));
  const long local0 = collision.numLocalRefits();
  long touching = 0, steps = 0;
  // As in the step: refit when the electrode becomes active, then follow the vertices.
  sim::NodeVectors x;
  replay(bm, r, x, [&] { collision.refit(r.x[0]); }, [&](size_t k) {
    collision.update(x);
    sweep.update(r.wire[k - 1], r.wire[k]);
    touching += collision.touches(sweep, r.loop.wire_radius_mm) ? 1 : 0;
    ++steps;
  });
  bm.counters["local_refits_per_step"] = static_cast<double>(collision.numLocalRefits() - local0) / static_cast<double>(steps);
  bm.counters["touching_per_step"] = static_cast<double>(touching) / static_cast<double>(steps);
  bm.counters["sim_in_tissue"] = r.in_tissue;
}

// The test the step used before: TetLocator point location of the wire's 17 points (first
// hit wins), with the O(#N) displacement check that decides a grid rebuild.
void BM_ShavingPassPointsInTets(benchmark::State& bm) {
  const PassRecording& r = passRecording();
  if (!r.error.empty()) return bm.SkipWithError(r.error.c_str());
  engine::TetLocator locator;
  long inside = 0, steps = 0;
  sim::NodeVectors x;
  replay(bm, r, x, [&] { locator.build(r.mesh, r.x[0]); }, [&](size_t k) {
    if (locator.maxDisplacement(x) > locator.margin()) locator.build(r.mesh, x);
    for (Eigen::Index i = 0; i < r.wire[k].rows(); ++i) {
      if (locator.locate(r.mesh, x, r.wire[k].row(i).transpose()) >= 0) {
        ++inside;
        break;
      }
    }
    ++steps;
  });
  bm.counters["inside_per_step"] = static_cast<double>(inside) / static_cast<double>(steps);
}

BENCHMARK(BM_ShavingPassSweep)->UseManualTime()->Unit(benchmark::kMicrosecond)->Iterations(20)->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_ShavingPassPointsInTets)->UseManualTime()->Unit(benchmark::kMicrosecond)->Iterations(20)->Repetitions(5)->ReportAggregatesOnly(true);

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
