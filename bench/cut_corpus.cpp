// cut_corpus: the hybrid 3D cut on tet meshes made by other meshers (issue 34). Each mesh of
// tests/data/corpus (TetGen, Gmsh, CGAL Mesh_3; tools/make-corpus) is cut, one cut at a time
// from the input mesh, by random complete planes (through the middle 40% of the bounding box)
// and by curved patches (spheres and cylinders; complete, or ending inside the mesh), with the
// default hybrid options. Each cut is checked against the bounds of tests/common/cut_checks.hpp
// (valid, separated, growth <= 1.10, q*_min >= 0.25x, min edge >= 0.2x, |dV|/V <= 1e-5).
// Prints a table per mesh and cut family, then every miss with its reasons and a command that
// repeats it (a plane at full precision, or the surface written to --dump).
// Exit status: 0 every cut valid and separated and >= 99% within all bounds, 2 otherwise,
// 1 bad input. A plain program, not a Google Benchmark: it reports numbers, it asserts nothing.
//   ./build/bench/cut_corpus [--planes 500] [--surfaces 100] [--json F] [--dump DIR]
//   ./build/bench/cut_corpus --mesh gmsh_capsule.msh --only plane:17   (one case)
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cut_checks.hpp"
#include "hysim/cutting/mesh_io.hpp"

