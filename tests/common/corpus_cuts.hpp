#pragma once
// The mesh corpus of issue 34 (tests/data/corpus, tet meshes made by other meshers; see
// tools/make-corpus) and the cuts measured on it: random complete planes and curved cut
// surfaces (spherical and cylindrical patches, complete or ending inside the mesh). Shared by
// bench/cut_corpus (the full measurement) and tests/cutting/test_cut_corpus.cpp (a sample):
// case k of a mesh is the same cut in both, since each case draws from its own seed.
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>

#include "hysim/cutting/cut_surface.hpp"
#include "hysim/cutting/mesh.hpp"

namespace hysim::testing {

struct CorpusMesh {
  const char* file;    // in tests/data/corpus
  const char* mesher;  // and how it was run (tools/make-corpus)
  const char* flags;
};

inline constexpr std::array<CorpusMesh, 6> kCorpus = {{
    {"tetgen_ellipsoid_q.msh", "TetGen 1.5", "-pq1.4a100 (ellipsoid 26x19x15, icosphere level 2)"},
    {"tetgen_ellipsoid_noq.msh", "TetGen 1.5", "-pa30 (same surface, no quality bound)"},
    {"gmsh_ellipsoid.msh", "Gmsh 4.8", "-3, size 4.5 (ellipsoid 30x22x18)"},
    {"gmsh_capsule.msh", "Gmsh 4.8", "-3, size 2.5 (capsule r 10, length 50)"},
    {"cgal_ellipsoid_opt.msh", "CGAL 5.5 Mesh_3", "size 3.2, perturb + exude (ellipsoid + inclusion)"},
    {"cgal_ellipsoid_raw.msh", "CGAL 5.5 Mesh_3", "size 3.2, no perturb, no exude"},
}};

enum class CutKind { Plane, SphereComplete, SpherePartial, CylinderComplete, CylinderPartial };

inline const char* cutKindName(CutKind k) {
  switch (k) {
    case CutKind::Plane: return "plane";
    case CutKind::SphereComplete: return "sphere-complete";
    case CutKind::SpherePartial: return "sphere-partial";
    case CutKind::CylinderComplete: return "cylinder-complete";
    case CutKind::CylinderPartial: return "cylinder-partial";
  }
  return "?";
}

inline bool isComplete(CutKind k) { return k != CutKind::SpherePartial && k != CutKind::CylinderPartial; }

// One cut: a plane (point, normal) or a triangulated patch (X, F).
struct CorpusCut {
  CutKind kind = CutKind::Plane;
  Eigen::Vector3d point = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::UnitZ();
  cutting::Positions X;
  cutting::Tris F;
};

// Curved cases cycle through the four surface kinds.
inline CutKind surfaceKind(int k) {
  constexpr std::array<CutKind, 4> kinds = {CutKind::SphereComplete, CutKind::CylinderPartial,
                                            CutKind::CylinderComplete, CutKind::SpherePartial};
  return kinds[static_cast<size_t>(k) % kinds.size()];
}

namespace detail {

// A generator of its own per (mesh, family, case), so that any case can be made alone.
inline std::mt19937_64 caseRng(std::uint64_t seed, int mesh, int family, int k) {
  std::seed_seq s{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                  static_cast<std::uint32_t>(mesh), static_cast<std::uint32_t>(family), static_cast<std::uint32_t>(k)};
  return std::mt19937_64(s);
}

// A point in the middle `fraction` of the box and a random unit direction.
inline void randomPointAndNormal(const Eigen::AlignedBox3d& box, double fraction, std::mt19937_64& rng,
                                 Eigen::Vector3d* point, Eigen::Vector3d* normal) {
  std::uniform_real_distribution<double> u(0.5 - fraction / 2, 0.5 + fraction / 2), g(-1, 1);
  const Eigen::Vector3d t(u(rng), u(rng), u(rng));
  *point = box.min() + box.sizes().cwiseProduct(t);
  Eigen::Vector3d n;
  do n = Eigen::Vector3d(g(rng), g(rng), g(rng));
  while (n.norm() < 0.1 || n.norm() > 1);
  *normal = n.normalized();
}

// A patch of the sphere or the cylinder (axis along `axis`) of radius R whose surface passes
// through c with normal n there, centre (axis) at c + R n: rows over the angle around the
// centre from -angle to angle, columns over the second angle (sphere) or along the axis
// (cylinder, -half_length..half_length). Two triangles per grid quad.
inline void curvedPatch(bool sphere, const Eigen::Vector3d& c, const Eigen::Vector3d& n, const Eigen::Vector3d& axis,
                        double R, double angle, double half_length, int cells, cutting::Positions* X,
                        cutting::Tris* F) {
  const Eigen::Vector3d o = c + R * n, w = axis.cross(n).normalized();
  const int m = cells + 1;
  X->resize(m * m, 3);
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < m; ++i) {
      const double a = angle * (2.0 * i / cells - 1), s = 2.0 * j / cells - 1;
      Eigen::Vector3d p;
      if (sphere) {
        const double b = angle * s;  // second angle about w: a latitude-longitude grid near the pole -n
        p = o + R * (-std::cos(a) * std::cos(b) * n + std::sin(a) * std::cos(b) * w + std::sin(b) * axis);
      } else {
        p = o + R * (-std::cos(a) * n + std::sin(a) * w) + half_length * s * axis;
      }
      X->row(j * m + i) = p.transpose();
    }
  *F = cutting::CutSurface::stripTriangles(m, m);
}

}  // namespace detail

