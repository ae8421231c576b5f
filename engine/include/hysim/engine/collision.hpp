#pragma once
// Loop electrode vs. tissue, with FCL: the volume the wire swept in one step against the
// tissue's surface.
//
// SweptWire is that volume: per wire segment the quad between its previous and current
// positions (2 triangles), a small FCL hierarchy whose vertices are replaced and whose boxes
// are refitted in place every step. TissueCollision holds an AABB hierarchy of the tissue's
// boundary triangles only, built after every topology change, refitted in place (same tree)
// when the electrode becomes active and then followed step by step: leaf boxes are grown by
// a margin, and only the leaves of vertices that moved further than that are refitted (with
// their ancestors grown). touches() is an FCL mesh-mesh distance traversal that stops at the
// first pair of triangles closer than the wire radius (that is the thickening). Nothing of
// this runs while the pedal is up and no pass is open.
//
// The hierarchy is split into chunks (one FCL hierarchy per cell of a coarse grid over the
// faces' rest centroids, ~110 non-empty on the shaving scene's mesh), so that the build after
// a cut rebuilds only the chunks whose faces changed and follows the others (renumbered) as a
// step does: on the 57 dumped passes of the default scene (bench_pass_geometry
// BM_CollisionAfterCut, callgrind) ~6 chunks are rebuilt per pass, 1.6 M instructions per
// build instead of 7.6 M for a whole one. touches() visits the chunks whose root box comes
// within the radius of the wire's. The answer does not depend on the trees: the traversal
// prunes only box pairs farther apart than the radius, so any pair of triangles closer than
// that is found either way.
//
// The boundary is enough: if the swept volume meets no boundary triangle, the wire lies
// wholly inside or wholly outside the tissue (a connected set that crosses no surface), so one
// point-in-tissue test (TetLocator) settles the "buried loop" case. Every tet face (interior
// ones too) would make that test unnecessary but costs ~8x in refit and ~10x in query.
//
// Which FCL paths copy (FCL 0.7, narrowphase/detail/collision_func_matrix-inl.h and
// distance_func_matrix-inl.h): fcl::collide / fcl::distance with a non-oriented BV (AABB) copy
// the BVHModel(s) with `new BVHModel(*obj)` on every call (shape-vs-mesh and mesh-vs-mesh
// alike), and transform + refit the copy when the pose is not the identity: that was the
// earlier capsule query's 0.7 ms. Oriented BVs (OBBRSS) do not copy but their refit is slow
// (~49 ms for all tet faces). So touches() builds the traversal node itself
// (fcl::detail::initialize with identity poses transforms nothing, copies nothing) and runs
// fcl::detail::distance on it: no copy, no allocation (tested with the allocation counter).
// The full refit is one backward loop over FCL's nodes (children are numbered after their
// parent, checked at build), ~2x faster than endReplaceModel(true, true).
//
// Cost on the shaving scene's mesh (assets/uterus_myoma.msh: 3378 boundary faces, 1691 of
// its 2865 nodes; ./build/bench/bench_collision, medians of 5 repetitions, CPU time, on the
// 2-core machine shared with other builds, so +-30%):
//   full refit, boundary 59 us (all tet faces: 471 us; FCL's own bottom-up refit ~100 us)
//   update() with no vertex past the 0.5 mm margin 2.4 us; SweptWire::update 0.9 us
//   touches(): loop crossing the myoma's surface 2.9 us, buried 2.0 us, in the fluid 0.4 us
//   (exact boxes, margin 0: 1.4 / 1.0 us; all tet faces: 21 / 17 us)
//   a real active step (BM_ShavingPassSweep: 300 recorded steps of pass 1, ~17 vertices a
//   step leave their margin, a jittering node among them): median 9.8 us, p99 28 us; the
//   earlier 17-point TetLocator test on the same steps: median 17 us, p99 42 us.
// In the whole shaving run (perf record of ./build/tools/hysim run scenes/shaving.yaml)
// collision is 0.7% of the samples, ~20 us per active step.
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "hysim/cutting/mesh.hpp"
#include "hysim/sim/model.hpp"

