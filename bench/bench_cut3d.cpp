// 3D cutting: one plane cut through the middle of a tet mesh plus the tissue update, the
// time the acceptance of issue 4 bounds ("time per hybrid cut including optimisation and
// tissue update: <= 5 ms on a 20,000-tet mesh"). Meshes: 0 = assets/uterus_myoma.msh (12,139
// tets), 1 = tests/data/cutting/uterus_20k.msh (20,971 tets, the same geometry meshed finer,
// see tests/data/cutting/README.md). Each iteration cuts the same input mesh with one of four
// fixed planes through the bounding-box centre and updates the mass-spring model and state
// (sim::updateModelAfterCut3D, the simulator's incremental update, or sim::updateModel3D, a
// whole rebuild; then sim::remapState3D).
// The benchmark's time is the whole (cut + optimisation + TopologyChange + update); the
// counters split it: cut_ms (cut3d, incl. optimisation), optimize_ms, update_ms (wall-clock
// means), update_cpu_med_ms (BM_Cut3DUpdate: the update's median thread CPU time, steadier
// than the wall clock on a loaded machine). Medians over the repetitions (the `_median` rows). Run from anywhere:
//   ./build/bench/bench_cut3d --benchmark_filter='BM_Cut3DUpdate/./././1'   (incremental)
// BM_Cut3DReplay: recorded shaving passes (HYSIM_REPLAY_DIR, see below).
// BM_Cut3DSurface: the same meshes cut by a curved swept strip (the shaving passes' surfaces):
//   ./build/bench/bench_cut3d --benchmark_filter='BM_Cut3DSurface'
// BM_CutSurfaceBuild: building the recorded passes' surfaces, strip tree against sorted tree.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/mesh_io.hpp"
#include "hysim/cutting/mesh_stats.hpp"
#include "hysim/sim/model.hpp"
#include "hysim/sim/tissue_update3d.hpp"
#include "replay_passes.hpp"

