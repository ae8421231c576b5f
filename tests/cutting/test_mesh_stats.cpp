// Radius ratio, dihedral angles and mesh statistics against values computed by hand, and
// against an independent computation (circumcentre from a linear system, incentre from
// face areas) on random elements.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "../common/box_mesh.hpp"
#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::cutting {
namespace {

using Eigen::Vector3d;
constexpr double kPi = std::numbers::pi;
constexpr double kSqrt2 = std::numbers::sqrt2;
constexpr double kSqrt3 = std::numbers::sqrt3;

double degrees(double radians) { return radians * 180.0 / kPi; }

// --- single elements -------------------------------------------------------------------

TEST(RadiusRatio, EquilateralTriangleIsOneHalf) {
  const Vector3d a(0, 0, 0), b(2, 0, 0), c(1, kSqrt3, 0);
  EXPECT_NEAR(radiusRatio(a, b, c), 0.5, 1e-15);
  // Invariant under rotation, translation and scale.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Vector3d shift(5, -3, 2);
  EXPECT_NEAR(radiusRatio(R * a * 1e-3 + shift, R * b * 1e-3 + shift, R * c * 1e-3 + shift), 0.5, 1e-12);
}

TEST(RadiusRatio, RightIsoscelesTriangle) {
  // Legs 1, hypotenuse sqrt 2: r_in = (1 + 1 - sqrt 2) / 2, R_circ = sqrt 2 / 2,
  // so q = (2 - sqrt 2) / sqrt 2 = sqrt 2 - 1.
  EXPECT_NEAR(radiusRatio(Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0)), kSqrt2 - 1, 1e-15);
}

TEST(RadiusRatio, RegularTetIsOneThird) {
  const Vector3d a(1, 1, 1), b(1, -1, -1), c(-1, 1, -1), d(-1, -1, 1);
  EXPECT_NEAR(radiusRatio(a, b, c, d), 1.0 / 3.0, 1e-15);
  EXPECT_NEAR(radiusRatio(a, b, d, c), 1.0 / 3.0, 1e-15);  // orientation does not matter
  // All six dihedral angles of a regular tet are acos(1/3).
  EXPECT_NEAR(minDihedralDeg(a, b, c, d), degrees(std::acos(1.0 / 3.0)), 1e-12);
  EXPECT_NEAR(minDihedralDeg(a, b, d, c), degrees(std::acos(1.0 / 3.0)), 1e-12);
}

TEST(RadiusRatio, CubeCornerTet) {
  // Corner of the unit cube: V = 1/6, faces 1/2, 1/2, 1/2 and sqrt3/2, so
  // r_in = 3V / S = 1 / (3 + sqrt 3); R_circ = half the cube diagonal = sqrt3 / 2.
  const Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0), d(0, 0, 1);
  const double expected = (1.0 / (3.0 + kSqrt3)) / (kSqrt3 / 2.0);
  EXPECT_NEAR(radiusRatio(a, b, c, d), expected, 1e-15);
  // Right angles at the three edges through the origin; the slanted face meets the
  // coordinate planes at acos(1/sqrt3) = 54.7356 degrees.
  EXPECT_NEAR(minDihedralDeg(a, b, c, d), degrees(std::acos(1.0 / kSqrt3)), 1e-12);
}

TEST(RadiusRatio, KuhnTet) {
  // Path (0,0,0) -> (1,0,0) -> (1,1,0) -> (1,1,1): faces 1/2, 1/2, sqrt2/2, sqrt2/2,
  // R_circ = sqrt3 / 2, V = 1/6, so q = (0.5 / (1 + sqrt 2)) / (sqrt3 / 2).
  const Vector3d a(0, 0, 0), b(1, 0, 0), c(1, 1, 0), d(1, 1, 1);
  EXPECT_NEAR(radiusRatio(a, b, c, d), 1.0 / (kSqrt3 * (1.0 + kSqrt2)), 1e-15);
  // Dihedral angles: 45 at the cube edges (a, b) and (c, d) (each shared by 2 of the 6
  // Kuhn tets), 60 at the main diagonal (a, d) (shared by all 6), 90 at the other three.
  EXPECT_NEAR(minDihedralDeg(a, b, c, d), 45.0, 1e-12);
}

