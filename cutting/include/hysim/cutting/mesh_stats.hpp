#pragma once
// Mesh statistics with the paper's columns (Tables 1 and 2).
#include <algorithm>
#include <cmath>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "hysim/cutting/mesh.hpp"

namespace hysim::cutting {

// Standard deviations are population standard deviations (divide by n).
struct MeshStats {
  int nodes = 0;            // #N: nodes referenced by at least one element
  int elements = 0;         // #E
  double size_min = 0, size_mean = 0, size_std = 0;  // area (2D) or volume (3D)
  double edge_min = 0, edge_mean = 0, edge_std = 0;  // over unique edges
  double q_min = 0, q_mean = 0, q_std = 0;           // r_in / R_circ: [0,1/2] triangles, [0,1/3] tets
  double dihedral_min_deg = 0;  // tets: minimum dihedral angle; triangles: minimum interior angle
};

// q = r_in / R_circ of one element.
double radiusRatio(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);
namespace detail {
// radiusRatio of the tet (a, b, c, d); with `oriented`, -1 where the tet is not positively
// oriented ((b - a).dot((c - a).cross(d - a)) not > 0), the optimiser's test.
// The same value, bit for bit, as the plain Eigen formula (kept in tests/cutting/
// test_radius_ratio_exact.cpp, RadiusRatio.BitIdenticalToEigenFormula):
//   volume = |(b - a).dot((c - a).cross(d - a))| / 6
//   p = |b - a| |d - c|, q = |c - a| |d - b|, r = |d - a| |c - b|
//   product = max(0, (p + q + r)(p + q - r)(p - q + r)(-p + q + r))
//   faceArea = 0.5 (|(b-a)x(c-a)| + |(b-a)x(d-a)| + |(c-a)x(d-a)| + |(c-b)x(d-b)|)
// Every value is computed by the operations Eigen uses, in its order (cross: y1 z2 - z1 y2,
// z1 x2 - x1 z2, x1 y2 - y1 x2; squared norm and dot (x + y) + z), two at a time in the two
// lanes of SSE2 registers; IEEE sqrt is correctly rounded, so sqrtpd's lanes equal std::sqrt.
// Lanes: L1 = (b - a, d - c), L2 = (c - a, d - b), L3 = (d - a, c - b) (p, q, r's pairs);
// faces F1 = ((b-a)x(c-a), (b-a)x(d-a)), F2 = ((c-a)x(d-a), (c-b)x(d-b)).
template <bool oriented>
inline double radiusRatioImpl(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                              const Eigen::Vector3d& d) {
#if defined(__SSE2__)
  __m128d X1, X2, X3, Y1, Y2, Y3, Z1, Z2, Z3;
  {
    // One coordinate: AB = (a, b), CD = (c, d).
    auto edges = [](double pa, double pb, double pc, double pd, __m128d& E1, __m128d& E2, __m128d& E3) {
      const __m128d AB = _mm_set_pd(pb, pa), CD = _mm_set_pd(pd, pc);
      E1 = _mm_sub_pd(_mm_unpackhi_pd(AB, CD), _mm_unpacklo_pd(AB, CD));  // (b - a, d - c)
      E2 = _mm_sub_pd(CD, AB);                                            // (c - a, d - b)
      E3 = _mm_sub_pd(_mm_shuffle_pd(CD, CD, 1), AB);                     // (d - a, c - b)
    };
    edges(a.x(), b.x(), c.x(), d.x(), X1, X2, X3);
    edges(a.y(), b.y(), c.y(), d.y(), Y1, Y2, Y3);
    edges(a.z(), b.z(), c.z(), d.z(), Z1, Z2, Z3);
  }
  auto sqNorm = [](__m128d x, __m128d y, __m128d z) {
    return _mm_add_pd(_mm_add_pd(_mm_mul_pd(x, x), _mm_mul_pd(y, y)), _mm_mul_pd(z, z));
  };
  // Faces: F1 = (u, u) x (v, w) with u = b - a, v = c - a, w = d - a; F2 = (v, c - b) x (w, d - b).
  auto u1 = [](__m128d E1, __m128d) { return _mm_unpacklo_pd(E1, E1); };
  auto v1 = [](__m128d E2, __m128d E3) { return _mm_unpacklo_pd(E2, E3); };
  auto u2 = [](__m128d E2, __m128d E3) { return _mm_shuffle_pd(E2, E3, 2); };  // (E2[0], E3[1])
  auto v2 = [](__m128d E2, __m128d E3) { return _mm_shuffle_pd(E3, E2, 2); };  // (E3[0], E2[1])
  const __m128d ux1 = u1(X1, X1), uy1 = u1(Y1, Y1), uz1 = u1(Z1, Z1);
  const __m128d vx1 = v1(X2, X3), vy1 = v1(Y2, Y3), vz1 = v1(Z2, Z3);
  const __m128d ux2 = u2(X2, X3), uy2 = u2(Y2, Y3), uz2 = u2(Z2, Z3);
  const __m128d vx2 = v2(X2, X3), vy2 = v2(Y2, Y3), vz2 = v2(Z2, Z3);
  const __m128d cx1 = _mm_sub_pd(_mm_mul_pd(uy1, vz1), _mm_mul_pd(uz1, vy1));
  const __m128d cy1 = _mm_sub_pd(_mm_mul_pd(uz1, vx1), _mm_mul_pd(ux1, vz1));
  const __m128d cz1 = _mm_sub_pd(_mm_mul_pd(ux1, vy1), _mm_mul_pd(uy1, vx1));
  const __m128d cx2 = _mm_sub_pd(_mm_mul_pd(uy2, vz2), _mm_mul_pd(uz2, vy2));
  const __m128d cy2 = _mm_sub_pd(_mm_mul_pd(uz2, vx2), _mm_mul_pd(ux2, vz2));
  const __m128d cz2 = _mm_sub_pd(_mm_mul_pd(ux2, vy2), _mm_mul_pd(uy2, vx2));
  // vol6 = (b - a).dot((c - a).cross(d - a)): lane 0 of L1 against lane 0 of F2.
  const double vol6 = _mm_cvtsd_f64(_mm_add_sd(_mm_add_sd(_mm_mul_sd(X1, cx2), _mm_mul_sd(Y1, cy2)), _mm_mul_sd(Z1, cz2)));
  if constexpr (oriented) {
    if (!(vol6 > 0)) return -1.0;
  }
  const __m128d L1 = _mm_sqrt_pd(sqNorm(X1, Y1, Z1));
  const __m128d L2 = _mm_sqrt_pd(sqNorm(X2, Y2, Z2));
  const __m128d L3 = _mm_sqrt_pd(sqNorm(X3, Y3, Z3));
  const __m128d A1 = _mm_sqrt_pd(sqNorm(cx1, cy1, cz1));
  const __m128d A2 = _mm_sqrt_pd(sqNorm(cx2, cy2, cz2));
  // (p, q) = (|b - a| |d - c|, |c - a| |d - b|), r = |d - a| |c - b|.
  const __m128d PQ = _mm_mul_pd(_mm_unpacklo_pd(L1, L2), _mm_unpackhi_pd(L1, L2));
  const double p = _mm_cvtsd_f64(PQ), q = _mm_cvtsd_f64(_mm_unpackhi_pd(PQ, PQ));
  const double r = _mm_cvtsd_f64(_mm_mul_sd(L3, _mm_unpackhi_pd(L3, L3)));
  const double volume = std::abs(vol6) / 6.0;
  const double product = std::max(0.0, (p + q + r) * (p + q - r) * (p - q + r) * (-p + q + r));
  const double faceArea = 0.5 * (_mm_cvtsd_f64(A1) + _mm_cvtsd_f64(_mm_unpackhi_pd(A1, A1)) + _mm_cvtsd_f64(A2) +
                                 _mm_cvtsd_f64(_mm_unpackhi_pd(A2, A2)));
  const double denominator = faceArea * _mm_cvtsd_f64(_mm_sqrt_sd(_mm_setzero_pd(), _mm_set_sd(product)));
#else
  const double vol6 = (b - a).dot((c - a).cross(d - a));
  if constexpr (oriented) {
    if (!(vol6 > 0)) return -1.0;
  }
  const double volume = std::abs(vol6) / 6.0;
  const double p = (b - a).norm() * (d - c).norm();
  const double q = (c - a).norm() * (d - b).norm();
  const double r = (d - a).norm() * (c - b).norm();
  const double product = std::max(0.0, (p + q + r) * (p + q - r) * (p - q + r) * (-p + q + r));
  const double faceArea = 0.5 * ((b - a).cross(c - a).norm() + (b - a).cross(d - a).norm() +
                                 (c - a).cross(d - a).norm() + (c - b).cross(d - b).norm());
  const double denominator = faceArea * std::sqrt(product);
#endif
  if (!(denominator > 0) || !std::isfinite(denominator)) return 0.0;
  const double ratio = 72.0 * volume * volume / denominator;
  return std::isfinite(ratio) ? ratio : 0.0;
}
}  // namespace detail

// Inline: the optimiser's hot loops evaluate it millions of times.
// r_in = 3V / S (S = total face area). The circumradius from the six edge lengths:
//   R = sqrt((p+q+r)(p+q-r)(p-q+r)(-p+q+r)) / (24 V)
// with p, q, r the products of the lengths of opposite edge pairs. Hence
//   q* = r_in / R = 72 V^2 / (S sqrt(...)).
// Rounding can push a factor of a degenerate tet slightly below zero; it is clamped.
inline double radiusRatio(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                          const Eigen::Vector3d& d) {
  return detail::radiusRatioImpl<false>(a, b, c, d);
}
// -1 where (b - a).dot((c - a).cross(d - a)) is not > 0 (inverted or flat), else radiusRatio.
inline double radiusRatioOriented(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                  const Eigen::Vector3d& d) {
  return detail::radiusRatioImpl<true>(a, b, c, d);
}
// Smallest of the six dihedral angles of a tet, in degrees.
double minDihedralDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                      const Eigen::Vector3d& d);

MeshStats computeStats(const TetMesh& mesh);
MeshStats computeStats(const TriMesh& mesh);

}  // namespace hysim::cutting