// Plane case k of mesh `mesh`: through the middle 40% of the bounding box, random normal.
inline CorpusCut corpusPlane(const cutting::TetMesh& m, int mesh, int k, std::uint64_t seed = 34) {
  const Eigen::AlignedBox3d box(m.X.colwise().minCoeff().transpose(), m.X.colwise().maxCoeff().transpose());
  auto rng = detail::caseRng(seed, mesh, 0, k);
  CorpusCut cut;
  detail::randomPointAndNormal(box, 0.4, rng, &cut.point, &cut.normal);
  return cut;
}

// Curved case k of mesh `mesh` (kind surfaceKind(k)). Complete patches reach every point of
// the bounding box around their point c (angle and length from the box diagonal), so they
// cut the mesh through; partial ones span 0.4 of the box's shortest side around c (in the
// middle 20%), so they end inside the mesh.
inline CorpusCut corpusSurface(const cutting::TetMesh& m, int mesh, int k, std::uint64_t seed = 34) {
  const Eigen::AlignedBox3d box(m.X.colwise().minCoeff().transpose(), m.X.colwise().maxCoeff().transpose());
  const double diag = box.diagonal().norm(), shortest = box.sizes().minCoeff();
  auto rng = detail::caseRng(seed, mesh, 1, k);
  CorpusCut cut;
  cut.kind = surfaceKind(k);
  const bool complete = isComplete(cut.kind);
  const bool sphere = cut.kind == CutKind::SphereComplete || cut.kind == CutKind::SpherePartial;
  detail::randomPointAndNormal(box, complete ? 0.4 : 0.2, rng, &cut.point, &cut.normal);
  // Complete: R >= 0.75 diag keeps the patch within 90 degrees of c (no fold-over).
  std::uniform_real_distribution<double> radius(complete ? 0.75 : 0.5, complete ? 2.0 : 1.5);
  const double R = radius(rng) * (complete ? diag : shortest);
  // Any axis across the normal.
  Eigen::Vector3d axis = cut.normal.unitOrthogonal();
  const double turn = std::uniform_real_distribution<double>(0, M_PI)(rng);
  axis = Eigen::AngleAxisd(turn, cut.normal) * axis;
  // A chord of length d from c subtends 2 asin(d / 2R) at the centre.
  const double reach = complete ? 1.05 * diag : 0.2 * shortest;
  const double angle = 2 * std::asin(std::min(1.0, reach / (2 * R)));
  const double halfLength = complete ? 1.05 * diag : 0.2 * shortest;
  detail::curvedPatch(sphere, cut.point, cut.normal, axis, R, angle, halfLength, complete ? 64 : 24, &cut.X, &cut.F);
  return cut;
}

}  // namespace hysim::testing