TEST(RadiusRatio, DegenerateElementsGiveZeroNotNaN) {
  const Vector3d o(0, 0, 0), x(1, 0, 0), y(0, 1, 0);
  EXPECT_EQ(radiusRatio(o, x, Vector3d(2, 0, 0)), 0.0);  // collinear
  EXPECT_EQ(radiusRatio(o, o, y), 0.0);                  // coincident nodes
  EXPECT_EQ(radiusRatio(o, o, o), 0.0);
  EXPECT_EQ(radiusRatio(o, x, y, Vector3d(1, 1, 0)), 0.0);  // flat tet
  EXPECT_EQ(radiusRatio(o, x, y, y), 0.0);                  // repeated node
  EXPECT_EQ(radiusRatio(o, o, o, o), 0.0);
  EXPECT_EQ(minDihedralDeg(o, x, y, y), 0.0);
  EXPECT_EQ(minDihedralDeg(o, o, o, o), 0.0);
  // A flat tet with non-degenerate faces: two faces fold onto each other.
  EXPECT_NEAR(minDihedralDeg(o, x, y, Vector3d(1, 1, 0)), 0.0, 1e-12);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(radiusRatio(o, x, Vector3d(nan, 0, 0)), 0.0);
  EXPECT_EQ(radiusRatio(o, x, y, Vector3d(0, 0, nan)), 0.0);
  EXPECT_EQ(minDihedralDeg(o, x, y, Vector3d(0, 0, nan)), 0.0);
}

// --- independent computation -----------------------------------------------------------

// Circumcentre c of a tet from |c - a| = |c - b| = |c - d| = |c - e|, i.e. the 3x3 system
// 2 (p - a) . c = |p|^2 - |a|^2 for p = b, c, d.
double circumradiusBySolve(const Vector3d& a, const Vector3d& b, const Vector3d& c, const Vector3d& d) {
  Eigen::Matrix3d A;
  A.row(0) = 2 * (b - a).transpose();
  A.row(1) = 2 * (c - a).transpose();
  A.row(2) = 2 * (d - a).transpose();
  const Vector3d rhs(b.squaredNorm() - a.squaredNorm(), c.squaredNorm() - a.squaredNorm(),
                     d.squaredNorm() - a.squaredNorm());
  const Vector3d centre = A.fullPivLu().solve(rhs);
  return (centre - a).norm();
}

// Incentre = face-area-weighted mean of the vertices (weight of a vertex = area of the
// opposite face); the inradius is its distance to any face plane.
double inradiusByFacePlanes(const Vector3d& a, const Vector3d& b, const Vector3d& c, const Vector3d& d) {
  const Vector3d v[4] = {a, b, c, d};
  double weights[4];
  Vector3d incentre = Vector3d::Zero();
  double total = 0;
  for (int k = 0; k < 4; ++k) {
    const Vector3d& p = v[(k + 1) % 4];
    const Vector3d& q = v[(k + 2) % 4];
    const Vector3d& r = v[(k + 3) % 4];
    weights[k] = 0.5 * (q - p).cross(r - p).norm();
    incentre += weights[k] * v[k];
    total += weights[k];
  }
  incentre /= total;
  // Distance to each of the four face planes; they agree, take the mean of them.
  double sum = 0;
  for (int k = 0; k < 4; ++k) {
    const Vector3d& p = v[(k + 1) % 4];
    const Vector3d n = (v[(k + 2) % 4] - p).cross(v[(k + 3) % 4] - p).normalized();
    sum += std::abs(n.dot(incentre - p));
  }
  return sum / 4;
}

