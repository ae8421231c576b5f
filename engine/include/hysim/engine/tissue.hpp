#pragma once
// One topology epoch of the tissue: the rest mesh, the mass-spring model built from it and
// every structure derived from them (boundary, render surface, contact nodes, collision
// hierarchy, tet locator). A cut makes the next epoch on the cut worker; the simulation
// swaps it in at the commit step. The state (positions, velocities) is not part of it.
#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "hysim/cutting/mesh.hpp"
#include "hysim/cutting/result.hpp"
#include "hysim/engine/collision.hpp"
#include "hysim/engine/mesh_faces.hpp"
#include "hysim/engine/pass_record.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/tet_locator.hpp"
#include "hysim/render/snapshot.hpp"
#include "hysim/sim/model.hpp"

namespace hysim::engine {

struct Tissue {
  cutting::TetMesh mesh;                 // rest shape
  sim::Model model;
  std::vector<std::uint8_t> anchored;    // #N: rest position in an anchor region (fixed)
  std::vector<std::uint8_t> on_cut;      // #N: node lies on a cut surface (drawn as cut tissue)
  std::vector<double> tet_quality;       // #T: q* of each element (rest shape), for q_min
  std::vector<int> face_next;            // 4 #T: matchFaces' next of mesh (empty: unknown)
  // #T: anchorDistance of mesh (empty: unknown), and whether every piece has an anchored
  // node (then a cut searches for free pieces near its cut only).
  std::vector<int> anchor_distance;
  bool pieces_anchored = false;
  int num_anchored = 0;
  int num_deformable_tets = 0;           // tets with at least one free node

  cutting::Tris surface_faces;                   // #B x 3 boundary faces, model node ids
  std::vector<int> surface_nodes;                // #V model node ids on the boundary
  std::vector<std::uint32_t> surface_triangles;  // #B*3 indices into surface_nodes
  std::vector<render::SurfaceMaterial> surface_material;  // #V
  std::vector<int> contact_nodes;                // free surface nodes (contact candidates)
  TissueCollision collision;                     // boundary faces (FCL)
  TetLocator locator;
  // The lookups mapping a deformed point to the rest shape needs apart from the locator: the
  // nearest surface node (grid over nearest_x, the positions it was built at) and a tet at
  // each node. nearest refers to nearest_x and surface_nodes: a Tissue is never copied.
  sim::NodeVectors nearest_x;
  NearestPoint nearest;

  Tissue() = default;
  Tissue(const Tissue&) = delete;
  Tissue& operator=(const Tissue&) = delete;
};

// The labels of the materials named "myoma" (a generated organ has one per myoma).
struct MyomaLabels {
  std::vector<int> labels;
  bool has(int label) const { return std::find(labels.begin(), labels.end(), label) != labels.end(); }
};
MyomaLabels myomaLabels(const Scene& scene);
// Whether a rest position lies in one of the scene's anchor regions.
bool anchoredAt(const Scene& scene, const Eigen::Vector3d& rest);
// q* = r_in / R_circ of tet t (rest shape).
double tetQuality(const cutting::TetMesh& mesh, int t);

// A whole epoch from a rest mesh (the start of a run): anchors, model, faces, pieces,
// qualities, and the geometry at positions x (null: rest).
Result<std::unique_ptr<Tissue>> makeTissue(cutting::TetMesh mesh, const Scene& scene);

// The boundary faces, render surface, contact nodes and collision hierarchy of tissue.mesh
// at positions x. `boundary` (optional, 4 #T): which tet faces (slot 4 t + k) lie on the
// boundary, when the caller knows; else they are found from the mesh. Times surface_ms and
// collision_ms into `timing` (optional).
Status buildSurface(Tissue& tissue, const Scene& scene, const sim::NodeVectors& x,
                    const std::vector<std::uint8_t>* boundary, PassRecord* timing);
// The tet locator and the nearest-node lookups at positions x (copied).
void buildLookups(Tissue& tissue, const sim::NodeVectors& x);
// anchor_distance and pieces_anchored from face_next and anchored (cleared and false when
// face_next is unknown); with count, returns the number of pieces (-1: unknown), else 0.
int findAnchorPieces(Tissue& tissue, bool count);
// num_anchored and num_deformable_tets from anchored and the model.
void countElements(Tissue& tissue);

}  // namespace hysim::engine
