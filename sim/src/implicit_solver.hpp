#pragma once
// Prefactored system of the implicit (backward) Euler integrator.
//
// Backward Euler for springs is solved as in Liu et al., "Fast simulation of mass-spring
// systems" (2013): the step minimises 1/(2h^2)|x - y|_M^2 + E_springs(x); alternating a local
// step (each spring's rest-length direction d_s from the current iterate) with a global step
// (one sparse solve with the constant matrix A = (1/h^2 + alpha/h) M + L_k + L_c/h) converges
// to the backward Euler solution. A is factorised once per topology ("precompute once, solve
// each frame"), so the step itself is two triangular solves per iteration.
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <memory>

#include "hysim/sim/model.hpp"

namespace hysim::sim {

class ImplicitSolver {
 public:
  static Result<std::shared_ptr<const ImplicitSolver>> create(const Model& model);

  int numFree() const { return static_cast<int>(free_nodes_.size()); }
  const std::vector<int>& freeNodes() const { return free_nodes_; }   // #F model node ids
  const std::vector<int>& freeIndex() const { return free_index_; }   // #N -> free index or -1

  // x (#F x 3, in/out): right-hand side in, solution out. tmp: #F x 3 workspace.
  // Allocates nothing.
  template <class DstBlock, class TmpBlock>
  void solveInPlace(DstBlock&& x, TmpBlock&& tmp) const {
    const auto& perm = ldlt_.permutationP().indices();
    const int nf = numFree();
    for (int i = 0; i < nf; ++i) tmp.row(perm[i]) = x.row(i);
    ldlt_.matrixL().solveInPlace(tmp);
    for (int i = 0; i < nf; ++i) tmp.row(i) *= inv_diag_[i];
    ldlt_.matrixU().solveInPlace(tmp);
    for (int i = 0; i < nf; ++i) x.row(i) = tmp.row(perm[i]);
  }

  double massScale() const { return mass_scale_; }  // 1/h^2 + alpha/h

  // A spring between a free node and an anchored one: the anchored end's position enters
  // the right-hand side (-A_fc x_c) with weight w = k + c/h.
  struct FixedLink {
    int free;    // free index of the moving end
    int node;    // model node id of the anchored end
    double w;
  };
  const std::vector<FixedLink>& fixedLinks() const { return fixed_links_; }

 private:
  std::vector<int> free_nodes_;
  std::vector<int> free_index_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::AMDOrdering<int>> ldlt_;
  Eigen::VectorXd inv_diag_;
  std::vector<FixedLink> fixed_links_;
  double mass_scale_ = 0.0;
};

}  // namespace hysim::sim