namespace hysim::engine {

using WirePoints = Eigen::Matrix<double, Eigen::Dynamic, 3>;  // #P x 3 polyline

// The loop wire's motion in one step, as triangles (previous row, current row).
class SweptWire {
 public:
  SweptWire();
  ~SweptWire();
  SweptWire(SweptWire&&) noexcept;
  SweptWire& operator=(SweptWire&&) noexcept;

  // Sizes the hierarchy for wires of `points` points (allocates; once per loop geometry).
  void reset(int points);
  // The quads between the wire at `previous` and at `current` (both #P x 3, P = the size
  // given to reset()). Allocates nothing.
  void update(const WirePoints& previous, const WirePoints& current);
  int numPoints() const;
  int numTriangles() const;  // 2 * (points - 1)
  // Corners of triangle t (for tests and debugging).
  void triangle(int t, Eigen::Vector3d& a, Eigen::Vector3d& b, Eigen::Vector3d& c) const;

 private:
  friend class TissueCollision;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

class TissueCollision {
 public:
  TissueCollision();
  ~TissueCollision();
  TissueCollision(TissueCollision&&) noexcept;
  TissueCollision& operator=(TissueCollision&&) noexcept;

  // (Re)builds the hierarchy over the triangles `faces` (#F x 3 node ids into x, e.g. the
  // tissue's boundary faces) at positions x (#N x 3). Every leaf box is grown by `margin_mm`,
  // so the boxes stay valid until some vertex has moved that far. Allocates.
  // The faces are split into chunks, one hierarchy each: the faces whose centroid at `rest`
  // (#N x 3; x when null) lies in one cell of a grid of kChunksAlongLongestAxis cells along
  // the longest side of the faces' centroids' box (set by a build without `renumber`, kept
  // by those with). With `renumber` (node id of the previous build -> node id now, or -1), a
  // chunk whose faces are the previous build's same faces in the same order, renumbered, is
  // kept (its tree refitted at x) instead of rebuilt: after a cut only the chunks it changed
  // are built again. touches() is the same either way (a pair of triangles closer than the
  // radius is found whatever the tree), as are the vertices and margins update() follows.
  Status build(const cutting::Tris& faces, const sim::NodeVectors& x, double margin_mm = 0.0,
               const cutting::Positions* rest = nullptr, const std::vector<int>* renumber = nullptr);
  static constexpr double kChunksAlongLongestAxis = 6.0;
  // Moves the hierarchy's vertices to x (same mesh) and refits the boxes bottom-up in place,
  // keeping the tree. Allocates nothing.
  void refit(const sim::NodeVectors& x);
  // Moves the vertices to x; a vertex that has moved further than the margin since its boxes
  // were fitted gets the leaf boxes of its triangles refitted and their ancestors grown (a
  // local refit, O(#V) check plus O(depth) per moved vertex; boxes only grow until the next
  // refit()). A margin of 0 refits everything every time. Returns whether a box changed.
  // Allocates nothing.
  bool update(const sim::NodeVectors& x);
  // Does the swept wire, thickened by `radius`, touch a triangle? Allocates nothing.
  bool touches(const SweptWire& sweep, double radius) const;
  int numFaces() const;
  int numVertices() const;  // distinct nodes of the faces
  // Vertices of the chunks' hierarchies: a node on a chunk border is a vertex of each chunk.
  int numHierarchyVertices() const;
  double margin() const;
  long numRefits() const;       // full refits since construction (build included)
  long numLocalRefits() const;  // hierarchy vertices refitted locally by update()
  long numChunksBuilt() const;  // chunk hierarchies built since construction
  long numChunksKept() const;   // chunks kept (refitted) by builds with a renumbering

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// All distinct faces of the tets (#F x 3 node ids), interior ones included.
cutting::Tris allTetFaces(const cutting::TetMesh& mesh);

}  // namespace hysim::engine
