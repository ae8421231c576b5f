#include "cut_methods.hpp"

#include <chrono>
#include <cmath>
#include <numbers>

#include "fields.hpp"
#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::engine::accuracy {
namespace {

using nlohmann::json;

// The mesh without the pieces no anchored node holds (they would fall away), nodes
// renumbered; `dropped_volume` receives their volume.
cutting::TetMesh keepAnchoredPieces(const cutting::TetMesh& mesh, const Scene& scene, double& dropped_volume) {
  const cutting::Components3D comp = cutting::tetComponents(mesh, anchoredNodes(scene, mesh));
  std::vector<int> new_index(mesh.numNodes(), -1), tets;
  dropped_volume = 0.0;
  for (int c = 0; c < comp.count; ++c)
    if (comp.free[c]) dropped_volume += comp.volume[c];
  for (int t = 0; t < mesh.numTets(); ++t)
    if (!comp.free[comp.label[t]]) tets.push_back(t);
  cutting::TetMesh out;
  int n = 0;
  for (int t : tets)
    for (int k = 0; k < 4; ++k)
      if (new_index[mesh.T(t, k)] < 0) new_index[mesh.T(t, k)] = n++;
  out.X.resize(n, 3);
  for (int i = 0; i < mesh.numNodes(); ++i)
    if (new_index[i] >= 0) out.X.row(new_index[i]) = mesh.X.row(i);
  out.T.resize(static_cast<int>(tets.size()), 4);
  out.material.resize(static_cast<int>(tets.size()));
  for (size_t k = 0; k < tets.size(); ++k) {
    for (int j = 0; j < 4; ++j) out.T(static_cast<int>(k), j) = new_index[mesh.T(tets[k], j)];
    out.material[static_cast<int>(k)] = mesh.material[tets[k]];
  }
  return out;
}

struct MethodState {
  cutting::CutMethod method;
  cutting::TetMesh mesh;
  double cut_ms = 0.0, dropped_volume = 0.0;
  bool failed = false;
  std::string error;
};

void applyCut(MethodState& m, int i, const Scene& scene) {
  Eigen::Vector3d p, n;
  cutPlane(i, p, n);
  auto surface = cutting::CutSurface::plane(p, n);
  cutting::Cut3DOptions o;
  o.method = m.method;
  const auto t0 = std::chrono::steady_clock::now();
  auto cut = cutting::cut3d(m.mesh, *surface, o);
  m.cut_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (!cut.ok()) {
    m.failed = true;
    m.error = cut.error();
    return;
  }
  double dropped = 0.0;
  m.mesh = keepAnchoredPieces(cut->mesh, scene, dropped);
  m.dropped_volume += dropped;
}

json checkpoint(const MethodState& m, const AccuracyCase& organ, const Scene& scene, double volume0, double crit0) {
  json j;
  const cutting::MeshStats st = cutting::computeStats(m.mesh);
  j["elements"] = m.mesh.numTets();
  j["q_min"] = st.q_min;
  j["edge_min_mm"] = st.edge_min;
  sim::ModelOptions o;
  o.max_substeps = 0;
  AccuracyCase c = organ;
  c.mesh = m.mesh;
  c.fixed = anchoredNodes(scene, m.mesh);
  c.indenter.clear();
  auto model = sim::buildModel(c.mesh, c.materials, c.fixed, o);
  if (model.ok()) {
    j["critical_dt_ms"] = model->critical_dt * 1e3;
    j["critical_dt_ratio"] = model->critical_dt / crit0;
    j["substeps_at_1ms"] = std::ceil(1e-3 / (o.stability_safety * model->critical_dt));  // may exceed an int
  }
  j["cut_ms_total"] = m.cut_ms;
  j["volume_error"] = std::abs(cutting::totalVolume(m.mesh) + m.dropped_volume - volume0) / volume0;
  j["volume_dropped_mm3"] = m.dropped_volume;
  return j;
}

// Probes closer to a cut than this see either side's displacement: they are left out.
constexpr double kNearCutMm = 3.0;

std::vector<std::uint8_t> awayFromCuts(const cutting::TetMesh& mesh, int cuts, double distance) {
  std::vector<std::uint8_t> away(mesh.numNodes(), 1);
  for (int i = 0; i < cuts; ++i) {
    Eigen::Vector3d p, n;
    cutPlane(i, p, n);
    for (int k = 0; k < mesh.numNodes(); ++k)
      if (std::abs((mesh.X.row(k).transpose() - p).dot(n)) < distance) away[k] = 0;
  }
  return away;
}

}  // namespace

