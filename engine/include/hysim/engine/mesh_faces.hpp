#pragma once
// Face matching and connected pieces of a tet mesh in linear time, and a nearest-point grid,
// for the pass after a cut (Simulation::finishPass). They give exactly what the whole-mesh
// routines they replace give (cutting::tetComponents' labels, cutting::boundaryFaces' faces
// and order, a linear nearest-point scan), see tests/engine/test_mesh_faces.cpp.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "hysim/cutting/mesh.hpp"
#include "hysim/sim/model.hpp"

namespace hysim::engine {

// The four faces of a tet as local vertex indices, face k opposite vertex k, oriented
// outwards for a positive tet: the order cutting::boundaryFaces uses.
inline constexpr int kTetFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

// Slot s = 4 t + k is face k of tet t; next[s] (4 #T) is another slot with the same three
// nodes (the slots of a shared face form a cycle, in ascending slot order), or -1 where the
// face is on the boundary.
// Faces are bucketed by their smallest node (a counting sort), then sorted by the other two
// inside each bucket (a few dozen faces). Returns false (next untouched) for node ids
// outside [0, #N), which a valid mesh never has.
bool matchFaces(const cutting::TetMesh& mesh, std::vector<int>& next);

// matchFaces' next for `after`, a cut of `before` (change: the cut's TopologyChange), from
// next_before (matchFaces' next of before) instead of from all faces: a slot of an element
// that the cut kept with the same nodes in the same order keeps its neighbour when that one
// was kept so too, and stays on the boundary when it was there and no node of its face
// belongs to a changed element; the other slots (the changed elements', and those next to
// them) are matched among themselves. Linear in #T with a small constant, sorting only the
// slots near the cut. Returns false (next untouched) when it cannot tell: sizes that do not
// match, a face of more than two elements, node ids out of range; matchFaces then.
bool updateFaces(const cutting::TetMesh& before, const std::vector<int>& next_before, const cutting::TetMesh& after,
                 const std::vector<std::int32_t>& node_old_to_new, const std::vector<std::int32_t>& element_old_to_new,
                 std::vector<int>& next);

// Connected components through shared faces, numbered in the order of their first tet, and
// whether each touches no anchored node: cutting::tetComponents' label, count and free (not
// its volumes), from matchFaces' next.
struct Pieces {
  std::vector<int> label;  // #T
  int count = 0;
  std::vector<std::uint8_t> free;  // per component
};
// anchored: #N flags.
Pieces tetPieces(const cutting::TetMesh& mesh, const std::vector<int>& next, const std::vector<std::uint8_t>& anchored);

// The boundary faces (the slots whose next is -1) in slot order, nodes in kTetFace order,
// and their tets: what cutting::boundaryFaces gives for the mesh. boundary: 4 #T flags.
void boundaryFromSlots(const cutting::TetMesh& mesh, const std::vector<std::uint8_t>& boundary, cutting::Tris& faces,
                       Eigen::VectorXi& face_tet);

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