// Dihedral angle at edge (p, q): angle between the other two nodes projected onto the
// plane perpendicular to the edge.
double minDihedralByProjection(const Vector3d& a, const Vector3d& b, const Vector3d& c, const Vector3d& d) {
  const Vector3d v[4] = {a, b, c, d};
  double smallest = 360;
  for (int i = 0; i < 4; ++i) {
    for (int j = i + 1; j < 4; ++j) {
      int others[2], n = 0;
      for (int k = 0; k < 4; ++k)
        if (k != i && k != j) others[n++] = k;
      const Vector3d e = (v[j] - v[i]).normalized();
      Vector3d u = v[others[0]] - v[i];
      Vector3d w = v[others[1]] - v[i];
      u -= u.dot(e) * e;
      w -= w.dot(e) * e;
      smallest = std::min(smallest, degrees(std::atan2(u.cross(w).norm(), u.dot(w))));
    }
  }
  return smallest;
}

TEST(RadiusRatio, MatchesIndependentComputationOnRandomTets) {
  std::mt19937_64 rng(20240601);
  std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
  auto randomPoint = [&] { return Vector3d(coordinate(rng), coordinate(rng), coordinate(rng)); };
  int checked = 0;
  while (checked < 200) {
    const Vector3d a = randomPoint(), b = randomPoint(), c = randomPoint(), d = randomPoint();
    const double q = radiusRatio(a, b, c, d);
    // Slivers make the reference's linear solve ill-conditioned; they are covered above.
    if (q < 0.05) continue;
    const double reference = inradiusByFacePlanes(a, b, c, d) / circumradiusBySolve(a, b, c, d);
    EXPECT_NEAR(q, reference, 1e-12) << "tet " << checked;
    EXPECT_NEAR(minDihedralDeg(a, b, c, d), minDihedralByProjection(a, b, c, d), 1e-12) << "tet " << checked;
    ++checked;
  }
}

TEST(RadiusRatio, MatchesIndependentComputationOnRandomTriangles) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
  auto randomPoint = [&] { return Vector3d(coordinate(rng), coordinate(rng), coordinate(rng)); };
  int checked = 0;
  while (checked < 200) {
    const Vector3d a = randomPoint(), b = randomPoint(), c = randomPoint();
    const double q = radiusRatio(a, b, c);
    if (q < 0.05) continue;
    // Circumcentre in the triangle's plane: c0 = a + s (b - a) + t (c - a) with
    // |c0 - a| = |c0 - b| = |c0 - c| gives a 2x2 system.
    const Vector3d u = b - a, w = c - a;
    Eigen::Matrix2d A;
    A << 2 * u.dot(u), 2 * u.dot(w), 2 * w.dot(u), 2 * w.dot(w);
    const Eigen::Vector2d st = A.fullPivLu().solve(Eigen::Vector2d(u.dot(u), w.dot(w)));
    const double circumradius = (st(0) * u + st(1) * w).norm();
    // Incentre weighted by opposite side lengths; inradius = distance to line (a, b).
    const double la = (c - b).norm(), lb = (a - c).norm(), lc = (b - a).norm();
    const Vector3d incentre = (la * a + lb * b + lc * c) / (la + lb + lc);
    const double inradius = u.cross(incentre - a).norm() / u.norm();
    EXPECT_NEAR(q, inradius / circumradius, 1e-12) << "triangle " << checked;
    ++checked;
  }
}

// --- whole meshes ----------------------------------------------------------------------

// Unit cube as 5 tets: 4 corner tets at the odd corners and the regular tet between them.
// Node i sits at (i & 1, (i >> 1) & 1, (i >> 2) & 1).
TetMesh cubeFiveTets() {
  TetMesh m;
  m.X.resize(8, 3);
  for (int i = 0; i < 8; ++i) m.X.row(i) << (i & 1), (i >> 1) & 1, (i >> 2) & 1;
  m.T.resize(5, 4);
  m.T << 1, 0, 3, 5,  //
      2, 0, 3, 6,     //
      4, 0, 5, 6,     //
      7, 3, 5, 6,     //
      0, 3, 5, 6;     // the regular tet
  for (int t = 0; t < 5; ++t) {
    if (tetVolume(m, t) < 0) std::swap(m.T(t, 2), m.T(t, 3));
  }
  m.material = Labels::Ones(5);
  return m;
}

