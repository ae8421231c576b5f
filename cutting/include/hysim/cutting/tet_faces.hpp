#pragma once
// Which tets share a face, for a whole tet mesh in linear time: the one face adjacency that
// cutting's whole-mesh routines (validate, boundaryFaces, tetComponents) and the engine's
// pass geometry (engine/mesh_faces.hpp, which updates it after a cut) are built on.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "hysim/cutting/mesh.hpp"

namespace hysim::cutting {

// The four faces of a tet as local vertex indices, face k opposite vertex k, oriented
// outwards for a positive tet.
inline constexpr int kTetFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

// Slot s = 4 t + k is face k of tet t; next[s] (4 #T) is another slot with the same three
// nodes (the slots of a shared face form a cycle, in ascending slot order), or -1 where the
// face is on the boundary. A valid mesh has cycles of two; longer ones are non-manifold.
// Faces are bucketed by their smallest node (a counting sort), then sorted by the other two
// inside each bucket (a few dozen faces). Returns false (next untouched) for node ids
// outside [0, #N), which a valid mesh never has.
bool matchFaces(const TetMesh& mesh, std::vector<int>& next);
// matchFaces for any node ids: where some are out of range (an invalid mesh), the ids are
// renumbered first (a sort), so faces still match by their ids.
void matchFacesOfAnyIds(const TetMesh& mesh, std::vector<int>& next);

// The lowest slot of the face that slot s belongs to (s itself on the boundary).
inline int firstSlotOfFace(const std::vector<int>& next, int s) {
  int first = s;
  for (int p = next[s]; p >= 0 && p != s; p = next[p]) first = p < first ? p : first;
  return first;
}

// The boundary faces (boundary[s] set) in slot order, nodes in kTetFace order, and their tets.
// boundary: 4 #T flags (those with next[s] == -1 for the whole boundary).
void boundaryFromSlots(const TetMesh& mesh, const std::vector<std::uint8_t>& boundary, Tris& faces,
                       Eigen::VectorXi& face_tet);

// Connected components through shared faces, numbered in the order of their first tet, and
// whether each touches no anchored node, from matchFaces' next.
struct Pieces {
  std::vector<int> label;  // #T
  int count = 0;
  std::vector<std::uint8_t> free;  // per component
};
// anchored: #N flags.
Pieces tetPieces(const TetMesh& mesh, const std::vector<int>& next, const std::vector<std::uint8_t>& anchored);

}  // namespace hysim::cutting
