// validate(), element sizes and boundaryFaces() on hand-made meshes.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <set>
#include <string>

#include "../common/box_mesh.hpp"
#include "hysim/cutting/mesh.hpp"

namespace hysim::cutting {
namespace {

// gmock is not linked into the test executables; a plain substring check does.
::testing::AssertionResult contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << text << "' does not contain '" << part << "'";
}

// The corner tet of the unit cube, positively oriented (signed volume 1/6).
TetMesh unitTet() {
  TetMesh m;
  m.X.resize(4, 3);
  m.X << 0, 0, 0,  //
      1, 0, 0,     //
      0, 1, 0,     //
      0, 0, 1;
  m.T.resize(1, 4);
  m.T << 0, 1, 2, 3;
  m.material = Labels::Constant(1, 1);
  return m;
}

// unitTet plus a second tet (1, 2, 3, 4) on the other side of their shared face (1, 2, 3).
TetMesh twoTets() {
  TetMesh m;
  m.X.resize(5, 3);
  m.X << 0, 0, 0,  //
      1, 0, 0,     //
      0, 1, 0,     //
      0, 0, 1,     //
      1, 1, 1;
  m.T.resize(2, 4);
  m.T << 0, 1, 2, 3,  //
      1, 2, 3, 4;
  m.material = Labels::Constant(2, 1);
  return m;
}

// Three nodes of face (0, 1, 2) in the plane z = 0 and apexes on both sides of it.
//   3 = (0, 0, 1) and 5 = (0.3, 0.3, 0.5) above, 4 = (0.2, 0.2, -1) below.
TetMesh fanAroundFace012(const Tets& tets) {
  TetMesh m;
  m.X.resize(6, 3);
  m.X << 0, 0, 0,    //
      1, 0, 0,       //
      0, 1, 0,       //
      0, 0, 1,       //
      0.2, 0.2, -1,  //
      0.3, 0.3, 0.5;
  m.T = tets;
  m.material = Labels::Zero(tets.rows());
  return m;
}

// Unit square split along its diagonal (0, 2), counter-clockwise seen from +z.
TriMesh unitSquare() {
  TriMesh m;
  m.X.resize(4, 3);
  m.X << 0, 0, 0,  //
      1, 0, 0,     //
      1, 1, 0,     //
      0, 1, 0;
  m.F.resize(2, 3);
  m.F << 0, 1, 2,  //
      0, 2, 3;
  m.material = Labels::Constant(2, 2);
  return m;
}

Eigen::Vector3d node(const TetMesh& m, int i) { return m.X.row(i).transpose(); }

// --- sizes -----------------------------------------------------------------------------

TEST(TetVolume, SignFollowsOrientation) {
  TetMesh m = unitTet();
  EXPECT_DOUBLE_EQ(tetVolume(m, 0), 1.0 / 6.0);
  std::swap(m.T(0, 2), m.T(0, 3));
  EXPECT_DOUBLE_EQ(tetVolume(m, 0), -1.0 / 6.0);
}

TEST(TriArea, PlanarIsSignedSurfaceIsUnsigned) {
  TriMesh m = unitSquare();
  EXPECT_TRUE(m.isPlanar());
  EXPECT_DOUBLE_EQ(triArea(m, 0), 0.5);
  std::swap(m.F(0, 1), m.F(0, 2));
  EXPECT_DOUBLE_EQ(triArea(m, 0), -0.5);  // clockwise seen from +z
  // Lift the square out of z = 0: a surface in 3D has no preferred side.
  m.X.col(2).setConstant(2.0);
  EXPECT_FALSE(m.isPlanar());
  EXPECT_DOUBLE_EQ(triArea(m, 0), 0.5);
  EXPECT_DOUBLE_EQ(triArea(m, 1), 0.5);
}

// --- validate(TetMesh) -----------------------------------------------------------------

TEST(ValidateTet, AcceptsGoodMeshes) {
  EXPECT_TRUE(validate(unitTet()).ok()) << validate(unitTet()).error();
  EXPECT_TRUE(validate(twoTets()).ok()) << validate(twoTets()).error();
  const TetMesh box = testing::boxTetMesh(3, 2, 2, 0.5);
  const Status s = validate(box, {.requireAllNodesUsed = true});
  EXPECT_TRUE(s.ok()) << s.error();
  EXPECT_TRUE(validate(TetMesh{}).ok());  // empty mesh is valid
}

TEST(ValidateTet, CatchesInvertedTet) {
  TetMesh m = twoTets();
  std::swap(m.T(1, 0), m.T(1, 1));
  const Status s = validate(m);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error(), "tet 1: inverted (signed volume -0.333333 <= 0)");
}

