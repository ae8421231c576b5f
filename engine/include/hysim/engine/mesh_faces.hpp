#pragma once
// The face adjacency kept current across a cut, the free pieces found near the cut, and a
// nearest-point grid, for the pass after a cut (Simulation::finishPass). They give exactly
// what the whole-mesh routines give (cutting::matchFaces' next, cutting::tetPieces' pieces, a
// linear nearest-point scan), see tests/engine/test_mesh_faces.cpp.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "hysim/cutting/mesh.hpp"
#include "hysim/cutting/tet_faces.hpp"
#include "hysim/sim/model.hpp"

namespace hysim::engine {

// The face adjacency itself (kTetFace, matchFaces, tetPieces, boundaryFromSlots) is cutting's
// (hysim/cutting/tet_faces.hpp); this file keeps it current across a cut.
using cutting::boundaryFromSlots;
using cutting::kTetFace;
using cutting::matchFaces;
using cutting::Pieces;
using cutting::tetPieces;

// matchFaces' next for `after`, a cut of `before` (change: the cut's TopologyChange), from
// next_before (matchFaces' next of before) instead of from all faces: a slot of an element
// that the cut kept with the same nodes in the same order keeps its neighbour when that one
// was kept so too, and stays on the boundary when it was there and no node of its face
// belongs to a changed element; the other slots (the changed elements', and those next to
// them) are matched among themselves. Linear in #T with a small constant, sorting only the
// slots near the cut. Returns false (next untouched) when it cannot tell: sizes that do not
// match, a face of more than two elements among the slots matched anew, node ids out of
// range (2^21 or more), matchFaces then. next_before must pair its slots (a face of at most
// two elements: matchFaces' and updateFaces' next of a valid mesh), as it is not checked.
// What updateFaces finds on the way, for freePiecesAfterCut.
struct FaceChange {
  // #T of after: the element of before with the same nodes in the same order, or -1.
  std::vector<int> old_of;
  // Ascending: the tets of after with a face whose neighbour may differ from before (the
  // slots matched anew), every tet whose old_of is -1 among them. Every other tet has the
  // neighbours its old_of had, renumbered.
  std::vector<int> near_cut;
};
// change (optional) is written when updateFaces returns true.
bool updateFaces(const cutting::TetMesh& before, const std::vector<int>& next_before, const cutting::TetMesh& after,
                 const std::vector<std::int32_t>& node_old_to_new, const std::vector<std::int32_t>& element_old_to_new,
                 std::vector<int>& next, FaceChange* change = nullptr);

// Per tet, the number of steps through shared faces to a tet with an anchored node (0 for
// those), or INT_MAX where no such tet is connected. A breadth-first search from all of them.
std::vector<int> anchorDistance(const cutting::TetMesh& mesh, const std::vector<int>& next,
                                const std::vector<std::uint8_t>& anchored);

// tetPieces' free pieces of `after`, a cut of `before`, found from the tets near the cut
// (change.near_cut) instead of from all tets, where
//   every piece of before had an anchored node, and every node of before that was anchored
//   still is (its node in after);
// then a piece of after without a tet near the cut is a piece of before (same tets, same
// faces), anchored. A search from each tet near the cut not reached yet walks the shared faces
// (next: updateFaces' next of after) until it meets an anchored node or a tet an earlier search
// reached (anchored: a free piece is searched whole), or runs out of tets: then its tets are
// a free piece. The search steps first to the neighbour nearest to the anchors before the cut
// (distance_before: anchorDistance of before; tets without an old_of last), so an anchored
// search usually ends after about that many steps.
// Returns: label 0 for every tet not in a free piece (piece 0, not free), the free pieces
// numbered 1, 2, ... in the order of their first tet (tetPieces' order of the free pieces),
// count = 1 + the number of free pieces.
Pieces freePiecesAfterCut(const cutting::TetMesh& after, const std::vector<int>& next,
                          const std::vector<std::uint8_t>& anchored, const FaceChange& change,
                          const std::vector<int>& distance_before);

// Nearest point of a set to a query, exactly as a linear scan in the set's order finds it
// (smallest squared distance, the first such point on ties), through a uniform grid.
class NearestPoint {
 public:
  // pts: indices into x of the candidate points, in scan order. Both are referenced, not
  // copied: they must outlive the queries.
  void build(const sim::NodeVectors& x, const std::vector<int>& pts);
  // The point (an entry of pts) nearest to q, or -1 for an empty set.
  int nearest(const Eigen::Vector3d& q) const;

 private:
  int clampIndex(const Eigen::Vector3d& q, int a) const;
  size_t cellOf(const Eigen::Vector3d& q) const;
  const std::vector<int>* pts_ = nullptr;
  const sim::NodeVectors* x_ = nullptr;
  Eigen::Vector3d origin_{0, 0, 0};
  double cell_ = 1.0;
  Eigen::Vector3i dims_{1, 1, 1};
  std::vector<int> start_, items_;
};

}  // namespace hysim::engine
