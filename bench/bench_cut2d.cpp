// 2D cutting: the Table-1 cuts (hysim tables --table 1) per method, and the hybrid method's
// mesh optimisation alone (its time is in the counter `optimize_ms`, median over the
// repetitions). Run from anywhere: meshes are read from tests/data/cutting.
#include <benchmark/benchmark.h>

#include <string>

#include "hysim/cutting/cut2d.hpp"
#include "hysim/cutting/mesh_io.hpp"

namespace {

using hysim::cutting::CutMethod;
using hysim::cutting::TriMesh;

const TriMesh& table1Mesh(int which) {
  static TriMesh meshes[2];
  static bool loaded = false;
  if (!loaded) {
    for (int i = 0; i < 2; ++i) {
      auto m = hysim::cutting::readTriMesh(std::string(HYSIM_SOURCE_DIR) + "/tests/data/cutting/table1_mesh" +
                                           std::to_string(i + 1) + ".msh");
      if (m.ok()) meshes[i] = *m;
    }
    loaded = true;
  }
  return meshes[which - 1];
}

struct Case {
  int mesh;
  Eigen::Vector2d a, b;
};
// The cuts of `hysim tables --table 1` (tools/tables.cpp): 1a, 1b, 2a, 2b.
const Case kCases[4] = {{1, {-5, 27}, {105, 41}}, {1, {-5, 60}, {105, 8}}, {2, {-25, -6}, {25, 3}},
                        {2, {-18, -18}, {20, 17}}};

void BM_Cut2D(benchmark::State& state) {
  const Case& c = kCases[state.range(0)];
  hysim::cutting::Cut2DOptions o;
  o.method = static_cast<CutMethod>(state.range(1));
  const TriMesh& mesh = table1Mesh(c.mesh);
  if (mesh.numTris() == 0) {
    state.SkipWithError("cannot read tests/data/cutting/table1_mesh*.msh");
    return;
  }
  double optMs = 0;
  int elements = 0;
  for (auto _ : state) {
    auto r = hysim::cutting::cut2d(mesh, c.a, c.b, o);
    benchmark::DoNotOptimize(r);
    optMs += r->report.optimize_ms;
    elements = r->mesh.numTris();
  }
  state.counters["optimize_ms"] = optMs / static_cast<double>(state.iterations());
  state.counters["elements"] = elements;
  state.SetLabel(std::string("cut ") + "12"[c.mesh - 1] + "ab"[state.range(0) % 2] + " " +
                 hysim::cutting::cutMethodName(o.method));
}
BENCHMARK(BM_Cut2D)
    ->ArgsProduct({{0, 1, 2, 3},
                   {static_cast<int>(CutMethod::Hybrid), static_cast<int>(CutMethod::Standard),
                    static_cast<int>(CutMethod::Snap), static_cast<int>(CutMethod::Delete)}})
    ->Unit(benchmark::kMicrosecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);

}  // namespace

BENCHMARK_MAIN();
