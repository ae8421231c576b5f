#include "hysim/sim/tissue_update2d.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "model_internal.hpp"

namespace hysim::sim {

namespace {

using Row6 = Eigen::Matrix<double, 6, 1>;

Row6 monomials(double x, double y) {
  Row6 r;
  r << 1.0, x, y, x * x, x * y, y * y;
  return r;
}

Eigen::VectorXd lumpedMasses(const cutting::TriMesh& mesh, double density) {
  Eigen::VectorXd m = Eigen::VectorXd::Zero(mesh.numNodes());
  for (int f = 0; f < mesh.numTris(); ++f) {
    const double a = std::abs(cutting::triArea(mesh, f)) * density / 3.0;
    for (int k = 0; k < 3; ++k) m(mesh.F(f, k)) += a;
  }
  return m;
}

}  // namespace

Tissue2D buildTissue2D(const cutting::TriMesh& mesh, double young_modulus, double density) {
  Tissue2D t;
  t.mass = lumpedMasses(mesh, density);
  std::map<std::pair<int, int>, double> edgeArea;
  for (int f = 0; f < mesh.numTris(); ++f) {
    const double a = std::abs(cutting::triArea(mesh, f));
    for (int k = 0; k < 3; ++k) {
      auto e = std::minmax(mesh.F(f, k), mesh.F(f, (k + 1) % 3));
      edgeArea[{e.first, e.second}] += a;
    }
  }
  const int S = static_cast<int>(edgeArea.size());
  t.springs.resize(S, 2);
  t.rest_length.resize(S);
  t.stiffness.resize(S);
  int s = 0;
  for (const auto& [e, area] : edgeArea) {
    t.springs(s, 0) = e.first;
    t.springs(s, 1) = e.second;
    const double len = (mesh.X.row(e.first) - mesh.X.row(e.second)).norm();
    t.rest_length(s) = len;
    // Van Gelder: k = E * sum(area of incident triangles) / |s|^2.
    t.stiffness(s) = len > 0 ? young_modulus * area / (len * len) : 0.0;
    ++s;
  }
  return t;
}

Eigen::Matrix<double, 6, 1> massMoments2D(const cutting::TriMesh& mesh, const Eigen::VectorXd& mass,
                                          const Eigen::Vector2d& centre, double scale) {
  Row6 p = Row6::Zero();
  for (int i = 0; i < mesh.numNodes(); ++i)
    p += mass(i) * monomials((mesh.X(i, 0) - centre.x()) / scale, (mesh.X(i, 1) - centre.y()) / scale);
  return p;
}

Result<Eigen::VectorXd> updateMasses2D(const cutting::TriMesh& before, const Eigen::VectorXd& mass_before,
                                       const cutting::TriMesh& after, const cutting::TopologyChange& change,
                                       double density, const MassUpdateOptions& options, MassUpdateReport* report) {
  if (mass_before.size() != before.numNodes()) return Error{"updateMasses2D: mass_before has the wrong size"};
  if (static_cast<int>(change.node_old_to_new.size()) != before.numNodes())
    return Error{"updateMasses2D: topology change does not match the mesh before the cut"};
  const int N = after.numNodes();
  // Centre and scale (conditioning of A A^T: monomials up to degree 2 of mm coordinates).
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (int i = 0; i < before.numNodes(); ++i) centre += before.X.row(i).head<2>().transpose();
  centre /= std::max(1, before.numNodes());
  double scale = 0;
  for (int i = 0; i < before.numNodes(); ++i)
    scale = std::max(scale, (before.X.row(i).head<2>().transpose() - centre).norm());
  if (scale <= 0) scale = 1;
  const Row6 p = massMoments2D(before, mass_before, centre, scale);

  // Prior: previous masses carried over; touched nodes get area-lumped masses.
  const Eigen::VectorXd lumped = lumpedMasses(after, density);
  Eigen::VectorXd m0 = Eigen::VectorXd::Zero(N);
  std::vector<char> touched(N, 0), carried(N, 0);
  for (int o = 0; o < before.numNodes(); ++o) {
    const int n = change.node_old_to_new[o];
    if (n < 0) continue;
    if (carried[n]) touched[n] = 1;  // merged nodes
    m0(n) += mass_before(o);
    carried[n] = 1;
  }
  for (const auto& nn : change.new_nodes) touched[nn.id] = 1;
  for (int n : change.moved_nodes) touched[n] = 1;
  for (int f : change.added_elements)
    for (int k = 0; k < 3; ++k) touched[after.F(f, k)] = 1;
  for (int n = 0; n < N; ++n)
    if (touched[n] || !carried[n]) {
      touched[n] = 1;
      m0(n) = lumped(n);
    }
  std::vector<int> U;
  for (int n = 0; n < N; ++n)
    if (touched[n] && m0(n) > 0) U.push_back(n);
  MassUpdateReport rep;
  if (U.size() < 12) {
    rep.global = true;
    U.clear();
    for (int n = 0; n < N; ++n)
      if (m0(n) > 0) U.push_back(n);
  }
  Eigen::Matrix<double, 6, Eigen::Dynamic> A(6, N);
  for (int i = 0; i < N; ++i) A.col(i) = monomials((after.X(i, 0) - centre.x()) / scale, (after.X(i, 1) - centre.y()) / scale);

  Eigen::VectorXd m = m0;
  std::vector<char> atFloor(N, 0);
  for (int iter = 0; iter < options.max_active_set_iterations; ++iter) {
    std::vector<int> free;
    for (int n : U)
      if (!atFloor[n]) free.push_back(n);
    if (free.size() < 6) break;
    // Masses outside `free` are fixed at their current values.
    Eigen::VectorXd mfix = m;
    for (int n : free) mfix(n) = m0(n);
    const Row6 r = p - A * mfix;
    Eigen::MatrixXd Af(6, free.size());
    for (std::size_t k = 0; k < free.size(); ++k) Af.col(static_cast<int>(k)) = A.col(free[k]);
    const Eigen::Matrix<double, 6, 6> B = gramFixedOrder<6>(Af);
    Eigen::CompleteOrthogonalDecomposition<Eigen::Matrix<double, 6, 6>> cod(B);
    if (cod.rank() < 6 && !rep.global) {
      // Local nodes do not determine all six moments: use every node.
      rep.global = true;
      U.clear();
      for (int n = 0; n < N; ++n)
        if (m0(n) > 0) U.push_back(n);
      std::fill(atFloor.begin(), atFloor.end(), 0);
      m = m0;
      --iter;
      continue;
    }
    const Row6 mt = cod.solve(r);
    const Eigen::VectorXd delta = Af.transpose() * mt;
    m = mfix;
    bool anyBelow = false;
    for (std::size_t k = 0; k < free.size(); ++k) {
      const int n = free[k];
      m(n) = m0(n) + delta(static_cast<int>(k));
      const double floor = options.floor_fraction * m0(n);
      if (m(n) < floor) {
        m(n) = floor;
        atFloor[n] = 1;
        anyBelow = true;
      }
    }
    if (!anyBelow) break;
  }
  for (int n = 0; n < N; ++n) rep.clamped += atFloor[n];
  rep.unknowns = static_cast<int>(U.size());
  const Row6 res = A * m - p;
  rep.moment_residual = res.cwiseAbs().maxCoeff() / std::max(p.cwiseAbs().maxCoeff(), 1e-300);
  if (report) *report = rep;
  return m;
}

Result<Tissue2D> updateTissue2D(const cutting::TriMesh& before, const Tissue2D& tissue_before,
                                const cutting::TriMesh& after, const cutting::TopologyChange& change,
                                double young_modulus, double density, const MassUpdateOptions& options,
                                MassUpdateReport* report) {
  auto m = updateMasses2D(before, tissue_before.mass, after, change, density, options, report);
  if (!m.ok()) return Error{m.error()};
  Tissue2D t = buildTissue2D(after, young_modulus, density);
  t.mass = std::move(*m);
  return t;
}

}  // namespace hysim::sim
