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

}  // namespace hysim::sim
