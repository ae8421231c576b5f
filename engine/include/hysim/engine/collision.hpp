#pragma once
// Loop electrode vs. tissue, with FCL. The tissue's bounding volume hierarchy holds every
// tet face, interior ones included: a wire that is inside the tissue crosses interior faces
// (the loop, ~11 mm of wire, is longer than any tet, ~4 mm), so "touches a face" means "in
// or on the tissue". The hierarchy is refitted as the tissue deforms and rebuilt after a
// topology change.
//
// Cost on the default mesh (26k faces, AABB tree; ./build/bench/bench_collision): refit
// ~0.9 ms, a touching query ~0.7 ms. Callgrind shows why the query is slow: for a
// non-oriented BV (AABB), FCL 0.7's shape-vs-mesh collide copies the BVHModel and rebuilds
// its tree on every call (BVHModel copy + recursiveBuildTree dominate). Oriented BVs
// (OBBRSS) avoid the copy but their refit took ~49 ms. Too slow for every 1 ms step as it
// stands; the shaving loop needs a broadphase that updates incrementally (e.g. FCL's
// dynamic AABB tree over tets with fat boxes) or a hierarchy limited to the reachable region.
#include <Eigen/Core>
#include <memory>

#include "hysim/cutting/mesh.hpp"
#include "hysim/sim/model.hpp"

namespace hysim::engine {

class TissueCollision {
 public:
  TissueCollision();
  ~TissueCollision();
  TissueCollision(TissueCollision&&) noexcept;
  TissueCollision& operator=(TissueCollision&&) noexcept;

  // (Re)builds the hierarchy for this mesh at positions x (#N x 3).
  Status build(const cutting::TetMesh& mesh, const sim::NodeVectors& x);
  // Moves the hierarchy's vertices to x (same mesh) and refits the bounding volumes.
  void refit(const sim::NodeVectors& x);
  // Does the wire (polyline, #P x 3, thickened to `radius`) touch the tissue?
  bool touches(const Eigen::Matrix<double, Eigen::Dynamic, 3>& wire, double radius) const;
  int numFaces() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hysim::engine
