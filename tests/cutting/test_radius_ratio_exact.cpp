// radiusRatio / radiusRatioOriented (mesh_stats.hpp, SSE2 lanes) against the plain Eigen
// formula they replace, bit for bit: the optimiser's decisions depend on every bit of q*.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::cutting {
namespace {

using Eigen::Vector3d;

// The formula as it was (37389c3), in plain Eigen.
double eigenRadiusRatio(const Vector3d& a, const Vector3d& b, const Vector3d& c, const Vector3d& d) {
  const double volume = std::abs((b - a).dot((c - a).cross(d - a))) / 6.0;
  const double p = (b - a).norm() * (d - c).norm();
  const double q = (c - a).norm() * (d - b).norm();
  const double r = (d - a).norm() * (c - b).norm();
  const double product = std::max(0.0, (p + q + r) * (p + q - r) * (p - q + r) * (-p + q + r));
  const double faceArea = 0.5 * ((b - a).cross(c - a).norm() + (b - a).cross(d - a).norm() +
                                 (c - a).cross(d - a).norm() + (c - b).cross(d - b).norm());
  const double denominator = faceArea * std::sqrt(product);
  if (!(denominator > 0) || !std::isfinite(denominator)) return 0.0;
  const double ratio = 72.0 * volume * volume / denominator;
  return std::isfinite(ratio) ? ratio : 0.0;
}
double eigenOriented(const Vector3d& a, const Vector3d& b, const Vector3d& c, const Vector3d& d) {
  if (!((b - a).dot((c - a).cross(d - a)) > 0)) return -1.0;
  return eigenRadiusRatio(a, b, c, d);
}

bool same(double x, double y) { return std::memcmp(&x, &y, sizeof x) == 0; }

struct Checker {
  long checked = 0, failed = 0;
  void operator()(const Vector3d& a, const Vector3d& b, const Vector3d& c, const Vector3d& d) {
    // All 24 orders would be slow; the identity, a swap and a rotation of the four.
    const Vector3d* orders[3][4] = {{&a, &b, &c, &d}, {&b, &a, &c, &d}, {&c, &d, &a, &b}};
    for (const auto& o : orders) {
      const double got = radiusRatio(*o[0], *o[1], *o[2], *o[3]);
      const double want = eigenRadiusRatio(*o[0], *o[1], *o[2], *o[3]);
      const double gotO = radiusRatioOriented(*o[0], *o[1], *o[2], *o[3]);
      const double wantO = eigenOriented(*o[0], *o[1], *o[2], *o[3]);
      ++checked;
      if (!same(got, want) || !same(gotO, wantO)) {
        if (++failed <= 5)
          ADD_FAILURE() << std::hexfloat << "a " << o[0]->transpose() << " b " << o[1]->transpose() << " c "
                        << o[2]->transpose() << " d " << o[3]->transpose() << ": " << got << " vs " << want << ", "
                        << gotO << " vs " << wantO;
      }
    }
  }
};

TEST(RadiusRatio, BitIdenticalToEigenFormula) {
  std::mt19937_64 rng(0x5eed10);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> small(-3, 3), expo(-300, 300);
  auto rp = [&] { return Vector3d(unit(rng), unit(rng), unit(rng)); };
  Checker check;
  constexpr int kN = 200000;
  for (int i = 0; i < kN; ++i) {
    // Random tets in a unit box.
    check(rp(), rp(), rp(), rp());
    // Mesh-like: a regular-ish tet of edge ~0.3 mm far from the origin, jittered.
    {
      const Vector3d o(12.3 + unit(rng), -7.9 + unit(rng), 40.1 + unit(rng));
      const double h = 0.3 * std::exp2(unit(rng) * 4);
      check(o + h * rp(), o + h * rp(), o + h * rp(), o + h * rp());
    }
    // Near-flat: d in the plane of a, b, c plus a tiny offset (or none).
    {
      const Vector3d a = rp(), b = rp(), c = rp();
      const double s = unit(rng), t = unit(rng);
      const double eps = (i % 4 == 0) ? 0.0 : std::ldexp(unit(rng), -20 - (i % 35));
      check(a, b, c, a + s * (b - a) + t * (c - a) + eps * rp());
    }
    // Exactly flat and near-degenerate on a small integer grid (ties, zero volume, repeats).
    check(Vector3d(small(rng), small(rng), small(rng)), Vector3d(small(rng), small(rng), small(rng)),
          Vector3d(small(rng), small(rng), 0), Vector3d(small(rng), small(rng), 0));
    check(Vector3d(small(rng), small(rng), small(rng)), Vector3d(small(rng), small(rng), small(rng)),
          Vector3d(small(rng), small(rng), small(rng)), Vector3d(small(rng), small(rng), small(rng)));
    // Needles and caps: three nodes close together, or two pairs.
    {
      const Vector3d a = rp(), d = rp();
      const double e = std::ldexp(1.0, -(i % 50));
      check(a, a + e * rp(), a + e * rp(), d);
      check(a, a + e * rp(), d, d + e * rp());
    }
    // Huge and tiny scales (overflow to inf, underflow to subnormals and zero).
    {
      const double sc = std::ldexp(1.0, expo(rng) + (i % 2 ? 700 : -700) * (i % 3 == 0));
      check(sc * rp(), sc * rp(), sc * rp(), sc * rp());
      const Vector3d o = std::ldexp(1.0, expo(rng)) * rp();
      const double h = std::ldexp(1.0, expo(rng));
      check(o + h * rp(), o + h * rp(), o + h * rp(), o + h * rp());
    }
  }
  // Repeated nodes and the regular tet.
  const Vector3d a(0, 0, 0), b(1, 0, 0), c(0.5, std::sqrt(3.0) / 2, 0), d(0.5, std::sqrt(3.0) / 6, std::sqrt(6.0) / 3);
  check(a, b, c, d);
  check(a, a, c, d);
  check(a, a, a, a);
  check(a, b, b, b);
  EXPECT_EQ(check.failed, 0) << "of " << check.checked;
  EXPECT_GT(check.checked, 10 * kN);
}

}  // namespace
}  // namespace hysim::cutting
