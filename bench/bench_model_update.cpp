// The tissue-model update after a cut alone (sim::updateModelAfterCut3D, then the state the
// simulator's resetState makes), on fixed inputs, for A/B comparisons and profiles:
//  - the 20k-tet uterus cut by the four planes of bench_cut3d (BM_Cut3DUpdate/1/p/0/1),
//  - each recorded shaving pass in $HYSIM_REPLAY_DIR (hysim run --dump-cuts DIR): the pass's
//    mesh modelled from scratch (buildModel, then a global Lanczos estimate as the simulator
//    has after its first pass), cut by the pass's surface, the pieces without an anchored
//    node removed as the simulator removes chips.
// HYSIM_NO_PLANES set: the passes only; HYSIM_LANCZOS_MIN_STEPS: CutUpdate3DOptions::lanczos_min_steps. Prints each case's median thread CPU time over HYSIM_REPS repetitions (default 21) and a
// hash over the updated models' arrays (equal hashes: bit-identical models). Not a
// Google Benchmark program (own main), so that callgrind can count one repetition:
//   HYSIM_REPS=1 valgrind --tool=callgrind --toggle-collect='*runUpdate*'
//       ./build/bench/bench_model_update
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/mesh_io.hpp"
#include "hysim/sim/model.hpp"
#include "hysim/sim/tissue_update3d.hpp"
#include "replay_passes.hpp"

namespace {

using hysim::cutting::TetMesh;
using Vec3 = Eigen::Vector3d;

struct Case {
  std::string name;
  TetMesh before, after;
  hysim::cutting::TopologyChange change;
  hysim::sim::Model model;
  std::vector<std::uint8_t> fixed_after;
  std::vector<std::int32_t> keep;
  TetMesh kept;
};

bool anchored(const Vec3& x) { return (x.array() / Eigen::Array3d(25, 20, 33)).matrix().squaredNorm() > 1.0; }

// `scene`: the default scene's materials and options (max_substeps 12, damping); otherwise
// bench_cut3d's (default ModelOptions, no damping).
bool prepare(Case& c, const hysim::cutting::CutSurface& surface, bool scene) {
  const bool remove_free = scene;
  hysim::sim::Material wall, myoma;
  wall.label = 1;
  wall.young_modulus_pa = 60e3;
  wall.density_g_mm3 = 1.05e-3;
  myoma.label = 2;
  myoma.young_modulus_pa = 150e3;
  myoma.density_g_mm3 = 1.10e-3;
  hysim::sim::ModelOptions options;
  if (scene) {
    wall.stiffness_damping_s = myoma.stiffness_damping_s = 2e-5;
    options.max_substeps = 12;
  }
  std::vector<int> fixed;
  for (int i = 0; i < c.before.numNodes(); ++i)
    if (anchored(c.before.X.row(i).transpose())) fixed.push_back(i);
  auto model = hysim::sim::buildModel(c.before, {wall, myoma}, fixed, options);
  if (!model.ok()) return false;
  c.model = std::move(*model);
  {
    hysim::cutting::TopologyChange identity;
    identity.old_num_nodes = identity.new_num_nodes = c.before.numNodes();
    for (int i = 0; i < c.before.numNodes(); ++i) identity.node_old_to_new.push_back(i);
    for (int t = 0; t < c.before.numTets(); ++t) identity.element_old_to_new.push_back(t);
    std::vector<std::uint8_t> flags(c.model.fixed.begin(), c.model.fixed.end());
    hysim::sim::CutUpdate3DOptions global;
    global.mode_overlap = -1.0;
    global.max_held_estimates = 0;
    if (!hysim::sim::updateModelAfterCut3D(c.model, c.before, c.before, identity, flags, {}, global).ok()) return false;
  }
  auto r = hysim::cutting::cut3d(c.before, surface);
  if (!r.ok()) return false;
  c.after = std::move(r->mesh);
  c.change = std::move(r->change);
  const int n = c.after.numNodes();
  c.fixed_after.assign(static_cast<size_t>(n), 0);
  for (int i = 0; i < c.before.numNodes(); ++i) {
    const int j = c.change.node_old_to_new[i];
    if (j >= 0) c.fixed_after[j] = c.model.fixed[i] && (!scene || anchored(c.before.X.row(i).transpose())) ? 1 : 0;
  }
  std::vector<int> tets;
  if (remove_free) {
    std::vector<int> anchors;
    for (int i = 0; i < n; ++i)
      if (c.fixed_after[i]) anchors.push_back(i);
    const auto comps = hysim::cutting::tetComponents(c.after, anchors);
    c.keep.assign(static_cast<size_t>(n), -1);
    for (int t = 0; t < c.after.numTets(); ++t)
      if (!comps.free[comps.label[t]]) {
        tets.push_back(t);
        for (int k = 0; k < 4; ++k) c.keep[c.after.T(t, k)] = 0;
      }
    int kept = 0;
    for (auto& k : c.keep)
      if (k == 0) k = kept++;
    c.kept.X.resize(kept, 3);
    for (int i = 0; i < n; ++i)
      if (c.keep[i] >= 0) c.kept.X.row(c.keep[i]) = c.after.X.row(i);
    c.kept.T.resize(static_cast<Eigen::Index>(tets.size()), 4);
    c.kept.material.resize(static_cast<Eigen::Index>(tets.size()));
    for (size_t k = 0; k < tets.size(); ++k) {
      for (int q = 0; q < 4; ++q) c.kept.T(static_cast<Eigen::Index>(k), q) = c.keep[c.after.T(tets[k], q)];
      c.kept.material[static_cast<Eigen::Index>(k)] = c.after.material[tets[k]];
    }
  } else {
    c.kept = c.after;
  }
  return true;
}

std::uint64_t mix(std::uint64_t h, const void* data, size_t bytes) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < bytes; ++i) {
    h ^= p[i];
    h *= 1099511628211ULL;
  }
  return h;
}

