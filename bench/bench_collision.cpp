// Loop vs. tissue collision on the default scene's mesh: refit of the FCL hierarchy (every
// step) and the wire query.
#include <benchmark/benchmark.h>

#include "hysim/cutting/mesh_io.hpp"
#include "hysim/engine/collision.hpp"
#include "hysim/engine/tool.hpp"

namespace {

using namespace hysim;

void run(benchmark::State& bm, bool refit, bool query) {
  auto mesh = cutting::readTetMesh(std::string(HYSIM_SOURCE_DIR) + "/assets/uterus_myoma.msh");
  if (!mesh.ok()) {
    bm.SkipWithError(mesh.error().c_str());
    return;
  }
  sim::NodeVectors x = mesh->X;
  engine::TissueCollision collision;
  if (!collision.build(*mesh, x).ok()) {
    bm.SkipWithError("build failed");
    return;
  }
  engine::LoopGeometry loop;
  haptics::ToolPose pose;
  pose.tip = {0, 3, -12};  // the loop on the myoma
  pose.extension_mm = 6;
  Eigen::Matrix<double, Eigen::Dynamic, 3> wire;
  engine::loopPoints(loop, pose, wire);
  bool touching = false;
  for (auto _ : bm) {
    x(0, 0) += 1e-9;  // a "deformation"
    if (refit) collision.refit(x);
    if (query) touching = collision.touches(wire, loop.wire_radius_mm);
    benchmark::DoNotOptimize(touching);
  }
  bm.counters["faces"] = collision.numFaces();
  bm.counters["touching"] = touching;
}
void BM_Refit(benchmark::State& bm) { run(bm, true, false); }
void BM_Query(benchmark::State& bm) { run(bm, false, true); }
BENCHMARK(BM_Refit)->Unit(benchmark::kMicrosecond)->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_Query)->Unit(benchmark::kMicrosecond)->Repetitions(5)->ReportAggregatesOnly(true);

}  // namespace

BENCHMARK_MAIN();
