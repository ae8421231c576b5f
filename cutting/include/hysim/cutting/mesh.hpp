#pragma once
// Triangle and tetrahedral meshes as structure-of-arrays Eigen matrices (libigl convention).
// Every mesh type has validate(); tests call it after every edit.
#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "hysim/cutting/result.hpp"

namespace hysim::cutting {

// Typed ids where mix-ups are possible; -1 means none.
enum class NodeId : std::int32_t { None = -1 };
enum class TetId : std::int32_t { None = -1 };
enum class TriId : std::int32_t { None = -1 };

using Positions = Eigen::Matrix<double, Eigen::Dynamic, 3>;       // #N x 3, column-major (x, y, z arrays)
using Tets = Eigen::Matrix<std::int32_t, Eigen::Dynamic, 4>;     // #T x 4 node indices
using Tris = Eigen::Matrix<std::int32_t, Eigen::Dynamic, 3>;     // #F x 3 node indices
using Labels = Eigen::Matrix<std::int32_t, Eigen::Dynamic, 1>;   // #E material label per element

// Largest coordinate magnitude a mesh or cut surface may hold: 1e30 mm. The tet quality
// measure multiplies up to eight edge lengths, so coordinates near the top of the double
// range would make volumes and q overflow to inf or NaN; within +-1e30 those products stay
// below 1e250, far from the double maximum 1.8e308. Readers refuse larger values.
inline constexpr double kMaxCoordinateMm = 1e30;

// Tetrahedral mesh. Positive orientation: (x1-x0) . ((x2-x0) x (x3-x0)) > 0.
struct TetMesh {
  Positions X;       // #N x 3 node positions (mm)
  Tets T;            // #T x 4 tetrahedra
  Labels material;   // #T material label (Gmsh physical tag); 0 when none

  int numNodes() const { return static_cast<int>(X.rows()); }
  int numTets() const { return static_cast<int>(T.rows()); }
};

// Triangle mesh. Used both for planar 2D meshes (z = 0, counter-clockwise seen from +z)
// and for surfaces in 3D (orientation consistent across shared edges).
struct TriMesh {
  Positions X;       // #N x 3 node positions (mm); z = 0 for planar meshes
  Tris F;            // #F x 3 triangles
  Labels material;   // #F material label; 0 when none

  int numNodes() const { return static_cast<int>(X.rows()); }
  int numTris() const { return static_cast<int>(F.rows()); }
  bool isPlanar() const;  // all z == 0
};

struct ValidateOptions {
  bool requireAllNodesUsed = false;  // dangling (unreferenced) nodes are an error
  double minSignedSize = 0.0;        // elements with signed area/volume <= this are errors
};

// Checks: sizes of arrays agree, indices in range, no repeated node in an element,
// finite coordinates, positive orientation (tets; planar triangles), manifoldness
// (each tet face shared by at most 2 tets with opposite orientation; each triangle
// edge shared by at most 2 triangles with opposite direction).
// Returns an empty Status or the first problem found, naming the element.
Status validate(const TetMesh& mesh, const ValidateOptions& options = {});
Status validate(const TriMesh& mesh, const ValidateOptions& options = {});

// Signed volume of tet t (positive when correctly oriented).
double tetVolume(const TetMesh& mesh, int t);
// Signed area of planar triangle f (positive when counter-clockwise seen from +z);
// for non-planar meshes, the unsigned area. "Planar" is decided per triangle (its three
// nodes at z == 0) so that the call is O(1); for a planar mesh that is the same thing.
double triArea(const TriMesh& mesh, int f);

// Boundary faces of a tet mesh (faces used by exactly one tet), outward oriented.
// faceTet (optional, #B) receives the tet each face belongs to.
Tris boundaryFaces(const TetMesh& mesh, Eigen::VectorXi* faceTet = nullptr);

}  // namespace hysim::cutting
