#pragma once
// Tissue update after a 2D cut (section 3 of the paper): node masses that keep the mass
// moments up to second order, p_jk = sum_i x_i^j y_i^k m_i (j + k <= 2), and new spring
// constants by Van Gelder's rule k_s = E * sum(area of incident triangles) / |s|^2.
#include <Eigen/Core>
#include <cstdint>

#include "hysim/cutting/mesh.hpp"
#include "hysim/cutting/result.hpp"
#include "hysim/cutting/topology_change.hpp"

namespace hysim::sim {

// A planar mass-spring tissue: one spring per unique triangle edge.
struct Tissue2D {
  Eigen::VectorXd mass;                                    // #N, g (per unit thickness)
  Eigen::Matrix<std::int32_t, Eigen::Dynamic, 2> springs;  // #S x 2 node indices
  Eigen::VectorXd rest_length;                             // #S, mm
  Eigen::VectorXd stiffness;                               // #S, Van Gelder
};

// Lumped masses (a third of each incident triangle's area times density) and Van Gelder
// springs.
Tissue2D buildTissue2D(const cutting::TriMesh& mesh, double young_modulus, double density);

// Moments p = (p00, p10, p01, p20, p11, p02) about `centre`, coordinates divided by `scale`.
Eigen::Matrix<double, 6, 1> massMoments2D(const cutting::TriMesh& mesh, const Eigen::VectorXd& mass,
                                          const Eigen::Vector2d& centre, double scale);

struct MassUpdateReport {
  int unknowns = 0;            // nodes whose mass was corrected
  bool global = false;         // the local system was too small or singular: all nodes used
  int clamped = 0;             // masses held at the positivity floor (active set)
  double moment_residual = 0;  // max |A m - p| / |p| (relative, scaled coordinates)
};

struct MassUpdateOptions {
  // Masses never go below this fraction of their prior (the unconstrained minimum-norm
  // correction can make a mass negative; those are held at the floor and the others solved
  // again, an active-set solution of min |m - m0|^2 s.t. A m = p, m >= floor).
  double floor_fraction = 0.05;
  int max_active_set_iterations = 20;
};

// New masses for `after` from the masses of `before`: the smallest correction, over the
// nodes touched by the change (new, moved, or on added elements), of the prior masses
// (previous masses carried over; area-lumped masses for touched nodes) that preserves the
// six moments of `before`. Coordinates are centred and scaled before forming A A^T.
Result<Eigen::VectorXd> updateMasses2D(const cutting::TriMesh& before, const Eigen::VectorXd& mass_before,
                                       const cutting::TriMesh& after, const cutting::TopologyChange& change,
                                       double density, const MassUpdateOptions& options = {},
                                       MassUpdateReport* report = nullptr);

// Masses by updateMasses2D and springs rebuilt by Van Gelder's rule.
Result<Tissue2D> updateTissue2D(const cutting::TriMesh& before, const Tissue2D& tissue_before,
                                const cutting::TriMesh& after, const cutting::TopologyChange& change,
                                double young_modulus, double density, const MassUpdateOptions& options = {},
                                MassUpdateReport* report = nullptr);

}  // namespace hysim::sim
