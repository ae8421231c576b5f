#include "hysim/sim/static_solve.hpp"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <vector>

namespace hysim::sim {
namespace {

// Total potential energy: springs minus the work of gravity and the external load.
double potentialEnergy(const Model& m, const NodeVectors& x, const NodeVectors* ext) {
  double e = 0.0;
  for (int s = 0; s < m.springs.rows(); ++s) {
    const double stretch = (x.row(m.springs(s, 1)) - x.row(m.springs(s, 0))).norm() - m.rest_length[s];
    e += 0.5 * m.stiffness[s] * stretch * stretch;
  }
  for (int i = 0; i < m.num_nodes; ++i) {
    if (m.fixed[i]) continue;
    e -= m.mass[i] * x.row(i).dot(m.options.gravity.transpose());
    if (ext != nullptr) e -= x.row(i).dot(ext->row(i));
  }
  return e;
}

double loadNorm(const Model& m, const NodeVectors* ext) {
  double sum = 0.0;
  for (int i = 0; i < m.num_nodes; ++i) {
    if (m.fixed[i]) continue;
    Eigen::RowVector3d f = m.mass[i] * m.options.gravity.transpose();
    if (ext != nullptr) f += ext->row(i);
    sum += f.squaredNorm();
  }
  return std::sqrt(sum);
}

double freeResidual(const Model& m, const NodeVectors& x, const NodeVectors* ext, const std::vector<int>& free_nodes) {
  const NodeVectors f = staticForces(m, x, ext);
  double sum = 0.0;
  for (int i : free_nodes) sum += f.row(i).squaredNorm();
  return std::sqrt(sum);
}

double reactionNorm(const Model& m, const NodeVectors& f) {
  double sum = 0.0;
  for (int i = 0; i < m.num_nodes; ++i)
    if (m.fixed[i]) sum += f.row(i).squaredNorm();
  return std::sqrt(sum);
}

// Stiffness matrix over free nodes (3 rows per free node): each spring's block
// k (u u^T + (1 - L/l) (I - u u^T)), its transverse part clamped at 0 when `project` so that
// the block is positive semi-definite.
Eigen::SparseMatrix<double> springHessian(const Model& m, const NodeVectors& x, const std::vector<int>& free_index,
                                          int num_free, bool project) {
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(36 * static_cast<size_t>(m.springs.rows()));
  for (int s = 0; s < m.springs.rows(); ++s) {
    const int a = m.springs(s, 0), b = m.springs(s, 1);
    Eigen::Vector3d d = (x.row(b) - x.row(a)).transpose();
    const double len = d.norm();
    if (!(len > 0.0)) continue;
    const Eigen::Vector3d u = d / len;
    const double transverse = project ? std::max(0.0, 1.0 - m.rest_length[s] / len) : 1.0 - m.rest_length[s] / len;
    const Eigen::Matrix3d block =
        m.stiffness[s] * (u * u.transpose() + transverse * (Eigen::Matrix3d::Identity() - u * u.transpose()));
    const int ends[2] = {free_index[a], free_index[b]};
    for (int p = 0; p < 2; ++p) {
      for (int q = 0; q < 2; ++q) {
        if (ends[p] < 0 || ends[q] < 0) continue;
        const double sign = p == q ? 1.0 : -1.0;
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) trip.emplace_back(3 * ends[p] + r, 3 * ends[q] + c, sign * block(r, c));
      }
    }
  }
  Eigen::SparseMatrix<double> H(3 * num_free, 3 * num_free);
  H.setFromTriplets(trip.begin(), trip.end());
  return H;
}

}  // namespace

NodeVectors staticForces(const Model& m, const NodeVectors& x, const NodeVectors* ext) {
  NodeVectors f = NodeVectors::Zero(m.num_nodes, 3);
  for (int i = 0; i < m.num_nodes; ++i) {
    if (m.fixed[i]) continue;
    f.row(i) = m.mass[i] * m.options.gravity.transpose();
    if (ext != nullptr) f.row(i) += ext->row(i);
  }
  for (int s = 0; s < m.springs.rows(); ++s) {
    const int a = m.springs(s, 0), b = m.springs(s, 1);
    Eigen::RowVector3d d = x.row(b) - x.row(a);
    const double len = d.norm();
    if (!(len > 0.0)) continue;
    const Eigen::RowVector3d force = m.stiffness[s] * (len - m.rest_length[s]) / len * d;
    f.row(a) += force;
    f.row(b) -= force;
  }
  return f;
}

StaticSolveResult solveStatic(const Model& m, State& state, const NodeVectors* ext, const StaticSolveOptions& options) {
  std::vector<int> free_index(m.num_nodes, -1), free_nodes;
  for (int i = 0; i < m.num_nodes; ++i) {
    if (m.fixed[i]) continue;
    free_index[i] = static_cast<int>(free_nodes.size());
    free_nodes.push_back(i);
  }
  const int nf = static_cast<int>(free_nodes.size());
  StaticSolveResult result;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  for (result.iterations = 0; result.iterations <= options.max_iterations; ++result.iterations) {
    const NodeVectors f = staticForces(m, state.x, ext);
    Eigen::VectorXd g(3 * nf);
    for (int k = 0; k < nf; ++k) g.segment<3>(3 * k) = f.row(free_nodes[k]).transpose();
    // Relative to the load, or to the anchors' reactions when the load is a prescribed move.
    const double scale = std::max({loadNorm(m, ext), reactionNorm(m, f), 1e-300});
    result.residual = g.norm() / scale;
    if (result.residual <= options.tolerance) {
      result.converged = true;
      break;
    }
    if (result.iterations == options.max_iterations) break;
    // The exact Hessian converges quadratically; where compressed springs make it indefinite,
    // the projected one still descends.
    Eigen::SparseMatrix<double> H = springHessian(m, state.x, free_index, nf, false);
    if (result.iterations == 0) ldlt.analyzePattern(H);
    ldlt.factorize(H);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) {
      H = springHessian(m, state.x, free_index, nf, true);
      ldlt.factorize(H);
    }
    if (ldlt.info() != Eigen::Success) break;
    const Eigen::VectorXd dx = ldlt.solve(g);  // H dx = net force: the Newton step
    const double e0 = potentialEnergy(m, state.x, ext);
    const NodeVectors x0 = state.x;
    double t = 1.0;
    for (int ls = 0; ls < 30; ++ls, t *= 0.5) {
      for (int k = 0; k < nf; ++k) state.x.row(free_nodes[k]) = x0.row(free_nodes[k]) + t * dx.segment<3>(3 * k).transpose();
      if (potentialEnergy(m, state.x, ext) <= e0 + 1e-12 * std::abs(e0)) break;
      // Near the solution the energy's change drowns in rounding: a smaller residual decides.
      if (freeResidual(m, state.x, ext, free_nodes) < g.norm()) break;
    }
  }
  state.v.setZero();
  return result;
}

}  // namespace hysim::sim