TEST(ValidateTet, CatchesDegenerateTet) {
  TetMesh m = unitTet();
  m.X.row(3) << 0.5, 0.5, 0.0;  // apex in the base plane
  const Status s = validate(m);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error(), "tet 0: degenerate (signed volume 0 <= 0)");
}

TEST(ValidateTet, MinSignedSizeRejectsSlivers) {
  const TetMesh m = unitTet();
  EXPECT_TRUE(validate(m, {.minSignedSize = 0.1}).ok());
  const Status s = validate(m, {.minSignedSize = 0.2});
  ASSERT_FALSE(s.ok());
  EXPECT_TRUE(contains(s.error(), "tet 0:"));
  EXPECT_TRUE(contains(s.error(), "<= 0.2"));
}

TEST(ValidateTet, CatchesOutOfRangeIndex) {
  TetMesh m = twoTets();
  m.T(1, 2) = 7;
  Status s = validate(m);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error(), "tet 1: node index 7 out of range [0, 5)");
  m.T(1, 2) = -1;
  s = validate(m);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error(), "tet 1: node index -1 out of range [0, 5)");
}

TEST(ValidateTet, CatchesRepeatedNode) {
  TetMesh m = twoTets();
  m.T(0, 3) = 1;
  const Status s = validate(m);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error(), "tet 0: node 1 repeated");
}

TEST(ValidateTet, CatchesNonFiniteCoordinate) {
  TetMesh m = twoTets();
  m.X(2, 1) = std::numeric_limits<double>::quiet_NaN();
  Status s = validate(m);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error(), "node 2: non-finite coordinate (0, nan, 0)");
  m.X(2, 1) = 1;
  m.X(4, 0) = -std::numeric_limits<double>::infinity();
  s = validate(m);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error(), "node 4: non-finite coordinate (-inf, 1, 1)");
}

TEST(ValidateTet, CatchesMaterialSizeMismatch) {
  TetMesh m = twoTets();
  m.material.resize(1);
  const Status s = validate(m);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error(), "material has 1 labels but the mesh has 2 tets");
}

TEST(ValidateTet, CatchesFaceSharedByThreeTets) {
  Tets tets(3, 4);
  tets << 0, 1, 2, 3,  // above z = 0
      0, 2, 1, 4,      // below
      0, 1, 2, 5;      // above again: overlaps tet 0 and makes face (0, 1, 2) non-manifold
  const TetMesh m = fanAroundFace012(tets);
  for (int t = 0; t < 3; ++t) ASSERT_GT(tetVolume(m, t), 0) << t;
  const Status s = validate(m);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error(), "tet 2: face (0, 1, 2) is shared by more than 2 tets (0, 1, 2): non-manifold");
}

TEST(ValidateTet, CatchesSharedFaceWithSameOrientation) {
  Tets tets(2, 4);
  tets << 0, 1, 2, 3,  // both apexes above z = 0: the tets overlap
      0, 1, 2, 5;
  const TetMesh m = fanAroundFace012(tets);
  const Status s = validate(m);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error(),
            "tet 1: face (0, 1, 2) shared with tet 0 with the same orientation "
            "(inconsistent orientation or duplicate tet)");

  // The two correctly facing tets are fine.
  Tets good(2, 4);
  good << 0, 1, 2, 3,  //
      0, 2, 1, 4;
  EXPECT_TRUE(validate(fanAroundFace012(good)).ok());
}

TEST(ValidateTet, CatchesDuplicateTet) {
  TetMesh m = unitTet();
  m.T.conservativeResize(2, 4);
  m.T.row(1) << 1, 2, 0, 3;  // same tet, rotated (even permutation: still positive)
  m.material = Labels::Zero(2);
  const Status s = validate(m);
  ASSERT_FALSE(s.ok());
  EXPECT_TRUE(contains(s.error(), "tet 1: face"));
  EXPECT_TRUE(contains(s.error(), "same orientation"));
}