template <class V>
std::uint64_t mixVec(std::uint64_t h, const V& v) {
  return mix(h, v.data(), sizeof(v.data()[0]) * static_cast<size_t>(v.size()));
}

std::uint64_t modelHash(const hysim::sim::Model& m) {
  std::uint64_t h = 1469598103934665603ULL;
  h = mix(h, &m.num_nodes, sizeof(m.num_nodes));
  h = mixVec(h, m.mass);
  h = mixVec(h, m.inv_mass);
  h = mixVec(h, m.springs);
  h = mixVec(h, m.rest_length);
  h = mixVec(h, m.stiffness);
  h = mixVec(h, m.damping);
  h = mixVec(h, m.fixed);
  const auto& st = m.step_springs;
  h = mixVec(h, st.a);
  h = mixVec(h, st.b);
  h = mixVec(h, st.rest_length);
  h = mixVec(h, st.stiffness);
  h = mixVec(h, st.damping);
  h = mixVec(h, st.node_offset);
  h = mixVec(h, st.incident);
  h = mixVec(h, st.sign);
  h = mix(h, &m.omega_max, sizeof(double));
  h = mix(h, &m.critical_dt, sizeof(double));
  h = mix(h, &m.added_mass, sizeof(double));
  h = mix(h, &m.substeps, sizeof(int));
  h = mix(h, &m.stability_held, sizeof(int));
  h = mixVec(h, m.stability_mode);
  return h;
}

// What is timed (a function of its own, for callgrind's --toggle-collect=runUpdate).
hysim::sim::CutUpdate3DOptions g_options;
hysim::sim::CutUpdate3DReport g_report;

__attribute__((noinline)) hysim::Status runUpdate(Case& c, hysim::sim::Model& model, hysim::sim::State& state) {
  const auto st =
      hysim::sim::updateModelAfterCut3D(model, c.before, c.after, c.change, c.fixed_after, c.keep, g_options, &g_report);
  state = hysim::sim::makeState(model, c.kept);
  return st;
}

