#pragma once
// Cutting planar triangle meshes (z = 0, counter-clockwise) along a polyline: the hybrid
// method of Harders et al. (section 3: snap a node onto the cut where the cut passes near
// it, subdivide where it passes near the middle of an edge, flip an edge where two type-2
// cases follow each other, then optimise the mesh locally) and the baselines it is compared
// against (standard subdivision, snapping only, element deletion), all with one interface.
#include <Eigen/Core>
#include <vector>

#include "hysim/cutting/mesh.hpp"
#include "hysim/cutting/result.hpp"
#include "hysim/cutting/topology_change.hpp"

namespace hysim::cutting {

enum class CutMethod {
  Hybrid,    // snap or subdivide per edge region, edge flips, mesh optimisation
  Standard,  // every intersected edge split, every crossed element subdivided
  Snap,      // snapping only: always displace the nearer node (subdivide only where a
             // displacement would fold or flatten an element)
  Delete,    // remove every element the cut crosses
};
const char* cutMethodName(CutMethod method);
bool parseCutMethod(const std::string& name, CutMethod* method);

// Mesh optimisation after the cut (Fig. 1 of the paper).
struct Optimize2DOptions {
  bool enabled = true;
  // Cut edges shorter than this fraction of the mesh's mean edge length are collapsed; the
  // cut is also collapsed down to ~length / mean edge segments (node count kept constant).
  double collapse_ratio = 0.6;
  bool distribute = true;            // equal node spacing along the cut
  int rings = 2;                     // nodes up to this many edge steps from the cut move
  double spring_weight = 1.0;        // alpha
  double particle_weight = 0.5;      // beta
  double step_gain = 0.12;           // dt^2 / (m + dt c): heavy damping, constant masses
  double stop_fraction = 0.02;       // stop when the largest move < this * mean edge length
  int max_iterations = 300;
  // A regularisation move is refused when it would leave the worst element around the node
  // below min(its quality before the move, quality_guard).
  double quality_guard = 0.35;
  // Quality repair after the regularisation (beyond the paper): triangles near the cut
  // below this quality get edge flips and node optimisation (see optimize2d.cpp).
  double repair_quality = 0.35;
  int repair_rounds = 6;
  // Node budget (beyond the paper): nodes near the cut are merged until the node count is
  // back to the input's, when the merge leaves no element below this quality.
  bool keep_node_count = true;
  double collapse_quality = 0.15;
};

struct Cut2DOptions {
  CutMethod method = CutMethod::Hybrid;
  // An edge crossed at a fraction t of its length from a node (t < snap_region) displaces
  // that node onto the cut (hybrid); otherwise the edge is subdivided (Fig. 5 regions).
  double snap_region = 0.3;
  // Border nodes move only along the border, and not at a feature: where the normals of
  // the two border edges differ by more than this angle.
  double feature_angle_deg = 20.0;
  // Hybrid: a cut entering or leaving through a border edge within this fraction of the
  // edge from a feature node is bent to pass through that node (beyond the paper; a sliver
  // cut off a corner cannot be meshed with elements of the mesh's size). 0 disables.
  double corner_region = 0.4;
  // A displacement (or flip) is refused, falling back to subdivision, when an element would
  // get a radius ratio below this (folded and flat elements always refuse).
  double min_quality = 0.12;
  bool edge_flips = true;            // look-ahead: two consecutive type-2 cases -> one flip
  bool separate = true;              // duplicate the nodes on the cut (sides share no edge)
  Optimize2DOptions optimize;        // used by Hybrid only
};

struct Cut2DReport {
  int crossed_edges = 0;       // edges the cut crosses (before any displacement)
  int displaced_nodes = 0;     // nodes snapped onto the cut
  int border_displacements = 0;  // of which moved along the border
  int subdivided_edges = 0;    // new nodes at edge intersections
  int edge_flips = 0;
  int collapsed_edges = 0;     // optimisation: edge collapses on the cut
  int regularised_nodes = 0;   // optimisation: movable nodes
  int regularisation_iterations = 0;
  int repair_flips = 0;         // optimisation: quality-driven edge flips
  int repair_moves = 0;         // optimisation: quality-driven node moves
  int deleted_elements = 0;
  int duplicated_nodes = 0;
  double cut_ms = 0.0;         // everything but the optimisation
  double optimize_ms = 0.0;    // edge collapse, distribution, regularisation
};

struct Cut2DResult {
  TriMesh mesh;
  TopologyChange change;
  Cut2DReport report;
};

// Cuts `mesh` (planar, valid) along `polyline` (>= 2 points, x/y). The part of the cut
// inside the mesh is used; a cut that ends inside the mesh ends at a node (crack tip) and
// may be continued by a later call starting there. Errors: non-planar or invalid input,
// fewer than two points, non-finite coordinates.
Result<Cut2DResult> cut2d(const TriMesh& mesh, const std::vector<Eigen::Vector2d>& polyline,
                          const Cut2DOptions& options = {});

// Convenience: a straight segment.
Result<Cut2DResult> cut2d(const TriMesh& mesh, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                          const Cut2DOptions& options = {});

// Number of distinct node positions among the nodes used by elements (duplicates made to
// separate the sides count once), positions compared exactly.
int countDistinctPositions(const TriMesh& mesh);

// Connected components of elements where two elements are connected when they share an
// edge (both nodes identical). Returns #F labels 0..k-1; *count = k.
Eigen::VectorXi elementComponents(const TriMesh& mesh, int* count);

// Total signed area of a planar mesh.
double totalArea(const TriMesh& mesh);

}  // namespace hysim::cutting