void cutPlane(int i, Eigen::Vector3d& point, Eigen::Vector3d& normal) {
  // Slices 3 mm apart across the organ (as a resection takes them), each tilted a few degrees
  // differently, so that no two are parallel and the mesh is not aligned with any.
  normal = Eigen::Vector3d(1.0, 0.06 * std::sin(1.3 * i), 0.06 * std::cos(0.9 * i)).normalized();
  const double order[20] = {9, 4, 14, 6, 11, 2, 16, 7, 12, 0, 18, 5, 13, 3, 15, 8, 10, 1, 17, 19};
  point = Eigen::Vector3d(-28.5 + 3.0 * order[i % 20], -9.0, 4.0);
}

json cutMethodStudy(const AccuracyCase& organ, const Scene& scene, const std::vector<int>& checkpoints) {
  const double volume0 = cutting::totalVolume(organ.mesh);
  sim::ModelOptions o;
  o.max_substeps = 0;
  auto model0 = sim::buildModel(organ.mesh, organ.materials, organ.fixed, o);
  const double crit0 = model0.ok() ? model0->critical_dt : 1.0;
  json out;
  out["initial"] = {{"elements", organ.mesh.numTets()}, {"critical_dt_ms", crit0 * 1e3}};
  out["probes_left_out_within_mm"] = kNearCutMm;
  const cutting::CutMethod methods[] = {cutting::CutMethod::Hybrid, cutting::CutMethod::Standard,
                                        cutting::CutMethod::Snap, cutting::CutMethod::Delete};
  std::vector<MethodState> states;
  for (cutting::CutMethod m : methods) {
    MethodState st;
    st.method = m;
    st.mesh = organ.mesh;
    states.push_back(std::move(st));
  }
  json rows = json::array();
  int done = 0;
  for (int cp : checkpoints) {
    for (; done < cp; ++done)
      for (MethodState& m : states)
        if (!m.failed) applyCut(m, done, scene);
    // The geometrically exact body: standard subdivision moves no node and deletes nothing.
    AccuracyCase exact = organ;
    exact.mesh = states[1].mesh;
    exact.fixed = anchoredNodes(scene, exact.mesh);
    // Slivers of standard subdivision make its system ill-conditioned: a looser tolerance.
    auto u_exact = springStatic(exact, true, 1e-5);
    if (!u_exact.ok()) out["exact_body_error_at_" + std::to_string(cp)] = u_exact.error();
    const std::vector<std::uint8_t> away = awayFromCuts(organ.mesh, cp, kNearCutMm);
    for (const MethodState& m : states) {
      json j = m.failed ? json{{"error", m.error}} : checkpoint(m, organ, scene, volume0, crit0);
      j["method"] = cutting::cutMethodName(m.method);
      j["cuts"] = cp;
      if (!m.failed && u_exact.ok()) {
        AccuracyCase c = organ;
        c.mesh = m.mesh;
        c.fixed = anchoredNodes(scene, m.mesh);
        auto u = springStatic(c, true, 1e-5);
        if (u.ok()) {
          // Both fields at the uncut organ's nodes.
          const Eigen::MatrixX3d a = interpolateAtNodes(m.mesh, *u, organ.mesh);
          const Eigen::MatrixX3d b = interpolateAtNodes(exact.mesh, *u_exact, organ.mesh);
          j["sag_error_vs_exact_body"] = relativeFieldError(a, b, &away);
        }
      }
      rows.push_back(j);
    }
  }
  out["rows"] = rows;
  return out;
}

}  // namespace hysim::engine::accuracy