TEST(ValidateTet, UnusedNodesOnlyWhenRequired) {
  TetMesh m = unitTet();
  m.X.conservativeResize(5, 3);
  m.X.row(4) << 3, 3, 3;
  EXPECT_TRUE(validate(m).ok());
  const Status s = validate(m, {.requireAllNodesUsed = true});
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error(), "node 4: not used by any element");
}

// validate() runs after every cut on 20k-tet meshes in tests. Its cost is measured by
// bench_cut3d (BM_ValidateTetMesh), not bounded here: a wall-clock bound fails on a busy machine.
TEST(ValidateTet, AcceptsTwentyThousandTets) {
  const TetMesh box = testing::boxTetMesh(16, 16, 13, 0.25);
  ASSERT_EQ(box.numTets(), 19968);
  const Status s = validate(box, {.requireAllNodesUsed = true});
  EXPECT_TRUE(s.ok()) << s.error();
}

// --- validate(TriMesh) -----------------------------------------------------------------

TEST(ValidateTri, AcceptsGoodMeshes) {
  EXPECT_TRUE(validate(unitSquare()).ok()) << validate(unitSquare()).error();
  EXPECT_TRUE(validate(TriMesh{}).ok());
}

TEST(ValidateTri, CatchesClockwisePlanarTriangle) {
  TriMesh m = unitSquare();
  std::swap(m.F(1, 1), m.F(1, 2));
  const Status s = validate(m);
  ASSERT_FALSE(s.ok());
  // The flipped triangle is reported for its orientation before the edge check runs.
  EXPECT_EQ(s.error(), "triangle 1: inverted (clockwise seen from +z) (signed area -0.5 <= 0)");
}

TEST(ValidateTri, CatchesDegenerateTriangle) {
  TriMesh m = unitSquare();
  m.X.row(3) << 0.5, 0.5, 0;  // on the diagonal (0, 2)
  const Status s = validate(m);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error(), "triangle 1: degenerate (signed area 0 <= 0)");
}

TEST(ValidateTri, CatchesBadIndicesAndCoordinates) {
  TriMesh m = unitSquare();
  m.F(1, 0) = 4;
  EXPECT_EQ(validate(m).error(), "triangle 1: node index 4 out of range [0, 4)");
  m = unitSquare();
  m.F(0, 2) = 0;
  EXPECT_EQ(validate(m).error(), "triangle 0: node 0 repeated");
  m = unitSquare();
  m.X(3, 0) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(validate(m).error(), "node 3: non-finite coordinate (inf, 1, 0)");
  m = unitSquare();
  m.material.resize(3);
  EXPECT_EQ(validate(m).error(), "material has 3 labels but the mesh has 2 triangles");
}

TEST(ValidateTri, CatchesNonManifoldAndInconsistentEdges) {
  // Edge (0, 1) with a triangle below it and two above it (all counter-clockwise).
  TriMesh m;
  m.X.resize(5, 3);
  m.X << 0, 0, 0,  //
      1, 0, 0,     //
      0.5, 1, 0,   //
      0.5, -1, 0,  //
      0.5, 2, 0;
  m.F.resize(3, 3);
  m.F << 0, 1, 2,  //
      1, 0, 3,     //
      0, 1, 4;
  m.material = Labels::Zero(3);
  Status s = validate(m);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error(), "triangle 2: edge (0, 1) is shared by more than 2 triangles (0, 1, 2): non-manifold");

  m.F.row(1) << 0, 1, 4;
  m.F.conservativeResize(2, 3);
  m.material = Labels::Zero(2);
  s = validate(m);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error(),
            "triangle 1: edge (0, 1) shared with triangle 0 in the same direction "
            "(inconsistent orientation or duplicate triangle)");
}

TEST(ValidateTri, ClosedSurfaceInThreeD) {
  // The boundary of a tet is a closed, consistently oriented surface.
  TriMesh surface;
  surface.X = unitTet().X;
  surface.F = boundaryFaces(unitTet());
  surface.material = Labels::Zero(surface.F.rows());
  ASSERT_FALSE(surface.isPlanar());
  EXPECT_TRUE(validate(surface).ok()) << validate(surface).error();
  std::swap(surface.F(2, 0), surface.F(2, 1));  // flip one face
  const Status s = validate(surface);
  ASSERT_FALSE(s.ok());
  EXPECT_TRUE(contains(s.error(), "in the same direction"));
}

