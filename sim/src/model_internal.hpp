#pragma once
// Pieces of the model build shared by buildModel and the incremental update after a cut.
#include "hysim/sim/model.hpp"

namespace hysim::sim {

// Model::step_springs from the spring arrays, fixed flags and num_nodes (O(#S + #N)).
void buildStepSprings(Model& model);

}  // namespace hysim::sim
