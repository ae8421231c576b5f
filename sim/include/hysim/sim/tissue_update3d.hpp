#pragma once
// Tissue update after a 3D cut (cutting::cut3d): node masses that keep the ten mass moments
// up to second order, p = sum_i m_i (1, x, y, z, x^2, y^2, z^2, xy, yz, zx)_i (Deussen et
// al., as in section 3 of the paper), with the smallest correction to the previous masses,
// all positive; Van Gelder springs k = E * sum(volume of incident tets) / |e|^2 (rebuilt by
// sim::buildModel); the state remapped (new nodes interpolate position and velocity from
// their parents with the TopologyChange's weights).
#include <Eigen/Core>
#include <vector>

#include "hysim/cutting/mesh.hpp"
#include "hysim/cutting/result.hpp"
#include "hysim/cutting/topology_change.hpp"
#include "hysim/sim/model.hpp"

namespace hysim::sim {

struct MassUpdate3DOptions {
  // Masses never go below this fraction of their prior: min |m - m0|^2 s.t. A m = p,
  // m >= floor (active set: clamped masses are fixed and the rest solved again).
  double floor_fraction = 0.05;
  int max_active_set_iterations = 20;
};

struct MassUpdate3DReport {
  int unknowns = 0;            // nodes whose mass was corrected
  int clamped = 0;             // held at the floor
  bool global = false;         // too few touched nodes: every node took part
  double moment_residual = 0;  // max |A m - p| / max |p| (scaled coordinates)
};

// Moments (1, x, y, z, x^2, y^2, z^2, xy, yz, zx) of point masses, coordinates taken as
// (x - centre) / scale.
Eigen::Matrix<double, 10, 1> massMoments3D(const cutting::Positions& X, const Eigen::VectorXd& mass,
                                           const Eigen::Vector3d& centre, double scale);

// Lumped masses: a quarter of rho * volume of each incident tet; `density` is #T (g/mm^3).
Eigen::VectorXd lumpedMasses3D(const cutting::TetMesh& mesh, const Eigen::VectorXd& density);

// New masses for `after`: nodes touched by the change (new nodes, moved nodes, nodes on
// the cut, nodes of added elements) are corrected from their lumped prior so that the ten
// moments of (before, mass_before) are kept; other nodes keep their mass.
Result<Eigen::VectorXd> updateMasses3D(const cutting::TetMesh& before, const Eigen::VectorXd& mass_before,
                                       const cutting::TetMesh& after, const cutting::TopologyChange& change,
                                       const Eigen::VectorXd& density_after, const MassUpdate3DOptions& options = {},
                                       MassUpdate3DReport* report = nullptr);

// State for the cut mesh: surviving nodes keep x and v, new nodes interpolate them from
// their parents (a duplicate copies its original); forces zeroed, scratch sized.
State remapState3D(const State& before, const cutting::TopologyChange& change);

// The model of the cut mesh: springs and materials by buildModel (Van Gelder), anchored
// nodes mapped through the change (a duplicate of an anchored node is anchored too), masses
// by updateMasses3D.
Result<Model> updateModel3D(const Model& before, const cutting::TetMesh& mesh_before,
                            const cutting::TetMesh& mesh_after, const cutting::TopologyChange& change,
                            const MassUpdate3DOptions& options = {}, MassUpdate3DReport* report = nullptr);

// ---------------------------------------------------------------------------------------
// Incremental update of a model after a cut, in place: what the simulator does after each
// shaving pass. Same physics as updateModel3D, but only the neighbourhood of the cut is
// recomputed; the rest is carried over by index (linear passes of plain copies):
//  - masses: the nodes touched by the change (new, moved, on the cut, of added or removed
//    elements, of elements with a moved node) and two rings of neighbours get their lumped
//    mass as prior and the smallest correction that keeps the ten moments (up to second
//    order) of the masses they replace, all positive (floor_fraction of the prior); other
//    nodes keep their mass. The moments are those of the nodes involved, so the residual
//    carries no round-off of the whole mesh's sums.
//  - springs: an edge with an untouched end is unchanged (every tet around it is); edges
//    between touched nodes are recomputed (Van Gelder k = sum_t E_t V_t / |e|^2 over the
//    tets around them, c = sum_t beta_t E_t V_t / |e|^2), vanished ones dropped.
//  - pieces cut free (node_to_kept[i] < 0 for their nodes, the rest renumbered by it) leave
//    with their masses and springs.
//  - stability: Lanczos estimate of the highest natural frequency of the free nodes near
//    the cut (the springs to nodes outside held fixed: a principal submatrix, whose top
//    eigenvalue is a lower bound of the whole mesh's, like the power iteration's estimate),
//    combined with the previous omega_max when the previous highest mode (stability_mode)
//    lies away from the cut. When that mode lies near the cut, the previous omega_max is
//    still a bound for the rest of the mesh: the free nodes away from the cut (their springs
//    and masses unchanged) form a principal submatrix of the previous matrix too, whose top
//    eigenvalue is at most the previous one (Cauchy interlacing), so max(estimate near the
//    cut, previous omega_max) is not below what the whole mesh's estimate would find away
//    from the cut, only possibly above it (the mode that set it may have been cut away).
//    That held bound decides omega_max for at most max_held_estimates updates in a row (an
//    estimate near the cut at or above it ends the run: it is then at least the rest's
//    bound, about what an estimate over all nodes would find); then, and
//    when the previous estimate is not a Lanczos one (buildModel's power iteration, which
//    approaches the top from below, too far to bound anything), a Lanczos estimate over all
//    free nodes, started from the previous mode, replaces it. Selective mass scaling as buildModel, on the
//    nodes of the estimate. Near the cut, the Lanczos run is skipped when a cheap upper bound
//    of the same top eigenvalue (max over the nodes of 2 lambda_max(sum_s k_s d_s d_s^T) / m_i)
//    is below the previous estimate: a Lanczos estimate would be below it too, so the outcome
//    (the previous estimate carried over) is the same.
//  - the implicit integrator's factorisation is redone (XPBD and symplectic Euler need none).
struct CutUpdate3DOptions {
  MassUpdate3DOptions masses;
  int mass_rings = 2;               // rings of neighbours around the touched nodes
  double mode_overlap = 0.05;       // previous mode's energy share near the cut that forces a global estimate
  int lanczos_steps = 60;           // at most
  // At least this many steps (when the space is that large) before the convergence test
  // (residual and growth over 5 steps below lanczos_tolerance) may stop; the test itself
  // guards against stopping below the top of a dense spectrum. 20 before: on the 4 planes
  // through the 20k-tet uterus and 52 recorded shaving passes, 10 gives omega_max within
  // 4e-6 of 20's (relative, far inside stability_safety) and the same substeps, in 11-38
  // steps instead of 21-48 (bench/bench_model_update, HYSIM_LANCZOS_MIN_STEPS).
  int lanczos_min_steps = 10;
  double lanczos_tolerance = 1e-3;  // relative residual of the top Ritz pair, and its growth over 5 steps
  // Full reorthogonalisation of each Lanczos vector against the previous ones when 3 x the
  // estimate's free nodes is at most this. 3000 before (every shaving pass's estimate): 0,
  // none, takes the same number of steps on the 4 planes through the 20k-tet uterus and the
  // 57 recorded shaving passes, with omega_max equal to 7 digits and the same substeps
  // (bench/bench_model_update), and the same default-scene hash; it saves two
  // (3 #nodes x step) matrix-vector products per step.
  int lanczos_reorthogonalise_max = 0;
  // Updates in a row whose omega_max may be the previous one held as a bound after its
  // mode was near the cut (Model::stability_held); 0 = estimate over all nodes instead.
  int max_held_estimates = 4;
  // An estimate followed by a round of mass scaling whatever its exact value (its Ritz value
  // already needs more substeps than allowed) stops there: the round's estimate replaces it,
  // so the model is the same to the last bit (false: every estimate runs to convergence).
  bool stop_decided_estimates = true;
};

struct CutUpdate3DReport {
  MassUpdate3DReport masses;      // unknowns, clamped, moment_residual (global stays false)
  int touched_nodes = 0;          // before the rings
  int springs_recomputed = 0;     // edges between touched nodes, recomputed
  int stability_nodes = 0;        // free nodes of the frequency estimate
  int lanczos_steps = 0;
  bool global_stability = false;  // estimated over all free nodes (no previous estimate, or held too long)
  bool held_stability = false;    // the previous mode was near the cut: omega_max = max(local, previous)
  double omega_local = 0.0;       // rad/s, estimate near the cut (or the upper bound that made it unneeded)
  double omega_previous = 0.0;    // rad/s
  // Wall time (ms), for profiling: the masses and springs around the cut (prepare_ms), the
  // model's springs carried over and recomputed with the step's arrays (springs_ms), and the
  // stability estimates with the rounds of mass scaling (stability_ms).
  double prepare_ms = 0.0, springs_ms = 0.0, stability_ms = 0.0;
};

// `model` belongs to `before`; afterwards it belongs to `after` with the nodes i where
// node_to_kept[i] < 0 removed and the others renumbered to node_to_kept[i] (increasing, so
// node order is kept; empty = keep every node). `fixed_after` (#N of after): anchored nodes.
// Every element of `after` must have positive volume. On error the model is unchanged (but
// for a failed factorisation of the implicit integrator, the last step).
Status updateModelAfterCut3D(Model& model, const cutting::TetMesh& before, const cutting::TetMesh& after,
                             const cutting::TopologyChange& change, const std::vector<std::uint8_t>& fixed_after,
                             const std::vector<std::int32_t>& node_to_kept, const CutUpdate3DOptions& options = {},
                             CutUpdate3DReport* report = nullptr);

}  // namespace hysim::sim