namespace {

using namespace hysim;
using testing::CorpusCut;
using testing::CutMeasure;

struct Args {
  std::string corpus = std::string(HYSIM_SOURCE_DIR) + "/tests/data/corpus";
  int planes = 500, surfaces = 100;
  std::string json, dump = "cut_corpus_misses", mesh, only, hysim = "./build/tools/hysim";
  std::uint64_t seed = 34;
};

struct CaseResult {
  int mesh = 0, k = 0;
  bool plane = true;
  testing::CutKind kind = testing::CutKind::Plane;
  CutMeasure m;
  std::vector<std::string> missed;
  std::string repro;
};

// Cases of mesh i when `total` are spread over `meshes` meshes (the first ones get the rest).
int share(int total, int meshes, int i) { return total / meshes + (i < total % meshes ? 1 : 0); }

std::string fmt17(const Eigen::Vector3d& v) {
  char s[96];
  std::snprintf(s, sizeof s, "%.17g,%.17g,%.17g", v.x(), v.y(), v.z());
  return s;
}

// A command that repeats the cut (hysim cut), writing the surface of a curved miss to `dump`.
std::string reproCommand(const Args& a, const std::string& meshPath, const CorpusCut& cut, int mesh, int k) {
  const std::string in = std::filesystem::proximate(meshPath).string();
  if (cut.kind == testing::CutKind::Plane)
    return a.hysim + " cut " + in + " --plane " + fmt17(cut.point) + "," + fmt17(cut.normal) +
           " --method hybrid --out /tmp/cut.msh";
  std::filesystem::create_directories(a.dump);
  const std::string stem = std::filesystem::path(testing::kCorpus[mesh].file).stem().string();
  const std::string file = a.dump + "/" + stem + "_surface_" + std::to_string(k) + ".msh";
  cutting::TriMesh s;
  s.X = cut.X;
  s.F = cut.F;
  s.material = cutting::Labels::Zero(cut.F.rows());
  if (Status st = cutting::writeMesh(file, s); !st.ok()) return "(could not write " + file + ": " + st.error() + ")";
  return a.hysim + " cut " + in + " --surface " + file + " --method hybrid --out /tmp/cut.msh";
}

bool selected(const Args& a, bool plane, int k) {
  if (a.only.empty()) return true;
  return a.only == std::string(plane ? "plane:" : "surface:") + std::to_string(k);
}

// All cases of corpus mesh i; false when the mesh cannot be read.
bool runMesh(const Args& a, int i, std::vector<CaseResult>* results, nlohmann::ordered_json* meshJson) {
  const std::string path = a.corpus + "/" + testing::kCorpus[i].file;
  auto mesh = cutting::readTetMesh(path);
  if (!mesh.ok()) {
    std::fprintf(stderr, "cut_corpus: %s\n", mesh.error().c_str());
    return false;
  }
  const auto base = testing::meshBaseline(*mesh);
  *meshJson = {{"file", testing::kCorpus[i].file}, {"mesher", testing::kCorpus[i].mesher},
               {"flags", testing::kCorpus[i].flags}, {"tets", mesh->numTets()}, {"nodes", mesh->numNodes()},
               {"q_min", base.stats.q_min}, {"q_mean", base.stats.q_mean}, {"edge_min", base.stats.edge_min},
               {"edge_mean", base.stats.edge_mean}, {"dihedral_min_deg", base.stats.dihedral_min_deg},
               {"volume", base.volume}};
  const int meshes = static_cast<int>(testing::kCorpus.size());
  for (int family = 0; family < 2; ++family) {
    const bool plane = family == 0;
    const int n = share(plane ? a.planes : a.surfaces, meshes, i);
    for (int k = 0; k < n; ++k) {
      if (!selected(a, plane, k)) continue;
      const CorpusCut cut = plane ? testing::corpusPlane(*mesh, i, k, a.seed) : testing::corpusSurface(*mesh, i, k, a.seed);
      CaseResult r{i, k, plane, cut.kind, testing::measureCut(*mesh, base, cut), {}, {}};
      r.missed = testing::missedBounds(r.m);
      if (!r.missed.empty()) r.repro = reproCommand(a, path, cut, i, k);
      results->push_back(std::move(r));
    }
  }
  return true;
}

// Counts and worst values of one table row.
struct Row {
  int cuts = 0, valid = 0, separated = 0, growth = 0, q = 0, edge = 0, volume = 0, all = 0;
  double worst_growth = 0, worst_q = 1e300, worst_edge = 1e300, worst_volume = 0, ms = 0;
  void add(const CaseResult& r) {
    const testing::CutBounds b;
    const CutMeasure& m = r.m;
    ++cuts;
    if (!m.error.empty()) return;
    valid += m.valid();
    separated += m.separated();
    growth += m.growth <= b.growth;
    q += m.q_ratio >= b.q_ratio;
    edge += m.edge_ratio >= b.edge_ratio;
    volume += std::abs(m.volume_change) <= b.volume;
    all += r.missed.empty();
    worst_growth = std::max(worst_growth, m.growth);
    worst_q = std::min(worst_q, m.q_ratio);
    worst_edge = std::min(worst_edge, m.edge_ratio);
    worst_volume = std::max(worst_volume, std::abs(m.volume_change));
    ms += m.cut_ms;
  }
  nlohmann::ordered_json json() const {
    return {{"cuts", cuts}, {"valid", valid}, {"separated", separated}, {"growth_ok", growth}, {"q_ok", q},
            {"edge_ok", edge}, {"volume_ok", volume}, {"all_ok", all}, {"worst_growth", worst_growth},
            {"worst_q_ratio", worst_q}, {"worst_edge_ratio", worst_edge}, {"worst_volume_change", worst_volume},
            {"mean_cut_ms", cuts ? ms / cuts : 0.0}};
  }
};

void printRow(const char* mesh, const char* family, const Row& r) {
  std::printf("%-26s %-8s %5d %5d %5d %6d %5d %5d %5d %5d   %6.3f %6.3f %6.3f %8.1e %7.1f\n", mesh, family, r.cuts,
              r.valid, r.separated, r.growth, r.q, r.edge, r.volume, r.all, r.worst_growth, r.worst_q, r.worst_edge,
              r.worst_volume, r.cuts ? r.ms / r.cuts : 0.0);
}

// The table (one row per mesh and family, then the totals); returns the totals row.
Row printTable(const std::vector<CaseResult>& results, nlohmann::ordered_json* meshes) {
  std::printf("%-26s %-8s %5s %5s %5s %6s %5s %5s %5s %5s   %6s %6s %6s %8s %7s\n", "mesh", "cuts", "n", "valid",
              "sep", "growth", "q*", "edge", "vol", "all", "growth", "q*x", "edge x", "|dV|/V", "ms");
  Row total;
  for (size_t i = 0; i < testing::kCorpus.size(); ++i) {
    Row family[2];
    for (const auto& r : results)
      if (r.mesh == static_cast<int>(i)) family[r.plane ? 0 : 1].add(r), total.add(r);
    printRow(testing::kCorpus[i].file, "planes", family[0]);
    printRow("", "surfaces", family[1]);
    if (i < meshes->size()) {
      (*meshes)[i]["planes"] = family[0].json();
      (*meshes)[i]["surfaces"] = family[1].json();
    }
  }
  printRow("all", "", total);
  return total;
}

nlohmann::ordered_json caseJson(const CaseResult& r) {
  const CutMeasure& m = r.m;
  nlohmann::ordered_json j = {{"mesh", testing::kCorpus[r.mesh].file}, {"family", r.plane ? "plane" : "surface"},
                              {"case", r.k}, {"kind", testing::cutKindName(r.kind)}};
  if (!m.error.empty()) j["error"] = m.error;
  j.update({{"valid", m.valid()}, {"separated", m.separated()}, {"crossing_edges", m.crossing_edges},
            {"max_crossing_depth_mm", m.max_depth}, {"components", m.components}, {"growth", m.growth},
            {"q_ratio", m.q_ratio}, {"edge_ratio", m.edge_ratio}, {"volume_change", m.volume_change},
            {"cut_ms", m.cut_ms}, {"missed", r.missed}});
  if (!r.repro.empty()) j["repro"] = r.repro;
  return j;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"cut_corpus: the hybrid 3D cut on the corpus of meshes from other meshers"};
  Args a;
  app.add_option("--corpus", a.corpus, "folder of the corpus meshes");
  app.add_option("--planes", a.planes, "random complete planes, spread over the meshes")->check(CLI::NonNegativeNumber);
  app.add_option("--surfaces", a.surfaces, "curved cut surfaces, spread over the meshes")->check(CLI::NonNegativeNumber);
  app.add_option("--seed", a.seed, "seed of the cases");
  app.add_option("--json", a.json, "write every cut and the tables as JSON");
  app.add_option("--dump", a.dump, "folder for the surfaces of curved misses (repro)");
  app.add_option("--mesh", a.mesh, "only this corpus file (e.g. gmsh_capsule.msh)");
  app.add_option("--only", a.only, "only this case: plane:K or surface:K");
  app.add_option("--hysim", a.hysim, "the hysim binary named in repro commands");
  CLI11_PARSE(app, argc, argv);

