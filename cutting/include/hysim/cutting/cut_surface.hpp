#pragma once
// Cut surfaces for 3D cutting: an infinite plane, or an open triangulated surface (the loop
// electrode's swept strip) with an axis-aligned bounding-box tree for segment and
// point queries. Eigen and the standard library only.
//
// Predicates (documented tolerance, not exact arithmetic): a point is ON the surface when its
// distance to it is <= eps, where eps is given by the caller (cut3d uses
// on_surface_tolerance * mesh bounding-box diagonal, default 1e-9 relative). A segment
// CROSSES the surface only when both end points are farther than eps from the plane of the
// hit triangle, on opposite sides, and the crossing point lies inside the triangle (inclusive
// barycentric test with a 1e-12 relative slack, so a segment through a shared edge or vertex
// of two surface triangles is found by at least one of them). End points within eps are
// treated as lying on the surface and the segment as not crossed there; a segment lying in a
// triangle's plane never crosses. This makes "through a node", "along an edge" and "in a face
// plane" cuts well defined: those nodes are on the cut and nothing is subdivided there.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <utility>
#include <vector>

#include "hysim/cutting/mesh.hpp"
#include "hysim/cutting/no_init_allocator.hpp"
#include "hysim/cutting/result.hpp"

namespace hysim::cutting {

class CutSurface {
 public:
  // Plane through `point` with normal `normal` (normalised here; must be non-zero).
  static Result<CutSurface> plane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal);
  // Open (or closed) triangle surface; degenerate triangles are dropped. Errors: no usable
  // triangle, indices out of range, non-finite coordinates.
  static Result<CutSurface> triangles(const Positions& X, const Tris& F);
  // A strip: `rows` rows of `row_size` vertices (X row-major, rows * row_size rows), two
  // triangles per quad as stripTriangles gives them. The same surface as
  // triangles(X, stripTriangles(rows, row_size)), triangle numbers included, so the queries
  // give the same answers (ties go to the lower number whatever the tree); its tree follows
  // the grid (bisected across its longer side, one or two quads per leaf) instead of sorting
  // centroids: cheaper to build, and tighter boxes for a swept loop.
  static Result<CutSurface> strip(const Positions& X, int rows, int row_size);
  // The strip's triangles: for row r and column i, (a, a + 1, a + row_size + 1) and
  // (a, a + row_size + 1, a + row_size) with a = r * row_size + i, row by row.
  static Tris stripTriangles(int rows, int row_size);

  bool isPlane() const { return is_plane_; }
  const Eigen::Vector3d& planePoint() const { return point_; }
  const Eigen::Vector3d& planeNormal() const { return normal_; }
  int numTriangles() const { return static_cast<int>(leafTri_.size()); }

  // Plane: signed distance. Surface: unsigned distance to the nearest triangle, with the sign
  // of that triangle's normal side (only meaningful close to the surface).
  // `closest` (optional) receives the nearest surface point.
  double signedDistance(const Eigen::Vector3d& x, Eigen::Vector3d* closest = nullptr) const;
  // signedDistance(x, closest), the same value and point, for a point known to be within r of
  // the surface: the search skips what lies farther than r (much cheaper near the surface).
  // Where nothing is within r after all, the full search.
  double signedDistanceNear(const Eigen::Vector3d& x, double r, Eigen::Vector3d* closest = nullptr) const;