TEST(Stats, UnitCubeFiveTets) {
  const TetMesh m = cubeFiveTets();
  ASSERT_TRUE(validate(m, {.requireAllNodesUsed = true}).ok()) << validate(m).error();
  const MeshStats s = computeStats(m);
  EXPECT_EQ(s.nodes, 8);
  EXPECT_EQ(s.elements, 5);
  // Volumes: four of 1/6 and one of 1/3; mean 1/5, population std 1/15.
  EXPECT_NEAR(s.size_min, 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(s.size_mean, 0.2, 1e-15);
  EXPECT_NEAR(s.size_std, 1.0 / 15.0, 1e-15);
  // 18 unique edges: the 12 cube edges (length 1) and 6 face diagonals (sqrt 2).
  EXPECT_NEAR(s.edge_min, 1.0, 1e-15);
  EXPECT_NEAR(s.edge_mean, (12.0 + 6.0 * kSqrt2) / 18.0, 1e-15);
  EXPECT_NEAR(s.edge_std, (kSqrt2 - 1.0) * std::sqrt(2.0 / 9.0), 1e-15);
  // Four corner tets and one regular tet.
  const double corner = (1.0 / (3.0 + kSqrt3)) / (kSqrt3 / 2.0);
  EXPECT_NEAR(s.q_min, corner, 1e-15);
  EXPECT_NEAR(s.q_mean, (4 * corner + 1.0 / 3.0) / 5.0, 1e-15);
  EXPECT_NEAR(s.q_std, 0.4 * (1.0 / 3.0 - corner), 1e-15);
  EXPECT_NEAR(s.dihedral_min_deg, degrees(std::acos(1.0 / kSqrt3)), 1e-12);
}

TEST(Stats, UnitCubeSixTets) {
  const TetMesh m = testing::boxTetMesh(1, 1, 1, 1.0);
  const MeshStats s = computeStats(m);
  EXPECT_EQ(s.nodes, 8);
  EXPECT_EQ(s.elements, 6);
  EXPECT_NEAR(s.size_min, 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(s.size_mean, 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(s.size_std, 0.0, 1e-15);
  // 19 unique edges: 12 cube edges, 6 face diagonals and the main diagonal.
  EXPECT_NEAR(s.edge_min, 1.0, 1e-15);
  EXPECT_NEAR(s.edge_mean, (12.0 + 6.0 * kSqrt2 + kSqrt3) / 19.0, 1e-15);
  const double mean = s.edge_mean;
  const double variance = (12.0 * (1 - mean) * (1 - mean) + 6.0 * (kSqrt2 - mean) * (kSqrt2 - mean) +
                           (kSqrt3 - mean) * (kSqrt3 - mean)) /
                          19.0;
  EXPECT_NEAR(s.edge_std, std::sqrt(variance), 1e-15);
  // Six congruent Kuhn tets.
  const double kuhn = 1.0 / (kSqrt3 * (1.0 + kSqrt2));
  EXPECT_NEAR(s.q_min, kuhn, 1e-15);
  EXPECT_NEAR(s.q_mean, kuhn, 1e-15);
  EXPECT_NEAR(s.q_std, 0.0, 1e-15);
  EXPECT_NEAR(s.dihedral_min_deg, 45.0, 1e-12);
}

TEST(Stats, ScaledBoxMesh) {
  // Stats scale as they should: volume h^3, edges h, q and angles not at all.
  const double h = 0.3;
  const MeshStats s = computeStats(testing::boxTetMesh(3, 2, 2, h));
  EXPECT_EQ(s.nodes, 4 * 3 * 3);
  EXPECT_EQ(s.elements, 6 * 12);
  EXPECT_NEAR(s.size_mean, h * h * h / 6.0, 1e-15);
  EXPECT_NEAR(s.edge_min, h, 1e-15);
  EXPECT_NEAR(s.q_min, 1.0 / (kSqrt3 * (1.0 + kSqrt2)), 1e-14);
  EXPECT_NEAR(s.dihedral_min_deg, 45.0, 1e-12);
}

TEST(Stats, TriangleMesh) {
  // Unit square as two right isosceles triangles, plus a node no triangle uses.
  TriMesh m;
  m.X.resize(5, 3);
  m.X << 0, 0, 0,  //
      1, 0, 0,     //
      1, 1, 0,     //
      0, 1, 0,     //
      9, 9, 0;
  m.F.resize(2, 3);
  m.F << 0, 1, 2,  //
      0, 2, 3;
  m.material = Labels::Zero(2);
  const MeshStats s = computeStats(m);
  EXPECT_EQ(s.nodes, 4);  // the unused node is not counted
  EXPECT_EQ(s.elements, 2);
  EXPECT_DOUBLE_EQ(s.size_min, 0.5);
  EXPECT_DOUBLE_EQ(s.size_mean, 0.5);
  EXPECT_DOUBLE_EQ(s.size_std, 0.0);
  // 5 unique edges: 4 sides and the diagonal.
  const double mean = (4.0 + kSqrt2) / 5.0;
  EXPECT_NEAR(s.edge_min, 1.0, 1e-15);
  EXPECT_NEAR(s.edge_mean, mean, 1e-15);
  EXPECT_NEAR(s.edge_std, std::sqrt((4 * (1 - mean) * (1 - mean) + (kSqrt2 - mean) * (kSqrt2 - mean)) / 5.0),
              1e-15);
  EXPECT_NEAR(s.q_min, kSqrt2 - 1, 1e-15);
  EXPECT_NEAR(s.q_mean, kSqrt2 - 1, 1e-15);
  EXPECT_NEAR(s.q_std, 0.0, 1e-15);
  EXPECT_NEAR(s.dihedral_min_deg, 45.0, 1e-12);  // smallest interior angle
}

TEST(Stats, EmptyMeshesAreAllZero) {
  for (const MeshStats& s : {computeStats(TetMesh{}), computeStats(TriMesh{})}) {
    EXPECT_EQ(s.nodes, 0);
    EXPECT_EQ(s.elements, 0);
    EXPECT_EQ(s.size_min, 0.0);
    EXPECT_EQ(s.size_std, 0.0);
    EXPECT_EQ(s.edge_mean, 0.0);
    EXPECT_EQ(s.q_min, 0.0);
    EXPECT_EQ(s.dihedral_min_deg, 0.0);
  }
}

TEST(Stats, DegenerateElementShowsAsMinimumWithoutNaN) {
  TetMesh m = cubeFiveTets();
  m.X.row(7) = m.X.row(3);  // collapse node 7 onto node 3: the corner tet at 7 degenerates
  const MeshStats s = computeStats(m);
  EXPECT_EQ(s.q_min, 0.0);
  EXPECT_EQ(s.dihedral_min_deg, 0.0);
  EXPECT_EQ(s.edge_min, 0.0);
  EXPECT_EQ(s.size_min, 0.0);
  for (double v : {s.size_mean, s.size_std, s.edge_mean, s.edge_std, s.q_mean, s.q_std}) {
    EXPECT_TRUE(std::isfinite(v));
  }
}

TEST(Stats, SkipsElementsWithBadIndicesWithoutCrashing) {
  TetMesh m = cubeFiveTets();
  m.T(4, 0) = 2000000000;  // the regular tet now references a node that does not exist
  m.T(3, 1) = -5;          // and so does the corner tet at node 7
  const MeshStats s = computeStats(m);
  EXPECT_EQ(s.elements, 5);
  EXPECT_EQ(s.nodes, 8);  // the damaged tets' remaining valid references still count
  // Only the three intact corner tets enter the size and quality columns.
  EXPECT_NEAR(s.size_mean, 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(s.q_std, 0.0, 1e-15);
}

}  // namespace
}  // namespace hysim::cutting