  std::vector<CaseResult> results;
  nlohmann::ordered_json meshes = nlohmann::ordered_json::array();
  for (int i = 0; i < static_cast<int>(testing::kCorpus.size()); ++i) {
    nlohmann::ordered_json mj;
    if (!a.mesh.empty() && a.mesh != testing::kCorpus[i].file) {
      meshes.push_back({{"file", testing::kCorpus[i].file}, {"skipped", true}});
      continue;
    }
    if (!runMesh(a, i, &results, &mj)) return 1;
    std::printf("%-26s %-16s %5d tets, q*_min %.4f, min edge %.3f mm (%s)\n", testing::kCorpus[i].file,
                testing::kCorpus[i].mesher, mj["tets"].get<int>(), mj["q_min"].get<double>(),
                mj["edge_min"].get<double>(), testing::kCorpus[i].flags);
    meshes.push_back(mj);
  }
  std::printf("\n");
  const Row total = printTable(results, &meshes);
  int misses = 0;
  nlohmann::ordered_json cases = nlohmann::ordered_json::array();
  for (const auto& r : results) {
    cases.push_back(caseJson(r));
    if (r.missed.empty()) continue;
    if (misses++ == 0) std::printf("\nmisses:\n");
    std::string why;
    for (const auto& w : r.missed) why += (why.empty() ? "" : "; ") + w;
    std::printf("  %s %s:%d (%s): %s\n    %s\n", testing::kCorpus[r.mesh].file, r.plane ? "plane" : "surface", r.k,
                testing::cutKindName(r.kind), why.c_str(), r.repro.c_str());
  }
  const double share_ok = total.cuts ? static_cast<double>(total.all) / total.cuts : 1.0;
  const bool accepted = total.valid == total.cuts && total.separated == total.cuts && share_ok >= 0.99;
  std::printf("\n%d cuts, %d within all bounds (%.1f%%), %d valid, %d separated: %s\n", total.cuts, total.all,
              100 * share_ok, total.valid, total.separated, accepted ? "accepted" : "NOT accepted");
  if (!a.json.empty()) {
    nlohmann::ordered_json j = {{"planes", a.planes}, {"surfaces", a.surfaces}, {"seed", a.seed},
                                {"meshes", meshes}, {"total", total.json()}, {"accepted", accepted},
                                {"cuts", cases}};
    std::ofstream out(a.json);
    out << j.dump(1) << "\n";
    if (!out) {
      std::fprintf(stderr, "cut_corpus: cannot write %s\n", a.json.c_str());
      return 1;
    }
  }
  return accepted ? 0 : 2;
}
