#pragma once
// Pieces of the model build shared by buildModel and the incremental update after a cut.
#include "hysim/sim/model.hpp"

namespace hysim::sim {

// Model::step_springs from the spring arrays, fixed flags and num_nodes (O(#S + #N)).
void buildStepSprings(Model& model);

// The ten monomials up to second order of a point (1, x, y, z, x², y², z², xy, yz, zx):
// the mass moments the tissue updates after a cut keep.
using Row10 = Eigen::Matrix<double, 10, 1>;
inline Row10 monomials(const Eigen::Vector3d& p) {
  Row10 r;
  r << 1.0, p.x(), p.y(), p.z(), p.x() * p.x(), p.y() * p.y(), p.z() * p.z(), p.x() * p.y(), p.y() * p.z(),
      p.z() * p.x();
  return r;
}

}  // namespace hysim::sim
