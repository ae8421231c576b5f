#pragma once
// Static equilibrium of the spring network (reference R1 of the accuracy study): the
// positions where spring forces balance gravity and the given external forces, anchored
// nodes held where the state puts them (so a prescribed displacement is an anchored node
// moved before the solve). No integrator is involved, so a step's error against it is
// the integrator's and solver's alone.
#include "hysim/sim/model.hpp"

namespace hysim::sim {

struct StaticSolveOptions {
  int max_iterations = 100;
  // stop when |net force on free nodes| <= tolerance * the larger of |gravity + external load|
  // and |the anchors' reactions|
  double tolerance = 1e-9;
};

struct StaticSolveResult {
  int iterations = 0;
  double residual = 0.0;  // final |net force on free nodes| / |load|
  bool converged = false;
};

// Newton with a backtracking line search on the total energy; where compressed springs make
// the Hessian indefinite, each spring's block keeps its transverse part only when stretched
// (positive definite, so the step still descends). Starts from state.x; writes the equilibrium into state.x, zeroes state.v.
StaticSolveResult solveStatic(const Model& model, State& state, const NodeVectors* external_force = nullptr,
                              const StaticSolveOptions& options = {});

// Net force on each node, #N x 3: gravity + external + springs on free nodes (damping
// ignored); the springs' pull alone on anchored nodes (what the anchor holds against).
NodeVectors staticForces(const Model& model, const NodeVectors& x, const NodeVectors* external_force);

}  // namespace hysim::sim