// --- boundaryFaces ---------------------------------------------------------------------

// The face's normal points away from the tet's fourth node.
void expectOutward(const TetMesh& m, const Eigen::Vector3i& face, int tet) {
  int apex = -1;
  for (int j = 0; j < 4; ++j) {
    const int v = m.T(tet, j);
    if (v != face(0) && v != face(1) && v != face(2)) apex = v;
  }
  ASSERT_GE(apex, 0) << "face is not a face of tet " << tet;
  const Eigen::Vector3d a = node(m, face(0)), b = node(m, face(1)), c = node(m, face(2));
  const Eigen::Vector3d normal = (b - a).cross(c - a);
  EXPECT_LT(normal.dot(node(m, apex) - a), 0) << "face (" << face.transpose() << ") of tet " << tet;
}

TEST(BoundaryFaces, SingleTetHasFourOutwardFaces) {
  const TetMesh m = unitTet();
  Eigen::VectorXi faceTet;
  const Tris faces = boundaryFaces(m, &faceTet);
  ASSERT_EQ(faces.rows(), 4);
  ASSERT_EQ(faceTet.size(), 4);
  Tris expected(4, 3);
  expected << 1, 2, 3,  // opposite node 0
      0, 3, 2,          // opposite node 1
      0, 1, 3,          // opposite node 2
      0, 2, 1;          // opposite node 3
  EXPECT_EQ(faces, expected);
  for (int f = 0; f < 4; ++f) {
    EXPECT_EQ(faceTet(f), 0);
    expectOutward(m, faces.row(f).transpose().cast<int>(), 0);
  }
}

TEST(BoundaryFaces, TwoTetsDropTheSharedFace) {
  const TetMesh m = twoTets();
  Eigen::VectorXi faceTet;
  const Tris faces = boundaryFaces(m, &faceTet);
  ASSERT_EQ(faces.rows(), 6);
  std::set<std::set<int>> seen;
  int perTet[2] = {0, 0};
  for (int f = 0; f < faces.rows(); ++f) {
    seen.insert({faces(f, 0), faces(f, 1), faces(f, 2)});
    ++perTet[faceTet(f)];
    expectOutward(m, faces.row(f).transpose().cast<int>(), faceTet(f));
  }
  EXPECT_EQ(seen.size(), 6u);
  EXPECT_EQ(seen.count({1, 2, 3}), 0u);  // the shared face is interior
  EXPECT_EQ(perTet[0], 3);
  EXPECT_EQ(perTet[1], 3);
  // Without faceTet the faces are the same.
  EXPECT_EQ(boundaryFaces(m), faces);
}

TEST(BoundaryFaces, SurvivesInvalidIndices) {
  // Not a valid mesh, but boundaryFaces must neither crash nor allocate per huge id.
  TetMesh m = twoTets();
  m.T(0, 0) = 2000000000;
  EXPECT_EQ(boundaryFaces(m).rows(), 6);
  m.T(1, 3) = -3;
  EXPECT_EQ(boundaryFaces(m).rows(), 6);
}

TEST(BoundaryFaces, BoxSurfaceIsClosedAndEnclosesTheVolume) {
  const int nx = 4, ny = 3, nz = 2;
  const double h = 0.5;
  const TetMesh box = testing::boxTetMesh(nx, ny, nz, h);
  const Tris faces = boundaryFaces(box);
  // Each boundary square is two triangles.
  EXPECT_EQ(faces.rows(), 4 * (nx * ny + ny * nz + nx * nz));
  TriMesh surface{box.X, faces, Labels::Zero(faces.rows())};
  EXPECT_TRUE(validate(surface).ok()) << validate(surface).error();
  // Divergence theorem: sum over outward faces of (a . (b x c)) / 6 is the enclosed volume.
  double volume = 0;
  for (int f = 0; f < faces.rows(); ++f) {
    volume += node(box, faces(f, 0)).dot(node(box, faces(f, 1)).cross(node(box, faces(f, 2)))) / 6.0;
  }
  EXPECT_NEAR(volume, nx * ny * nz * h * h * h, 1e-12);
}

}  // namespace
}  // namespace hysim::cutting