double cpuMs() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

}  // namespace

int main() {
  const char* reps_env = std::getenv("HYSIM_REPS");
  const int reps = reps_env ? std::max(1, std::atoi(reps_env)) : 21;
  if (const char* min_steps = std::getenv("HYSIM_LANCZOS_MIN_STEPS")) g_options.lanczos_min_steps = std::atoi(min_steps);
  std::vector<Case> cases;
  if (std::getenv("HYSIM_NO_PLANES") == nullptr) {
    auto m = hysim::cutting::readTetMesh(std::string(HYSIM_SOURCE_DIR) + "/tests/data/cutting/uterus_20k.msh");
    if (!m.ok()) return 1;
    const Vec3 normals[4] = {{0.05, 0.1, 1.0}, {1.0, 0.12, 0.07}, {0.1, 1.0, 0.2}, {0.6, -0.5, 0.8}};
    const Vec3 offsets[4] = {{0.3, -0.2, 1.1}, {0.7, 0.4, -0.6}, {-0.5, 1.3, 0.2}, {0.2, 0.1, -2.4}};
    const Vec3 lo = m->X.colwise().minCoeff().transpose(), hi = m->X.colwise().maxCoeff().transpose();
    for (int p = 0; p < 4; ++p) {
      Case c;
      c.name = "20k plane " + std::to_string(p);
      c.before = *m;
      auto s = hysim::cutting::CutSurface::plane(0.5 * (lo + hi) + offsets[p], normals[p].normalized());
      if (!prepare(c, *s, false)) return 1;
      cases.push_back(std::move(c));
    }
  }
  {
    hysim::cutting::TetMesh mesh;
    hysim::cutting::TriMesh tri;
    for (int i = 1; hysim::bench::readDumpedPass(i, mesh, tri); ++i) {
      auto s = hysim::bench::dumpedSurface(tri);
      if (!s.ok()) break;
      Case c;
      c.name = "pass " + std::to_string(i);
      c.before = std::move(mesh);
      if (!prepare(c, *s, true)) {
        std::fprintf(stderr, "pass %d: cannot prepare\n", i);
        continue;
      }
      cases.push_back(std::move(c));
    }
  }
  std::uint64_t all = 1469598103934665603ULL;
  std::vector<double> plane_med, pass_med;
  for (Case& c : cases) {
    std::vector<double> times;
    hysim::sim::Model model;
    for (int r = 0; r < reps; ++r) {
      model = c.model;
      const double t0 = cpuMs();
      hysim::sim::State state;
      const auto st = runUpdate(c, model, state);
      const double t1 = cpuMs();
      if (!st.ok()) {
        std::fprintf(stderr, "%s: %s\n", c.name.c_str(), st.error().c_str());
        return 1;
      }
      times.push_back(t1 - t0);
    }
    std::sort(times.begin(), times.end());
    const double med = times[times.size() / 2];
    const std::uint64_t h = modelHash(model);
    all = mix(all, &h, sizeof(h));
    (c.name.rfind("pass", 0) == 0 ? pass_med : plane_med).push_back(med);
    std::printf("%-14s nodes %6d springs %6d stab_nodes %5d lanczos %3d%s omega %.6e substeps %2d  update_cpu_med_ms %.3f  hash %016llx\n",
                c.name.c_str(), model.num_nodes, static_cast<int>(model.springs.rows()), g_report.stability_nodes,
                g_report.lanczos_steps, g_report.global_stability ? "G" : (g_report.held_stability ? "H" : " "),
                model.omega_max, model.substeps, med, static_cast<unsigned long long>(h));
  }
  auto median = [](std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  std::printf("median over planes %.3f ms, over passes %.3f ms (%zu); all models hash %016llx\n", median(plane_med),
              median(pass_med), pass_med.size(), static_cast<unsigned long long>(all));
  return 0;
}
