#include "cli_cut3d.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/mesh_io.hpp"
#include "hysim/cutting/mesh_stats.hpp"
#include "hysim/engine/cut_surface_file.hpp"
#include "hysim/render/image.hpp"
#include "tet_picture.hpp"
#include "tool_common.hpp"

namespace hysim::tools {
namespace {

int fail(const std::string& m) {
  std::cerr << "hysim: " << m << "\n";
  return 1;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int runCut3d(const Cut3dArgs& a) {
  cutting::Cut3DOptions o;
  if (!cutting::parseCutMethod(a.method, &o.method))
    return fail("--method: unknown method '" + a.method + "' (hybrid, standard, snap, delete)");
  if (a.plane.empty() == a.surface.empty()) return fail("cut: give exactly one of --plane and --surface");
  auto mesh = cutting::readTetMesh(a.in);
  if (!mesh.ok()) return fail(mesh.error());
  if (Status st = cutting::validate(*mesh); !st.ok()) return fail(a.in + ": invalid mesh: " + st.error());
  Result<cutting::CutSurface> surface = Error{""};
  if (!a.plane.empty()) {
    // The normal's size does not matter (it is normalised without overflow), but every value
    // must be a number a mesh coordinate could be.
    auto parsed = parseNumberList("--plane", a.plane, 6, "px,py,pz,nx,ny,nz (six numbers)", cutting::kMaxCoordinateMm);
    if (!parsed.ok()) return fail(parsed.error());
    const std::vector<double>& v = *parsed;
    surface = cutting::CutSurface::plane(Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector3d(v[3], v[4], v[5]));
    if (!surface.ok()) return fail("--plane '" + a.plane + "': " + surface.error());
  } else {
    surface = engine::loadCutSurface(a.surface);
  }
  if (!surface.ok()) return fail(surface.error());
  const auto t0 = std::chrono::steady_clock::now();
  auto res = cutting::cut3d(*mesh, *surface, o);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (!res.ok()) return fail(res.error());
  if (Status st = cutting::validate(res->mesh); !st.ok()) return fail("internal error: invalid cut mesh: " + st.error());
  if (Status st = cutting::writeMesh(a.out, res->mesh); !st.ok()) return fail(st.error());
  const auto s = cutting::computeStats(res->mesh);
  const auto comps = cutting::tetComponents(res->mesh);
  const auto& r = res->report;
  std::printf("%s cut: %d -> %d nodes, %d -> %d tets; %d crossed edges, %d snapped (%d on the boundary), %d split, "
              "%d duplicated, %d deleted; %d components; q*_min %.4f; %.3f ms (optimisation %.3f ms)\n",
              cutting::cutMethodName(o.method), mesh->numNodes(), res->mesh.numNodes(), mesh->numTets(),
              res->mesh.numTets(), r.crossed_edges, r.snapped_nodes, r.boundary_snaps, r.split_edges,
              r.duplicated_nodes, r.deleted_elements, comps.count, s.q_min, ms, r.optimize_ms);
  if (!a.stats.empty()) {
    auto j = statsJson(s);
    j["time_ms"] = ms;
    j["optimize_ms"] = r.optimize_ms;
    j["peeled_elements"] = r.peeled_elements;
    j["flap_peeled"] = r.flap_peeled;
    j["peeled_volume"] = r.peeled_volume;
    j["volume_restored"] = r.volume_restored;
    j["volume_moves"] = r.volume_moves;
    j["method"] = cutting::cutMethodName(o.method);
    j["components"] = comps.count;
    nlohmann::ordered_json vols = nlohmann::ordered_json::array();
    for (double v : comps.volume) vols.push_back(v);
    j["component_volumes"] = vols;
    j["volume_before"] = r.volume_before;
    j["volume_after"] = r.volume_after;
    j["volume_drift"] = r.volume_drift;
    j["cut_off_volume"] = r.cut_off_volume;
    nlohmann::ordered_json materials = nlohmann::ordered_json::array();
    for (const cutting::MaterialVolume& m : r.material_volumes)
      materials.push_back({{"label", m.label}, {"before", m.before}, {"after", m.after}, {"drift", m.drift()}});
    j["material_volumes"] = materials;
    std::ofstream out(a.stats);
    if (!out) return fail("cannot write '" + a.stats + "'");
    out << j.dump(2) << "\n";
  }
  return 0;
}

namespace {

// The small quality mesh of Table 2, like the paper's (~69 nodes, ~136 tets): a coarse Gmsh
// ellipsoid, tests/data/cutting/table2_ellipsoid.msh (regeneration command in its .geo).
Result<cutting::TetMesh> table2Mesh() {
  return cutting::readTetMesh(std::string(HYSIM_SOURCE_DIR) + "/tests/data/cutting/table2_ellipsoid.msh");
}

// The coarse ellipsoid has ~35 degree dihedral angles between boundary faces everywhere, so
// the default 30 degree feature angle would freeze every boundary node; the Hybrid rows
// treat only sharper creases as features.
constexpr double kTable2FeatureAngleDeg = 60.0;

nlohmann::ordered_json row(const std::string& name, const cutting::MeshStats& s, double ms) {
  auto j = statsJson(s);
  j = nlohmann::ordered_json{{"row", name}, {"stats", j}, {"time_ms", ms}};
  std::printf("| %-9s | %4d | %4d | %9.3g | %7.2f | %6.2f | %6.3f | %5.2f | %5.2f | %7.4f | %5.3f | %5.3f | %6.2f | %7.3f |\n",
              name.c_str(), s.nodes, s.elements, s.size_min, s.size_mean, s.size_std, s.edge_min, s.edge_mean,
              s.edge_std, s.q_min, s.q_mean, s.q_std, s.dihedral_min_deg, ms);
  return j;
}

struct Timed {
  cutting::Cut3DResult result;
  double ms = 0;
};
Timed timedCut(const cutting::TetMesh& m, const cutting::CutSurface& s, cutting::CutMethod method, int repeats) {
  cutting::Cut3DOptions o;
  o.method = method;
  o.feature_angle_deg = kTable2FeatureAngleDeg;
  std::vector<double> times;
  Timed t;
  for (int r = 0; r < std::max(1, repeats); ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    auto res = cutting::cut3d(m, s, o);
    times.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (r == 0) t.result = std::move(res).value();
  }
  t.ms = median(times);
  return t;
}

}  // namespace

int runTable2(const Table2Options& o) {
  nlohmann::ordered_json out;
  const auto loaded = table2Mesh();
  if (!loaded.ok()) return fail(loaded.error());
  const auto& mesh = *loaded;
  const auto planeA = *cutting::CutSurface::plane(Eigen::Vector3d(0.5, 0.3, 0.2), Eigen::Vector3d(0.15, 0.1, 1.0));
  const auto planeB = *cutting::CutSurface::plane(Eigen::Vector3d(1.1, -0.7, 0.0), Eigen::Vector3d(1.0, 0.35, 0.2));
  std::printf("Table 2 (Gmsh ellipsoid 20 x 15 x 12 mm, one plane cut, feature angle %.0f deg; time = median of %d "
              "runs)\n\n",
              kTable2FeatureAngleDeg, o.repeats);
  std::printf("| Test      |  #N  |  #E  |   V_min   |  V_mu   |  V_sd  | E_min  | E_mu  | E_sd  | q*_min  | q*_mu | q*_sd | dih_min | t [ms]  |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  rows.push_back(row("Initial", cutting::computeStats(mesh), 0));
  const auto st = timedCut(mesh, planeA, cutting::CutMethod::Standard, o.repeats);
  rows.push_back(row("Standard", cutting::computeStats(st.result.mesh), st.ms));
  const auto ha = timedCut(mesh, planeA, cutting::CutMethod::Hybrid, o.repeats);
  rows.push_back(row("Hybrid A", cutting::computeStats(ha.result.mesh), ha.ms));
  const auto hb = timedCut(mesh, planeB, cutting::CutMethod::Hybrid, o.repeats);
  rows.push_back(row("Hybrid B", cutting::computeStats(hb.result.mesh), hb.ms));
  for (const auto* r : {&st, &ha, &hb})
    if (Status v = cutting::validate(r->result.mesh); !v.ok()) return fail("invalid cut mesh: " + v.error());
  out["table2"] = rows;
  if (!o.pictures_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(o.pictures_dir, ec);
    if (ec) return fail("cannot create pictures folder '" + o.pictures_dir + "': " + ec.message());
    TetPictureOptions po;
    po.frame_min = mesh.X.colwise().minCoeff().transpose();
    po.frame_max = mesh.X.colwise().maxCoeff().transpose();
    struct Picture {
      const char* name;
      const cutting::TetMesh* mesh;
      const cutting::CutSurface* plane;
    };
    for (const Picture& p : {Picture{"table2_initial", &mesh, nullptr}, Picture{"table2_standard", &st.result.mesh, &planeA},
                             Picture{"table2_hybrid_a", &ha.result.mesh, &planeA},
                             Picture{"table2_hybrid_b", &hb.result.mesh, &planeB}}) {
      po.has_plane = p.plane != nullptr;
      if (p.plane) {
        po.plane_point = p.plane->planePoint();
        po.plane_normal = p.plane->planeNormal();
      }
      const std::string path = o.pictures_dir + "/" + p.name + ".png";
      if (Status s = render::writePng(path, drawTetMesh(*p.mesh, po)); !s.ok()) return fail(s.error());
    }
    std::printf("\npictures in %s (table2_initial, _standard, _hybrid_a, _hybrid_b .png; pieces moved %.0f mm apart)\n",
                o.pictures_dir.c_str(), po.gap);
  }

  // Second block: successive parallel cuts through the uterus mesh.
  const std::string path = std::string(HYSIM_SOURCE_DIR) + "/assets/uterus_myoma.msh";
  auto uterus = cutting::readTetMesh(path);
  if (!uterus.ok()) return fail(uterus.error());
  const auto s0 = cutting::computeStats(*uterus);
  const Eigen::Vector3d lo = uterus->X.colwise().minCoeff().transpose(), hi = uterus->X.colwise().maxCoeff().transpose();
  const Eigen::Vector3d normal = Eigen::Vector3d(0.1, 0.05, 1.0).normalized();
  std::printf("\nUterus mesh (%s): %d successive parallel plane cuts, pieces kept\n\n", path.c_str(), o.uterus_cuts);
  std::printf("| Method   |  #N  |  #E  | #E / #E0 | q*_min | q*_min / initial | dih_min | E_min | E_min / initial | V change | t/cut median [ms] | t/cut max [ms] | valid |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  std::printf("| initial  | %4d | %5d | 1.000 | %.4f | 1.00 | %.2f | %.3f | 1.00 | 0 | - | - | yes |\n", s0.nodes, s0.elements,
              s0.q_min, s0.dihedral_min_deg, s0.edge_min);
  nlohmann::ordered_json block = nlohmann::ordered_json::array();
  const double v0 = cutting::totalVolume(*uterus);
  for (auto method : {cutting::CutMethod::Hybrid, cutting::CutMethod::Standard}) {
    cutting::TetMesh m = *uterus;
    std::vector<double> times;
    bool valid = true;
    for (int c = 0; c < o.uterus_cuts; ++c) {
      const double f = (c + 1.0) / (o.uterus_cuts + 1.0);
      const Eigen::Vector3d p = lo + f * (hi - lo);
      const auto plane = *cutting::CutSurface::plane(p, normal);
      cutting::Cut3DOptions co;
      co.method = method;
      const auto t0 = std::chrono::steady_clock::now();
      auto r = cutting::cut3d(m, plane, co);
      times.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      if (!r.ok()) return fail(r.error());
      m = std::move(r->mesh);
      valid = valid && cutting::validate(m).ok() && cutting::countStraddling(m, p, normal, 1e-7) == 0;
    }
    const auto s = cutting::computeStats(m);
    const double dv = (cutting::totalVolume(m) - v0) / v0;
    std::printf("| %-8s | %4d | %5d | %.3f | %.4f | %.2f | %.2f | %.3f | %.2f | %.2e | %.3f | %.3f | %s |\n",
                cutting::cutMethodName(method), s.nodes, s.elements, double(s.elements) / s0.elements, s.q_min,
                s.q_min / s0.q_min, s.dihedral_min_deg, s.edge_min, s.edge_min / s0.edge_min, dv, median(times),
                *std::max_element(times.begin(), times.end()), valid ? "yes" : "NO");
    block.push_back({{"method", cutting::cutMethodName(method)},
                     {"stats", statsJson(s)},
                     {"element_ratio", double(s.elements) / s0.elements},
                     {"q_min_ratio", s.q_min / s0.q_min},
                     {"edge_min_ratio", s.edge_min / s0.edge_min},
                     {"volume_change", dv},
                     {"time_per_cut_median_ms", median(times)},
                     {"valid", valid}});
  }
  out["uterus_initial"] = statsJson(s0);
  out["uterus_successive_cuts"] = block;
  if (!o.json_path.empty()) {
    std::ofstream f(o.json_path);
    if (!f) return fail("cannot write '" + o.json_path + "'");
    f << out.dump(2) << "\n";
  }
  return 0;
}

}  // namespace hysim::tools