  struct Hit {
    double t = 0;                 // a + t (b - a), 0 < t < 1
    Eigen::Vector3d point;
    Eigen::Vector3d normal;       // unit normal of the hit triangle (plane normal)
    double da = 0, db = 0;        // signed distances of a and b from the hit triangle's plane
  };
  // Crossing of the segment a-b (nearest to a when there are several). False when the
  // segment does not cross (see the predicates above).
  bool intersectSegment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double eps, Hit* hit) const;

  // The surface's bounding box (plane: empty box, i.e. unbounded).
  const Eigen::AlignedBox3d& bounds() const { return bounds_; }
  // Does the box (grown by eps) possibly touch the surface? Surfaces: the grown box meets the
  // box of a leaf of the tree (a few triangles); false means it surely does not.
  bool mayTouch(const Eigen::AlignedBox3d& box, double eps) const;
  // |signedDistance(x)| <= r, without searching the surface farther than r from x (cheap for
  // points far from the surface, unlike the nearest-point search).
  bool within(const Eigen::Vector3d& x, double r) const;

 private:
  struct Tri {
    Eigen::Vector3d a, b, c, n;  // vertices, unit normal
  };
  struct Node {
    Eigen::AlignedBox3d box;
    int left = -1, right = -1;   // children; leaf when left < 0
    int begin = 0, end = 0;      // leaf: range in order_
  };
  // Per inner node, its children's boxes axis by axis as (left, right) pairs: one step of a
  // nearest-point walk measures both children with paired (SSE2) arithmetic.
  struct alignas(16) ChildBoxes {
    double lo[3][2], hi[3][2];
  };
  // Per leaf triangle, its vertices axis by axis, each value twice, and (b - a, c - a) axis by
  // axis: the nearest-point test takes two dot products with one vertex at once (and reads
  // the point it returns from the first of each pair: c - b is formed there, as
  // closestPointOnTriangle forms it).
  struct alignas(16) NearPairs {
    double a[3][2], b[3][2], c[3][2], e[3][2];
  };
  // Per leaf triangle, its first vertex and its normal axis by axis, each value twice: the
  // segment test measures both ends of a segment from the triangle's plane at once.
  struct alignas(16) PlanePairs {
    double p0[3][2], n[3][2];
  };
  struct LeafTri {
    Tri t;
    double area;  // t.n . ((b - a) x (c - a)), for the inside test of intersectSegment
  };
  struct BuildScratch {
    std::vector<Eigen::Vector3d> lo, hi, sum, centre;  // per triangle: box, a + b + c, centroid
    std::vector<std::pair<double, int>> keyed;         // the split's (key, triangle) pairs
  };
  // Tri records of F's non-degenerate triangles in input order (`kept`: F's row -> index
  // there, -1 when dropped), or an error.
  static Result<std::vector<Tri>> collect(const Positions& X, const Tris& F, std::vector<int>* kept);
  // The centroid-sorted tree over the triangles (order_ preset to input order) and the leaf
  // triangles.
  void finish(const std::vector<Tri>& tri);
  int build(int begin, int end, BuildScratch& scratch);
  // childBoxes_, nearPairs_ and planePairs_ from nodes_ and leafTri_ (after the tree is
  // built), each entry written once (the arrays are not zero-filled first).
  void finishWalkData();
  // One step of a nearest-point walk at inner node `id` (see there); xx: the point's
  // coordinates, each twice (x0 x0 x1 x1 x2 x2, 16-byte aligned).
  int stepChildren(int id, const double* xx, double limit, int* stack, double* stackDist, int& top) const;
  // The nearest-point walk (signedDistanceNear, within): nodes whose boxes are within `bound`
  // of the point (read again at each step: a leaf may lower it), the nearer child first;
  // leaf(begin, end) tests a leaf's triangles and returns true to end the walk.
  template <class Leaf>
  void walkNear(const Eigen::Vector3d& x, const double* xx, const double& bound, Leaf&& leaf) const;
  // Which of inner node `id`'s children's boxes meet the box [lo, hi] (bit 0 left, bit 1 right);
  // lohi: lo's coordinates, then hi's, each twice (16-byte aligned).
  int childrenMeet(int id, const double* lohi) const;
  // The nearest point of leaf triangle i (place in leafTri_) to the point xx (coordinates each
  // twice, as stepChildren), as closestPointOnTriangle gives it (SSE2 builds).
  Eigen::Vector3d closestPointPaired(const double* xx, int i) const;
  // The nearest point of leaf triangle i to x (xx: x's coordinates each twice): closestPointPaired
  // in SSE2 builds, closestPointOnTriangle's arithmetic otherwise (the same point).
  Eigen::Vector3d nearestOnLeaf(const double* xx, const Eigen::Vector3d& x, int i) const;

  bool is_plane_ = true;
  Eigen::Vector3d point_ = Eigen::Vector3d::Zero(), normal_ = Eigen::Vector3d::UnitZ();
  std::vector<int> order_;        // tree order -> input triangle index
  std::vector<Node> nodes_;
  std::vector<LeafTri> leafTri_;  // the triangles in tree order: input triangle order_[i] at i
  // (NoInitAllocator: resize() leaves the new entries uninitialised; finishWalkData writes
  // every entry once.)
  std::vector<ChildBoxes, NoInitAllocator<ChildBoxes>> childBoxes_;  // by node id (a leaf's entry zero)
  std::vector<PlanePairs, NoInitAllocator<PlanePairs>> planePairs_;  // by place in leafTri_
  std::vector<NearPairs, NoInitAllocator<NearPairs>> nearPairs_;     // by place in leafTri_
  Eigen::AlignedBox3d bounds_;
};

// Closest point of triangle (a, b, c) to p.
Eigen::Vector3d closestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                       const Eigen::Vector3d& b, const Eigen::Vector3d& c);

}  // namespace hysim::cutting