namespace {

using hysim::cutting::CutMethod;
using hysim::cutting::TetMesh;
using Vec3 = Eigen::Vector3d;

struct Prepared {
  TetMesh mesh;
  hysim::sim::Model model;
  hysim::sim::State state;
  std::string name;
  bool ok = false;
};

// The scene's materials (scenes/default.yaml): 1 = myometrium, 2 = myoma. Nodes outside the
// ellipsoid (25, 20, 33) are anchored, as in the default scene.
Prepared prepare(const std::string& path, const std::string& name) {
  Prepared p;
  p.name = name;
  auto m = hysim::cutting::readTetMesh(path);
  if (!m.ok()) return p;
  p.mesh = std::move(*m);
  hysim::sim::Material wall, myoma;
  wall.label = 1;
  wall.young_modulus_pa = 60e3;
  myoma.label = 2;
  myoma.young_modulus_pa = 150e3;
  myoma.density_g_mm3 = 1.10e-3;
  std::vector<int> fixed;
  for (int i = 0; i < p.mesh.numNodes(); ++i) {
    const Vec3 x = p.mesh.X.row(i).transpose();
    if ((x.array() / Eigen::Array3d(25, 20, 33)).matrix().squaredNorm() > 1.0) fixed.push_back(i);
  }
  auto model = hysim::sim::buildModel(p.mesh, {wall, myoma}, fixed, {});
  if (!model.ok()) return p;
  p.model = std::move(*model);
  // The simulator's model after its first pass: a Lanczos estimate over all free nodes (an
  // update with nothing changed, forced global), which later updates may hold as a bound.
  {
    hysim::cutting::TopologyChange identity;
    identity.old_num_nodes = identity.new_num_nodes = p.mesh.numNodes();
    for (int i = 0; i < p.mesh.numNodes(); ++i) identity.node_old_to_new.push_back(i);
    for (int t = 0; t < p.mesh.numTets(); ++t) identity.element_old_to_new.push_back(t);
    std::vector<std::uint8_t> flags(p.model.fixed.begin(), p.model.fixed.end());
    hysim::sim::CutUpdate3DOptions global;
    global.mode_overlap = -1.0;
    global.max_held_estimates = 0;
    if (!hysim::sim::updateModelAfterCut3D(p.model, p.mesh, p.mesh, identity, flags, {}, global).ok()) return p;
  }
  p.state = hysim::sim::makeState(p.model, p.mesh);
  p.ok = true;
  return p;
}

const Prepared& mesh(int which) {
  static const Prepared meshes[2] = {
      prepare(std::string(HYSIM_SOURCE_DIR) + "/assets/uterus_myoma.msh", "uterus 12k"),
      prepare(std::string(HYSIM_SOURCE_DIR) + "/tests/data/cutting/uterus_20k.msh", "uterus 20k")};
  return meshes[which];
}

// Planes through the bounding-box centre (offset a little so that they do not pass exactly
// through the symmetric geometry's nodes): transverse, sagittal, coronal, oblique.
const Vec3 kNormals[4] = {{0.05, 0.1, 1.0}, {1.0, 0.12, 0.07}, {0.1, 1.0, 0.2}, {0.6, -0.5, 0.8}};
const Vec3 kOffsets[4] = {{0.3, -0.2, 1.1}, {0.7, 0.4, -0.6}, {-0.5, 1.3, 0.2}, {0.2, 0.1, -2.4}};

// Plane `which` of the four, through the mesh's bounding-box centre.
hysim::cutting::CutSurface planeThrough(const TetMesh& m, int which) {
  const Vec3 lo = m.X.colwise().minCoeff().transpose(), hi = m.X.colwise().maxCoeff().transpose();
  return *hysim::cutting::CutSurface::plane(0.5 * (lo + hi) + kOffsets[which], kNormals[which].normalized());
}

// The simulator's update after a pass: anchored after the cut are the surviving nodes that
// were anchored (new nodes are free); `model` is a copy of p.model, updated in place.
hysim::Status incrementalUpdate(const Prepared& p, const hysim::cutting::Cut3DResult& r, hysim::sim::Model& model,
                                     std::vector<std::uint8_t>& fixed, hysim::sim::CutUpdate3DReport* report = nullptr) {
  fixed.assign(static_cast<size_t>(r.mesh.numNodes()), 0);
  for (int i = 0; i < p.mesh.numNodes(); ++i) {
    const int j = r.change.node_old_to_new[i];
    if (j >= 0) fixed[j] = p.model.fixed[i] ? 1 : 0;
  }
  return hysim::sim::updateModelAfterCut3D(model, p.mesh, r.mesh, r.change, fixed, {}, {}, report);
}

// The steps' wall times (Cut3DReport's and CutUpdate3DReport's *_ms), summed over the
// iterations and given as means per iteration: counters classify_ms (with the node -> tets
// lists), snap_ms, separate_ms (subdivision and separation), collapse_ms, late_snap_ms and
// move_ms (in optimize_ms), prepare_ms (the update's masses and springs around the cut) and
// stability_ms.
struct PhaseTimes {
  double classify = 0, snap = 0, separate = 0, collapse = 0, late_snap = 0, move = 0, prepare = 0, stability = 0;
  void add(const hysim::cutting::Cut3DReport& c, const hysim::sim::CutUpdate3DReport& u) {
    classify += c.classify_ms;
    snap += c.snap_ms;
    separate += c.subdivide_ms + c.separate_ms;
    collapse += c.collapse_ms;
    late_snap += c.late_snap_ms;
    move += c.move_ms;
    prepare += u.prepare_ms;
    stability += u.stability_ms;
  }
  void report(benchmark::State& state, double n) const {
    state.counters["classify_ms"] = classify / n;
    state.counters["snap_ms"] = snap / n;
    state.counters["separate_ms"] = separate / n;
    state.counters["collapse_ms"] = collapse / n;
    state.counters["late_snap_ms"] = late_snap / n;
    state.counters["move_ms"] = move / n;
    state.counters["prepare_ms"] = prepare / n;
    state.counters["stability_ms"] = stability / n;
  }
};

void BM_Cut3DUpdate(benchmark::State& state) {
  const Prepared& p = mesh(static_cast<int>(state.range(0)));
  const int plane = static_cast<int>(state.range(1));
  hysim::cutting::Cut3DOptions o;
  o.method = static_cast<CutMethod>(state.range(2));
  if (!p.ok) {
    state.SkipWithError("cannot read or model the mesh (assets/uterus_myoma.msh, tests/data/cutting/uterus_20k.msh)");
    return;
  }
  const auto surface = planeThrough(p.mesh, plane);
  const bool incremental = state.range(3) != 0;
  double cutMs = 0, optMs = 0, updMs = 0;
  std::vector<double> updCpu;
  PhaseTimes phases;
  int elements = 0, nodes = 0;
  hysim::sim::Model model;
  std::vector<std::uint8_t> fixed;
  for (auto _ : state) {
    if (incremental) {  // the update works in place on a copy, made with the timer paused
      state.PauseTiming();
      model = p.model;
      state.ResumeTiming();
    }
    const auto t0 = std::chrono::steady_clock::now();
    auto r = hysim::cutting::cut3d(p.mesh, surface, o);
    const auto t1 = std::chrono::steady_clock::now();
    if (!r.ok()) {
      state.SkipWithError(r.error().c_str());
      return;
    }
    timespec c0, c1;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c0);
    if (incremental) {
      hysim::sim::CutUpdate3DReport update;
      const auto st = incrementalUpdate(p, *r, model, fixed, &update);
      if (!st.ok()) {
        state.SkipWithError(st.error().c_str());
        return;
      }
      phases.add(r->report, update);
    } else {
      auto rebuilt = hysim::sim::updateModel3D(p.model, p.mesh, r->mesh, r->change);
      if (!rebuilt.ok()) {
        state.SkipWithError(rebuilt.error().c_str());
        return;
      }
      model = std::move(*rebuilt);
    }
    auto s = hysim::sim::remapState3D(p.state, r->change);
    const auto t2 = std::chrono::steady_clock::now();
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c1);
    updCpu.push_back((c1.tv_sec - c0.tv_sec) * 1e3 + (c1.tv_nsec - c0.tv_nsec) * 1e-6);
    benchmark::DoNotOptimize(s);
    benchmark::DoNotOptimize(model);
    cutMs += std::chrono::duration<double, std::milli>(t1 - t0).count();
    updMs += std::chrono::duration<double, std::milli>(t2 - t1).count();
    optMs += r->report.optimize_ms;
    elements = r->mesh.numTets();
    nodes = r->mesh.numNodes();
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["cut_ms"] = cutMs / n;
  state.counters["optimize_ms"] = optMs / n;
  state.counters["update_ms"] = updMs / n;
  std::sort(updCpu.begin(), updCpu.end());
  if (!updCpu.empty()) state.counters["update_cpu_med_ms"] = updCpu[updCpu.size() / 2];
  state.counters["tets"] = elements;
  state.counters["nodes"] = nodes;
  if (incremental) phases.report(state, n);
  state.SetLabel(p.name + " plane " + std::to_string(plane) + " " + hysim::cutting::cutMethodName(o.method) +
                 (incremental ? ", incremental update" : ", rebuilt model"));
}
// Arguments: mesh, plane, method, update (0: sim::updateModel3D, a whole rebuild through
// buildModel; 1: sim::updateModelAfterCut3D, what the simulator does after each pass: masses
// and springs recomputed around the cut only, a Lanczos estimate of the stable substep).
BENCHMARK(BM_Cut3DUpdate)
    ->ArgsProduct({{0, 1},
                   {0, 1, 2, 3},
                   {static_cast<int>(CutMethod::Hybrid), static_cast<int>(CutMethod::Standard)},
                   {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(0.2)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);

// The cut alone (cut3d incl. optimisation and TopologyChange), without the tissue update.
void BM_Cut3D(benchmark::State& state) {
  const Prepared& p = mesh(static_cast<int>(state.range(0)));
  const int plane = static_cast<int>(state.range(1));
  hysim::cutting::Cut3DOptions o;
  o.method = static_cast<CutMethod>(state.range(2));
  if (!p.ok) {
    state.SkipWithError("cannot read the mesh");
    return;
  }
  const auto surface = planeThrough(p.mesh, plane);
  for (auto _ : state) {
    auto r = hysim::cutting::cut3d(p.mesh, surface, o);
    benchmark::DoNotOptimize(r);
  }
  state.SetLabel(p.name + " plane " + std::to_string(plane) + " " + hysim::cutting::cutMethodName(o.method));
}
BENCHMARK(BM_Cut3D)
    ->ArgsProduct({{0, 1}, {0, 1, 2, 3}, {static_cast<int>(CutMethod::Hybrid), static_cast<int>(CutMethod::Standard)}})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(0.2)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);

// A curved open surface like the shaving simulation's swept strip: a half-circle loop (radius
// 6 mm, 40 points) swept 20 mm along a slightly bent path, rows 0.3 mm apart (67 rows, 5,148
// triangles), reaching from the cavity side (y = 0.5) into the myoma (centre (0, -9, 4),
// radius 8). Cuts the same input mesh each iteration; the surface is built once (in the
// simulator that is the map step, not cut3d), then updates the model incrementally and remaps
// the state as BM_Cut3DUpdate/..../1 does. The benchmark's time is the whole; counters: cut_ms
// (cut3d incl. optimisation), optimize_ms, their difference cut_minus_opt_ms, and update_ms
// (medians over the repetitions).
hysim::cutting::CutSurface sweptStrip() {
  const int rows = 67, points = 40;
  const double radius = 6.0, length = 20.0, bend = 1.5;
  const Vec3 start(-1.0, 0.5, -6.0);
  hysim::cutting::Positions X(rows * points, 3);
  hysim::cutting::Tris F(2 * (rows - 1) * (points - 1), 3);
  for (int i = 0; i < rows; ++i) {
    const double s = length * i / (rows - 1);
    const Vec3 c = start + Vec3(bend * std::sin(M_PI * s / length), 0.3 * bend * std::sin(2 * M_PI * s / length), s);
    for (int j = 0; j < points; ++j) {
      const double th = M_PI * j / (points - 1);
      X.row(i * points + j) = (c + Vec3(radius * std::cos(th), -radius * std::sin(th), 0.0)).transpose();
    }
  }
  for (int i = 0, f = 0; i + 1 < rows; ++i)
    for (int j = 0; j + 1 < points; ++j) {
      const int a = i * points + j, b = a + 1, c = a + points, d = c + 1;
      F.row(f++) << a, b, d;
      F.row(f++) << a, d, c;
    }
  return *hysim::cutting::CutSurface::triangles(X, F);
}

void BM_Cut3DSurface(benchmark::State& state) {
  const Prepared& p = mesh(static_cast<int>(state.range(0)));
  hysim::cutting::Cut3DOptions o;
  o.method = static_cast<CutMethod>(state.range(1));
  if (!p.ok) {
    state.SkipWithError("cannot read the mesh");
    return;
  }
  static const hysim::cutting::CutSurface surface = sweptStrip();
  double cutMs = 0, optMs = 0, updMs = 0;
  int crossed = 0, elements = 0;
  hysim::sim::Model model;
  std::vector<std::uint8_t> fixed;
  for (auto _ : state) {
    state.PauseTiming();
    model = p.model;  // the update works in place on a copy
    state.ResumeTiming();
    const auto t0 = std::chrono::steady_clock::now();
    auto r = hysim::cutting::cut3d(p.mesh, surface, o);
    const auto t1 = std::chrono::steady_clock::now();
    if (!r.ok()) {
      state.SkipWithError(r.error().c_str());
      return;
    }
    const auto st = incrementalUpdate(p, *r, model, fixed);
    if (!st.ok()) {
      state.SkipWithError(st.error().c_str());
      return;
    }
    auto remapped = hysim::sim::remapState3D(p.state, r->change);
    benchmark::DoNotOptimize(remapped);
    const auto t2 = std::chrono::steady_clock::now();
    cutMs += std::chrono::duration<double, std::milli>(t1 - t0).count();
    updMs += std::chrono::duration<double, std::milli>(t2 - t1).count();
    optMs += r->report.optimize_ms;
    crossed = r->report.crossed_edges;
    elements = r->mesh.numTets();
    benchmark::DoNotOptimize(r);
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["cut_ms"] = cutMs / n;
  state.counters["optimize_ms"] = optMs / n;
  state.counters["cut_minus_opt_ms"] = (cutMs - optMs) / n;
  state.counters["update_ms"] = updMs / n;
  state.counters["crossed_edges"] = crossed;
  state.counters["tets"] = elements;
  state.SetLabel(p.name + " swept strip (" + std::to_string(surface.numTriangles()) + " triangles) " +
                 hysim::cutting::cutMethodName(o.method));
}
BENCHMARK(BM_Cut3DSurface)
    ->ArgsProduct({{0, 1}, {static_cast<int>(CutMethod::Hybrid), static_cast<int>(CutMethod::Standard)}})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(0.2)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);

// Recorded shaving passes: the inputs of the simulator's cuts dumped as
// $HYSIM_REPLAY_DIR/pass_NNN_mesh.msh and pass_NNN_surface.msh (NNN = 001, 002, ... up to the
// first missing one). Each iteration cuts every pass (hybrid, default options; no tissue
// update). Counters: the median and the largest per-pass cut_ms (cut3d incl. optimisation)
// and optimize_ms over all passes and iterations, passes, and the sum over the passes of the
// last iteration's q*_min (a quick check that quality is unchanged). Skipped when
// HYSIM_REPLAY_DIR is unset or holds no pass.
//   HYSIM_REPLAY_DIR=/path/to/dump ./build/bench/bench_cut3d --benchmark_filter=BM_Cut3DReplay
struct ReplayPass {
  TetMesh mesh;
  hysim::cutting::CutSurface surface;
};
const std::vector<ReplayPass>& replayPasses() {
  static const std::vector<ReplayPass> passes = [] {
    std::vector<ReplayPass> out;
    hysim::cutting::TetMesh mesh;
    hysim::cutting::TriMesh tri;
    for (int i = 1; hysim::bench::readDumpedPass(i, mesh, tri); ++i) {
      auto s = hysim::bench::dumpedSurface(tri);
      if (!s.ok()) break;
      out.push_back({std::move(mesh), std::move(*s)});
    }
    return out;
  }();
  return passes;
}

void BM_Cut3DReplay(benchmark::State& state) {
  const auto& passes = replayPasses();
  if (passes.empty()) {
    state.SkipWithError("HYSIM_REPLAY_DIR unset or without pass_001_mesh.msh / pass_001_surface.msh");
    return;
  }
  // Arg 1: the pieces cut off are left as cut (Cut3DOptions::anchored_nodes, chips.optimize
  // false in a scene), with the default scene's anchors (outside its ellipsoid: the corpus is
  // the default run's).
  const bool leaveChips = state.range(0) == 1;
  hysim::cutting::Cut3DOptions o;
  auto outside = [](const Eigen::Vector3d& p) {
    const double x = p[0] / 25, y = p[1] / 20, z = p[2] / 33;
    return x * x + y * y + z * z > 1;
  };
  if (leaveChips) o.anchored_at = outside;
  std::vector<double> cutMs, optMs, keepMs;
  double qSum = 0, qKept = 0, driftMax = 0;
  int driftOver = 0;
  int cutOff = 0;
  for (auto _ : state) {
    qSum = 0;
    qKept = 0;
    cutOff = 0;
    for (const auto& p : passes) {
      state.PauseTiming();
      std::vector<std::uint8_t> anchored(static_cast<size_t>(p.mesh.numNodes()));
      for (int i = 0; i < p.mesh.numNodes(); ++i) anchored[i] = outside(p.mesh.X.row(i).transpose()) ? 1 : 0;
      if (leaveChips) o.anchored_nodes = &anchored;
      state.ResumeTiming();
      const auto t0 = std::chrono::steady_clock::now();
      auto r = hysim::cutting::cut3d(p.mesh, p.surface, o);
      const auto t1 = std::chrono::steady_clock::now();
      if (!r.ok()) {
        state.SkipWithError(r.error().c_str());
        return;
      }
      cutMs.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
      optMs.push_back(r->report.optimize_ms);
      keepMs.push_back(r->report.keep_volume_ms);
      const double drift = std::abs(r->report.volume_drift) / r->report.volume_before;
      driftMax = std::max(driftMax, drift);
      if (drift > 1e-5) ++driftOver;
      state.PauseTiming();
      qSum += hysim::cutting::computeStats(r->mesh).q_min;
      {  // q*_min of the anchored pieces (what the simulator keeps)
        const hysim::cutting::TetMesh& m = r->mesh;
        std::vector<int> anchors;
        for (int i = 0; i < m.numNodes(); ++i)
          if (outside(m.X.row(i).transpose())) anchors.push_back(i);
        const auto c = hysim::cutting::tetComponents(m, anchors);
        double q = 1;
        for (int t = 0; t < m.numTets(); ++t)
          if (!c.free[c.label[t]])
            q = std::min(q, hysim::cutting::radiusRatio(m.X.row(m.T(t, 0)).transpose(), m.X.row(m.T(t, 1)).transpose(),
                                                        m.X.row(m.T(t, 2)).transpose(), m.X.row(m.T(t, 3)).transpose()));
        qKept += q;
        cutOff += r->report.cut_off_elements;
      }
      state.ResumeTiming();
      benchmark::DoNotOptimize(r);
    }
  }
  auto medianOf = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
  };
  state.counters["cut_ms"] = medianOf(cutMs);
  state.counters["optimize_ms"] = medianOf(optMs);
  state.counters["keep_volume_ms"] = medianOf(keepMs);
  state.counters["drift_max"] = driftMax;  // largest |volume drift| / volume of a cut
  state.counters["drift_over"] = driftOver / static_cast<double>(state.iterations());  // cuts above 1e-5
  state.counters["cut_ms_max"] = cutMs.empty() ? 0.0 : *std::max_element(cutMs.begin(), cutMs.end());
  state.counters["optimize_ms_max"] = optMs.empty() ? 0.0 : *std::max_element(optMs.begin(), optMs.end());
  state.counters["passes"] = static_cast<double>(passes.size());
  state.counters["q_min_sum"] = qSum;
  state.counters["q_kept_sum"] = qKept;
  state.counters["cut_off"] = cutOff;
}
BENCHMARK(BM_Cut3DReplay)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(3)->Repetitions(1);

