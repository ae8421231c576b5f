#pragma once
// Pieces of the model build shared by buildModel and the incremental update after a cut,
// and the XPBD step that step() calls.
#include <algorithm>
#include <functional>
#include <vector>

#include "hysim/cutting/mesh.hpp"
#include "hysim/sim/model.hpp"
#include "hysim/sim/tissue_update3d.hpp"

namespace hysim::sim {

// Model::step_springs from the spring arrays, fixed flags and num_nodes (O(#S + #N)).
void buildStepSprings(Model& model);
// Its second part: node_offset sized #N+1 and holding at [i] node i's number of step springs
// (at [#N] 0), `count` the number of step springs.
void fillStepSprings(Model& model, int count);

// One fixed step of the XPBD integrator (step_xpbd.cpp), called by step().
void stepXpbd(const Model& model, State& state, const StepInput& input);

// Whether selective mass scaling may hold the automatic substeps at max_substeps: symplectic
// Euler's count is automatic and capped. Never for implicit Euler (no substeps: the mass would
// only add weight) or XPBD (stable at any substep).
inline bool massScalingApplies(const ModelOptions& o) {
  return o.integrator == Integrator::SymplecticEuler && o.substeps <= 0 && o.max_substeps > 0;
}
// Model::substeps and substep, given the count symplectic Euler's stability limit asks for.
// XPBD: options.xpbd_substeps, or that count capped at max_substeps when it is 0.
inline void setSubsteps(Model& m, int stability_substeps) {
  const ModelOptions& o = m.options;
  const int wanted = o.integrator == Integrator::Xpbd ? o.xpbd_substeps : o.substeps;
  m.substeps = wanted > 0 ? wanted : stability_substeps;
  if (wanted <= 0 && o.max_substeps > 0) m.substeps = std::min(m.substeps, o.max_substeps);
  m.substep = o.dt / m.substeps;
}

// The largest eigenvalue of the symmetric tridiagonal matrix with diagonal `diag` and
// subdiagonal `sub` (size diag.size() - 1), to a few units in the last place of the matrix's
// largest entry; NaN when it does not settle (the caller then asks a dense solver). Cheaper
// than a full eigenvalue solve; its value can differ from one in those last bits.
double topTridiagonalEigenvalue(const Eigen::VectorXd& diag, const Eigen::VectorXd& sub);

// A Aᵀ (K x K, K fixed) summed column by column in index order, the same bits on every
// machine. (Eigen's general product splits a long inner dimension into blocks sized from the
// CPU's cache sizes, so its rounding, and with it the masses after a cut and the whole run
// that follows, differed between machines: a 48 KiB L1 gave another default run than 32 KiB.)
template <int K, class Mat>
Eigen::Matrix<double, K, K> gramFixedOrder(const Mat& A) {
  Eigen::Matrix<double, K, K> B = Eigen::Matrix<double, K, K>::Zero();
  for (Eigen::Index j = 0; j < A.cols(); ++j)
    for (int c = 0; c < K; ++c) {
      const double ac = A(c, j);
      for (int r = c; r < K; ++r) B(r, c) += A(r, j) * ac;
    }
  for (int c = 0; c < K; ++c)
    for (int r = c + 1; r < K; ++r) B(c, r) = B(r, c);
  return B;
}

// The ten monomials up to second order of a point (1, x, y, z, x², y², z², xy, yz, zx):
// the mass moments the tissue updates after a cut keep.
using Row10 = Eigen::Matrix<double, 10, 1>;
inline Row10 monomials(const Eigen::Vector3d& p) {
  Row10 r;
  r << 1.0, p.x(), p.y(), p.z(), p.x() * p.x(), p.y() * p.y(), p.z() * p.z(), p.x() * p.y(), p.y() * p.z(),
      p.z() * p.x();
  return r;
}

// The smallest correction of the masses of `unknown` (positions X, monomials about `centre`,
// divided by `scale`) that brings moments(mass) to `target`, no mass below floor_fraction of
// its value on entry: an active set, clamped masses fixed at their floor and the rest solved
// again. Returns the number of unknowns clamped. Shared by updateMasses3D (moments of the
// whole mesh) and updateModelAfterCut3D (moments of the nodes near the cut).
int correctMassMoments(const cutting::Positions& X, const std::vector<int>& unknown, const Row10& target,
                       const Eigen::Vector3d& centre, double scale, const MassUpdate3DOptions& options,
                       const std::function<Row10(const Eigen::VectorXd&)>& moments, Eigen::VectorXd& mass);

}  // namespace hysim::sim
