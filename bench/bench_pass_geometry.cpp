// The engine's per-pass geometry work on dumped pass meshes (hysim run --dump-cuts DIR):
// boundary faces, face matching, the FCL hierarchy build, the tet locator build, pieces.
// HYSIM_REPLAY_DIR names the folder (default: skipped). Rest positions stand in for the
// deformed ones.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/mesh_io.hpp"
#include "hysim/engine/collision.hpp"
#include "hysim/engine/mesh_faces.hpp"
#include "hysim/engine/tet_locator.hpp"
#include "replay_passes.hpp"

namespace {
using namespace hysim;

std::vector<cutting::TetMesh>& meshes() {
  static std::vector<cutting::TetMesh> all;
  static bool loaded = false;
  if (loaded) return all;
  loaded = true;
  const char* dir = std::getenv("HYSIM_REPLAY_DIR");
  if (dir == nullptr) return all;
  for (int p = 1; p < 200; p += 1) {
    char name[64];
    std::snprintf(name, sizeof(name), "/pass_%03d_mesh.msh", p);
    auto m = cutting::readTetMesh(std::string(dir) + name);
    if (!m.ok()) break;
    all.push_back(std::move(*m));
  }
  return all;
}

void BM_CollisionBuild(benchmark::State& state) {
  auto& ms = meshes();
  if (ms.empty()) return state.SkipWithError("no HYSIM_REPLAY_DIR");
  std::vector<cutting::Tris> faces;
  for (auto& m : ms) faces.push_back(cutting::boundaryFaces(m));
  engine::TissueCollision c;
  state.counters["meshes"] = static_cast<double>(ms.size());
  for (auto _ : state)
    for (size_t i = 0; i < ms.size(); ++i) benchmark::DoNotOptimize(c.build(faces[i], ms[i].X, 0.5).ok());
}
BENCHMARK(BM_CollisionBuild)->Unit(benchmark::kMillisecond);

void BM_LocatorBuild(benchmark::State& state) {
  auto& ms = meshes();
  if (ms.empty()) return state.SkipWithError("no HYSIM_REPLAY_DIR");
  engine::TetLocator l;
  for (auto _ : state)
    for (auto& m : ms) l.build(m, m.X);
}
BENCHMARK(BM_LocatorBuild)->Unit(benchmark::kMillisecond);

void BM_MatchPieces(benchmark::State& state) {
  auto& ms = meshes();
  if (ms.empty()) return state.SkipWithError("no HYSIM_REPLAY_DIR");
  std::vector<int> next;
  for (auto _ : state)
    for (auto& m : ms) {
      engine::matchFaces(m, next);
      std::vector<std::uint8_t> anchored(m.numNodes(), 0);
      anchored[0] = 1;
      benchmark::DoNotOptimize(engine::tetPieces(m, next, anchored).count);
    }
}
BENCHMARK(BM_MatchPieces)->Unit(benchmark::kMillisecond);

// The map's point location: each dumped pass's sweep points (rest shape) in its mesh, the
// locator built at rest, queried with a displacement bound of range(0) / 10 mm.
void BM_Locate(benchmark::State& state) {
  struct Pass {
    cutting::TetMesh mesh;
    cutting::Positions points;
    sim::NodeVectors x;
    engine::TetLocator locator;
  };
  static std::vector<Pass> passes = [] {
    std::vector<Pass> out;
    cutting::TetMesh mesh;
    cutting::TriMesh surface;
    for (int i = 1; bench::readDumpedPass(i, mesh, surface); ++i) {
      Pass p;
      p.mesh = std::move(mesh);
      p.points = surface.X;
      p.x = p.mesh.X;
      p.locator.build(p.mesh, p.x);
      out.push_back(std::move(p));
    }
    return out;
  }();
  if (passes.empty()) return state.SkipWithError("no HYSIM_REPLAY_DIR");
  const double moved = static_cast<double>(state.range(0)) / 10.0;
  long inside = 0, total = 0, sum = 0;
  for (auto _ : state) {
    inside = total = sum = 0;
    for (const Pass& p : passes)
      for (Eigen::Index i = 0; i < p.points.rows(); ++i) {
        const int t = p.locator.locate(p.mesh, p.x, p.points.row(i).transpose(), moved);
        inside += t >= 0;
        sum += t;
        ++total;
      }
  }
  state.counters["inside"] = static_cast<double>(inside);
  state.counters["points"] = static_cast<double>(total);
  state.counters["tet_sum"] = static_cast<double>(sum);
}
BENCHMARK(BM_Locate)->Arg(0)->Arg(5)->Arg(10)->Unit(benchmark::kMillisecond);

// Each dumped pass's hybrid cut: the mesh before and after, the change, face neighbours
// before, anchors after (the default scene's: outside the 25 x 20 x 33 mm ellipsoid).
struct CutPass {
  cutting::TetMesh before, after;
  cutting::TopologyChange change;
  std::vector<int> next_before;
  std::vector<std::uint8_t> anchored;
};
const std::vector<CutPass>& cutPasses() {
  static std::vector<CutPass> passes = [] {
    std::vector<CutPass> out;
    cutting::TetMesh mesh;
    cutting::TriMesh surface;
    for (int i = 1; bench::readDumpedPass(i, mesh, surface); ++i) {
      auto s = bench::dumpedSurface(surface);
      if (!s.ok()) break;
      cutting::Cut3DOptions o;
      o.method = cutting::CutMethod::Hybrid;
      auto r = cutting::cut3d(mesh, *s, o);
      if (!r.ok()) break;
      CutPass p;
      p.before = std::move(mesh);
      p.after = std::move(r->mesh);
      p.change = std::move(r->change);
      engine::matchFaces(p.before, p.next_before);
      p.anchored.assign(static_cast<size_t>(p.after.numNodes()), 0);
      for (int n = 0; n < p.after.numNodes(); ++n) {
        const Eigen::Vector3d x = p.after.X.row(n).transpose();
        p.anchored[n] = (x.array() / Eigen::Array3d(25, 20, 33)).matrix().squaredNorm() > 1.0;
      }
      out.push_back(std::move(p));
    }
    return out;
  }();
  return passes;
}

// The collision hierarchy of each pass's cut mesh, built after the one of the mesh before:
// keeping the chunks the cut did not change (range(0) = 1) or from scratch (0). Manual time:
// the second build only.
void BM_CollisionAfterCut(benchmark::State& state) {
  const std::vector<CutPass>& passes = cutPasses();
  if (passes.empty()) return state.SkipWithError("no HYSIM_REPLAY_DIR");
  const bool keep = state.range(0) != 0;
  std::vector<cutting::Tris> before, after;
  std::vector<std::vector<int>> renumber;
  for (const CutPass& p : passes) {
    before.push_back(cutting::boundaryFaces(p.before));
    after.push_back(cutting::boundaryFaces(p.after));
    renumber.emplace_back(p.change.node_old_to_new.begin(), p.change.node_old_to_new.end());
  }
  long built = 0, kept = 0;
  for (auto _ : state) {
    double seconds = 0.0;
    built = kept = 0;
    for (size_t i = 0; i < passes.size(); ++i) {
      engine::TissueCollision c;
      if (!c.build(before[i], passes[i].before.X, 0.5, &passes[i].before.X).ok()) return state.SkipWithError("build");
      const long b0 = c.numChunksBuilt(), k0 = c.numChunksKept();
      const auto t0 = std::chrono::steady_clock::now();
      const bool ok = c.build(after[i], passes[i].after.X, 0.5, &passes[i].after.X, keep ? &renumber[i] : nullptr).ok();
      seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (!ok) return state.SkipWithError("build after");
      built += c.numChunksBuilt() - b0;
      kept += c.numChunksKept() - k0;
    }
    state.SetIterationTime(seconds);
  }
  state.counters["chunks_built"] = static_cast<double>(built) / static_cast<double>(passes.size());
  state.counters["chunks_kept"] = static_cast<double>(kept) / static_cast<double>(passes.size());
}
BENCHMARK(BM_CollisionAfterCut)->Arg(0)->Arg(1)->UseManualTime()->Unit(benchmark::kMillisecond);

// updateFaces + tetPieces after each dumped pass's hybrid cut (as Simulation::finishPass).
void BM_FacesPieces(benchmark::State& state) {
  const std::vector<CutPass>& passes = cutPasses();
  if (passes.empty()) return state.SkipWithError("no HYSIM_REPLAY_DIR");
  std::vector<int> next;
  int chips = 0;
  for (auto _ : state) {
    chips = 0;
    for (const CutPass& p : passes) {
      if (!engine::updateFaces(p.before, p.next_before, p.after, p.change.node_old_to_new,
                               p.change.element_old_to_new, next)) {
        return state.SkipWithError("updateFaces failed");
      }
      const engine::Pieces c = engine::tetPieces(p.after, next, p.anchored);
      for (int k = 0; k < c.count; ++k) chips += c.free[k];
    }
  }
  state.counters["chips"] = chips;
  state.counters["passes"] = static_cast<double>(passes.size());
  int identity = 0;
  for (const CutPass& p : passes) {
    bool same = true;
    for (size_t i = 0; i < p.change.node_old_to_new.size() && same; ++i) same = p.change.node_old_to_new[i] == static_cast<int>(i);
    for (size_t t = 0; t < p.change.element_old_to_new.size() && same; ++t)
      same = p.change.element_old_to_new[t] < 0 || p.change.element_old_to_new[t] == static_cast<int>(t);
    identity += same;
  }
  state.counters["identity_maps"] = identity;
}
BENCHMARK(BM_FacesPieces)->Unit(benchmark::kMillisecond);

// updateFaces alone after each dumped pass's hybrid cut (Simulation::finishPass's first step
// after the cut), with its FaceChange; manual time per pass, counter ms_median.
void BM_UpdateFaces(benchmark::State& state) {
  const std::vector<CutPass>& passes = cutPasses();
  if (passes.empty()) return state.SkipWithError("no HYSIM_REPLAY_DIR");
  std::vector<int> next;
  engine::FaceChange change;
  std::vector<double> ms;
  for (auto _ : state) {
    double seconds = 0.0;
    for (const CutPass& p : passes) {
      const auto t0 = std::chrono::steady_clock::now();
      const bool ok = engine::updateFaces(p.before, p.next_before, p.after, p.change.node_old_to_new,
                                          p.change.element_old_to_new, next, &change);
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (!ok) return state.SkipWithError("updateFaces failed");
      seconds += s;
      ms.push_back(1e3 * s);
    }
    state.SetIterationTime(seconds);
  }
  std::sort(ms.begin(), ms.end());
  state.counters["ms_median"] = ms[ms.size() / 2];
}
BENCHMARK(BM_UpdateFaces)->UseManualTime()->Unit(benchmark::kMillisecond);

}  // namespace
BENCHMARK_MAIN();