// Building the recorded passes' cut surfaces (the last part of the pass's map_ms): arg 0 =
// CutSurface::strip (the simulator's, a tree along the grid), 1 = CutSurface::triangles of
// the same triangles (centroid-sorted tree). Counter build_ms: the median over the passes.
void BM_CutSurfaceBuild(benchmark::State& state) {
  std::vector<hysim::cutting::TriMesh> surfaces;
  {
    hysim::cutting::TetMesh mesh;
    hysim::cutting::TriMesh tri;
    for (int i = 1; hysim::bench::readDumpedPass(i, mesh, tri); ++i) surfaces.push_back(tri);
  }
  if (surfaces.empty()) {
    state.SkipWithError("HYSIM_REPLAY_DIR unset or without pass_001_mesh.msh / pass_001_surface.msh");
    return;
  }
  std::vector<std::pair<int, int>> shape;
  for (const auto& t : surfaces) {
    shape.push_back(hysim::bench::stripShape(t));
    if (shape.back().first == 0) {
      state.SkipWithError("a dumped surface is not a strip");
      return;
    }
  }
  std::vector<double> ms;
  for (auto _ : state)
    for (size_t i = 0; i < surfaces.size(); ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      auto s = state.range(0) == 0 ? hysim::cutting::CutSurface::strip(surfaces[i].X, shape[i].first, shape[i].second)
                                   : hysim::cutting::CutSurface::triangles(surfaces[i].X, surfaces[i].F);
      ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      benchmark::DoNotOptimize(s);
    }
  std::sort(ms.begin(), ms.end());
  state.counters["build_ms"] = ms[ms.size() / 2];
}
BENCHMARK(BM_CutSurfaceBuild)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(20);

// validate() runs after every cut in the tests, so it must stay cheap (O(n log n)) on a 20k-tet
// mesh; its cost is measured here, where a number informs, instead of bounded in a test, where
// a shared machine makes any wall-clock bound flaky.
void BM_ValidateTetMesh(benchmark::State& state) {
  const auto mesh = hysim::cutting::readTetMesh(std::string(HYSIM_SOURCE_DIR) + "/tests/data/cutting/uterus_20k.msh");
  if (!mesh.ok()) {
    state.SkipWithError(mesh.error().c_str());
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(hysim::cutting::validate(*mesh, {.requireAllNodesUsed = true}).ok());
  state.counters["tets"] = mesh->numTets();
}
BENCHMARK(BM_ValidateTetMesh)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
