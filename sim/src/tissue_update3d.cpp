#include "hysim/sim/tissue_update3d.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <string>

#include "model_internal.hpp"

namespace hysim::sim {

Eigen::Matrix<double, 10, 1> massMoments3D(const cutting::Positions& X, const Eigen::VectorXd& mass,
                                           const Eigen::Vector3d& centre, double scale) {
  Row10 p = Row10::Zero();
  for (Eigen::Index i = 0; i < X.rows(); ++i)
    if (mass[i] != 0) p += mass[i] * monomials((X.row(i).transpose() - centre) / scale);
  return p;
}

Eigen::VectorXd lumpedMasses3D(const cutting::TetMesh& mesh, const Eigen::VectorXd& density) {
  Eigen::VectorXd m = Eigen::VectorXd::Zero(mesh.numNodes());
  for (int t = 0; t < mesh.numTets(); ++t) {
    const double v = std::abs(cutting::tetVolume(mesh, t));
    for (int k = 0; k < 4; ++k) m[mesh.T(t, k)] += 0.25 * density[t] * v;
  }
  return m;
}

Result<Eigen::VectorXd> updateMasses3D(const cutting::TetMesh& before, const Eigen::VectorXd& mass_before,
                                       const cutting::TetMesh& after, const cutting::TopologyChange& change,
                                       const Eigen::VectorXd& density_after, const MassUpdate3DOptions& options,
                                       MassUpdate3DReport* report) {
  const int N0 = before.numNodes(), N1 = after.numNodes();
  if (mass_before.size() != N0) return Error{"updateMasses3D: mass_before size differs from the mesh"};
  if (density_after.size() != after.numTets()) return Error{"updateMasses3D: density size differs from #T"};
  if (static_cast<int>(change.node_old_to_new.size()) != N0 || change.new_num_nodes != N1)
    return Error{"updateMasses3D: the change does not match the meshes"};
  const Eigen::Vector3d lo = before.X.colwise().minCoeff().transpose(), hi = before.X.colwise().maxCoeff().transpose();
  const Eigen::Vector3d centre = 0.5 * (lo + hi);
  const double scale = std::max(0.5 * (hi - lo).maxCoeff(), 1e-12);
  const Row10 target = massMoments3D(before.X, mass_before, centre, scale);

  // Prior: carried-over masses; touched nodes get the lumped mass of the new mesh.
  Eigen::VectorXd m = Eigen::VectorXd::Zero(N1);
  for (int i = 0; i < N0; ++i)
    if (change.node_old_to_new[i] >= 0) m[change.node_old_to_new[i]] = mass_before[i];
  std::vector<std::uint8_t> touched(N1, 0);
  for (const auto& nn : change.new_nodes) touched[nn.id] = 1;
  for (int n : change.moved_nodes) touched[n] = 1;
  for (int n : change.cut_nodes) touched[n] = 1;
  for (int t : change.added_elements)
    for (int k = 0; k < 4; ++k) touched[after.T(t, k)] = 1;
  // Nodes that lost elements (deletion) are touched too.
  if (!change.removed_elements.empty() && change.added_elements.empty())
    for (int t : change.removed_elements)
      for (int k = 0; k < 4; ++k) {
        const int n = change.node_old_to_new[before.T(t, k)];
        if (n >= 0) touched[n] = 1;
      }
  // Nodes of a cut lie near one surface, where the second moments across it are badly
  // conditioned: two rings of neighbours join the unknowns.
  for (int ring = 0; ring < 2; ++ring) {
    std::vector<std::uint8_t> grown = touched;
    for (int t = 0; t < after.numTets(); ++t) {
      const bool any = touched[after.T(t, 0)] || touched[after.T(t, 1)] || touched[after.T(t, 2)] || touched[after.T(t, 3)];
      if (any)
        for (int k = 0; k < 4; ++k) grown[after.T(t, k)] = 1;
    }
    touched.swap(grown);
  }
  const Eigen::VectorXd lumped = lumpedMasses3D(after, density_after);
  std::vector<int> unknown;
  for (int i = 0; i < N1; ++i)
    if (touched[i] && lumped[i] > 0) {
      m[i] = lumped[i];
      unknown.push_back(i);
    }
  MassUpdate3DReport rep;
  if (unknown.size() < 20) {
    rep.global = true;
    unknown.clear();
    for (int i = 0; i < N1; ++i)
      if (lumped[i] > 0) unknown.push_back(i);
  }
  auto moments = [&](const Eigen::VectorXd& mass) { return massMoments3D(after.X, mass, centre, scale); };
  const int clamped = correctMassMoments(after.X, unknown, target, centre, scale, options, moments, m);
  const Row10 res = target - massMoments3D(after.X, m, centre, scale);
  rep.unknowns = static_cast<int>(unknown.size());
  rep.clamped = clamped;
  rep.moment_residual = res.cwiseAbs().maxCoeff() / std::max(target.cwiseAbs().maxCoeff(), 1e-300);
  for (int i = 0; i < N1; ++i)
    if (!(m[i] >= 0) || !std::isfinite(m[i])) return Error{"updateMasses3D: non-finite or negative mass"};
  if (report) *report = rep;
  return m;
}

int correctMassMoments(const cutting::Positions& X, const std::vector<int>& unknown, const Row10& target,
                       const Eigen::Vector3d& centre, double scale, const MassUpdate3DOptions& options,
                       const std::function<Row10(const Eigen::VectorXd&)>& moments, Eigen::VectorXd& mass) {
  const Eigen::VectorXd prior = mass;
  std::vector<std::uint8_t> clamped(static_cast<size_t>(mass.size()), 0);
  for (int iter = 0; iter < options.max_active_set_iterations; ++iter) {
    const Row10 r = target - moments(mass);
    std::vector<int> active;
    for (int i : unknown)
      if (!clamped[i]) active.push_back(i);
    if (active.empty()) break;
    Eigen::Matrix<double, 10, Eigen::Dynamic> A(10, static_cast<Eigen::Index>(active.size()));
    for (size_t j = 0; j < active.size(); ++j)
      A.col(static_cast<Eigen::Index>(j)) = monomials((X.row(active[j]).transpose() - centre) / scale);
    const Eigen::Matrix<double, 10, 10> B = gramFixedOrder<10>(A);
    const Row10 y = Eigen::CompleteOrthogonalDecomposition<Eigen::Matrix<double, 10, 10>>(B).solve(r);
    const Eigen::VectorXd dm = A.transpose() * y;
    bool any = false;
    for (size_t j = 0; j < active.size(); ++j) {
      const int i = active[j];
      const double floor = options.floor_fraction * prior[i];
      if (mass[i] + dm[static_cast<Eigen::Index>(j)] < floor) {
        mass[i] = floor;
        clamped[i] = 1;
        any = true;
      }
    }
    if (!any) {
      for (size_t j = 0; j < active.size(); ++j) mass[active[j]] += dm[static_cast<Eigen::Index>(j)];
      break;
    }
  }
  int count = 0;
  for (int i : unknown) count += clamped[i];
  return count;
}

State remapState3D(const State& before, const cutting::TopologyChange& change) {
  State s;
  const int N1 = change.new_num_nodes;
  s.x = NodeVectors::Zero(N1, 3);
  s.v = NodeVectors::Zero(N1, 3);
  for (int i = 0; i < change.old_num_nodes; ++i) {
    const int j = change.node_old_to_new[i];
    if (j < 0) continue;
    s.x.row(j) = before.x.row(i);
    s.v.row(j) = before.v.row(i);
  }
  for (const auto& nn : change.new_nodes) {
    Eigen::RowVector3d x = Eigen::RowVector3d::Zero(), v = Eigen::RowVector3d::Zero();
    for (int k = 0; k < nn.num_parents; ++k) {
      x += nn.weights[k] * before.x.row(nn.parents[k]);
      v += nn.weights[k] * before.v.row(nn.parents[k]);
    }
    s.x.row(nn.id) = x;
    s.v.row(nn.id) = v;
  }
  s.f = NodeVectors::Zero(N1, 3);
  s.scratch0 = NodeVectors::Zero(N1, 3);
  s.scratch1 = NodeVectors::Zero(N1, 3);
  s.scratch2 = NodeVectors::Zero(N1, 3);
  s.solve0 = Eigen::MatrixX3d::Zero(N1, 3);
  s.solve1 = Eigen::MatrixX3d::Zero(N1, 3);
  s.steps = before.steps;
  s.time = before.time;
  s.warnings = before.warnings;
  s.diverged = before.diverged;
  return s;
}

Result<Model> updateModel3D(const Model& before, const cutting::TetMesh& mesh_before,
                            const cutting::TetMesh& mesh_after, const cutting::TopologyChange& change,
                            const MassUpdate3DOptions& options, MassUpdate3DReport* report) {
  // Anchored nodes carried over (with their duplicates).
  std::vector<int> fixed;
  std::vector<std::uint8_t> wasFixed(mesh_before.numNodes(), 0);
  for (int i = 0; i < mesh_before.numNodes() && i < static_cast<int>(before.fixed.size()); ++i)
    if (before.fixed[i] && before.mass.size() > i && before.mass[i] > 0) {
      wasFixed[i] = 1;
      if (change.node_old_to_new[i] >= 0) fixed.push_back(change.node_old_to_new[i]);
    }
  for (const auto& nn : change.new_nodes)
    if (nn.duplicate && nn.num_parents == 1 && wasFixed[nn.parents[0]]) fixed.push_back(nn.id);
  auto model = buildModel(mesh_after, before.materials, fixed, before.options);
  if (!model.ok()) return Error{"updateModel3D: " + model.error()};
  Eigen::VectorXd density(mesh_after.numTets());
  for (int t = 0; t < mesh_after.numTets(); ++t) {
    density[t] = 0;
    for (const auto& mat : before.materials)
      if (mat.label == mesh_after.material(t)) density[t] = mat.density_g_mm3;
  }
  auto mass = updateMasses3D(mesh_before, before.mass, mesh_after, change, density, options, report);
  if (!mass.ok()) return Error{mass.error()};
  Model& m = *model;
  m.mass = *mass;
  for (int i = 0; i < m.num_nodes; ++i) {
    if (m.mass[i] <= 0.0) m.fixed[i] = 1;
    m.inv_mass[i] = m.fixed[i] ? 0.0 : 1.0 / m.mass[i];
  }
  return model;
}

}  // namespace hysim::sim
