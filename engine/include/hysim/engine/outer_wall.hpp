#pragma once
// The uterus' outer (serosal) surface and the signed distance of a point from it: the
// perforation check of the loop electrode. Built once from the initial mesh; queries never
// allocate.
//
// Which boundary faces are serosa: a face of the initial mesh's boundary is serosal when
// rays from its centre along its outward normal, and along four directions tilted 30 degrees
// from it, all leave the mesh without meeting another boundary face. Faces of the cavity,
// the myoma's bulge and the cervical canal look at tissue across the cavity or the canal, so
// at least one of their rays is blocked; faces of the outer surface look into free space.
// (The boundary is a single connected surface: the canal joins the cavity to the outside,
// so telling the surfaces apart by connected components does not work.)
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "hysim/cutting/mesh.hpp"
#include "hysim/cutting/result.hpp"
#include "hysim/sim/model.hpp"

namespace hysim::engine {

// Bounding volume hierarchy over a triangle soup (positions #V x 3, triangles #F x 3).
// Build allocates; refit and queries do not.
class TriangleBvh {
 public:
  void build(const cutting::Positions& V, const cutting::Tris& F);
  void refit(const cutting::Positions& V);  // same triangles, moved vertices
  // Nearest point of the surface to p. Returns the face (-1 when the surface is empty) and
  // fills `closest` and `feature` (0: face interior, 1-3: vertex F(f, feature-1), 4-6: edge
  // F(f, k) - F(f, (k+1)%3) with k = feature-4).
  int nearest(const Eigen::Vector3d& p, Eigen::Vector3d& closest, int& feature) const;
  // Whether the ray origin + t dir, t > 0, meets any triangle other than `skip_face`.
  bool rayHits(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, int skip_face) const;
  int numFaces() const { return static_cast<int>(F_.rows()); }

 private:
  struct Node {
    Eigen::AlignedBox3d box;
    int left = -1, right = -1;  // children (inner node)
    int first = 0, count = 0;   // range in order_ (leaf: count > 0)
  };
  int buildRange(int first, int count, std::vector<Eigen::Vector3d>& centroids);
  void fitNode(int node);

  static constexpr int kStack = 96;
  cutting::Positions V_;  // #V x 3
  cutting::Tris F_;       // #F x 3
  std::vector<Node> nodes_;  // depth-first preorder: children after their parent
  std::vector<int> order_;   // #F face ids, leaf ranges
};

class OuterWall {
 public:
  // Finds the serosal faces of `mesh` (the initial mesh). `fixed` (#N, 1 = anchored): when
  // every serosal node is anchored the surface never moves; otherwise update() moves it
  // with the tissue. A grid of cells of `cell_mm` marks where a point is surely farther
  // than `band_mm` inside the wall (for a moving surface: farther than band_mm + cell_mm, and
  // only while no vertex has moved more than cell_mm), so most queries cost one look-up.
  void build(const cutting::TetMesh& mesh, const std::vector<std::uint8_t>& fixed, double band_mm,
             double cell_mm = 2.0);
  bool empty() const { return F_.rows() == 0; }
  int numFaces() const { return static_cast<int>(F_.rows()); }
  int numBoundaryFaces() const { return num_boundary_faces_; }  // of the initial mesh
  bool isStatic() const { return static_; }
  double band() const { return band_; }
  const cutting::Positions& vertices() const { return V_; }  // #S x 3
  const cutting::Tris& faces() const { return F_; }          // #F x 3 into vertices()

  // Moves a non-static surface to the current positions x (#N x 3). Allocates nothing.
  void update(const sim::NodeVectors& x);
  // The mesh changed: node old_to_new[i] (-1: gone) is what node i was. A vertex whose node
  // is gone keeps its last position.
  void remapNodes(const std::vector<int>& old_to_new);

  // Signed distance of p from the serosa, mm: > 0 on the tissue/cavity side, < 0 beyond it.
  double signedDistance(const Eigen::Vector3d& p) const;
  // Like signedDistance where that is below band(); otherwise any value >= band() (cheap).
  double clearance(const Eigen::Vector3d& p) const;

 private:
  Eigen::Vector3d faceNormal(int f) const;    // unit, outward
  Eigen::Vector3d vertexNormal(int v) const;  // angle-weighted sum of the face normals
  bool farInside(const Eigen::Vector3d& p) const;

  cutting::Positions V_;             // #S x 3 serosal vertices
  cutting::Tris F_;                  // #F x 3 serosal faces (outward), into V_
  std::vector<int> node_;            // #S mesh node of each vertex (-1: gone)
  std::vector<int> neighbour_;       // #F*3: face across edge k of face f (-1: none)
  std::vector<int> vertex_face_start_, vertex_faces_;  // #S+1, #F*3: faces around each vertex
  TriangleBvh bvh_;
  bool static_ = false;
  double band_ = 0.0;
  int num_boundary_faces_ = 0;
  // Grid over the surface's bounding box: 1 = a query is needed.
  Eigen::Vector3d grid_origin_{0, 0, 0};
  double cell_ = 1.0;
  Eigen::Vector3i grid_size_{0, 0, 0};
  std::vector<std::uint8_t> needs_query_;
  cutting::Positions grid_V_;  // #S x 3 vertex positions the grid was made for
  double grid_slack_ = 0.0;    // how far vertices may move before the grid is void
  bool grid_valid_ = false;
};

}  // namespace hysim::engine
