// DistMesh 2D with CGAL's Delaunay triangulation (exact predicates).
#include "distmesh.hpp"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

namespace hysim::tools {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<int, K>;
using Tds = CGAL::Triangulation_data_structure_2<Vb>;
using Delaunay = CGAL::Delaunay_triangulation_2<K, Tds>;
using Vec2 = Eigen::Vector2d;

std::vector<std::array<int, 3>> delaunay(const std::vector<Vec2>& p) {
  std::vector<std::pair<K::Point_2, int>> pts;
  pts.reserve(p.size());
  for (int i = 0; i < static_cast<int>(p.size()); ++i) pts.push_back({K::Point_2(p[i].x(), p[i].y()), i});
  Delaunay dt(pts.begin(), pts.end());
  std::vector<std::array<int, 3>> tris;
  for (auto f = dt.finite_faces_begin(); f != dt.finite_faces_end(); ++f)
    tris.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});  // CCW
  return tris;
}

}  // namespace

SignedDistance rectangleDistance(double x0, double y0, double x1, double y1) {
  return [=](const Vec2& p) {
    const double dx = std::max(x0 - p.x(), p.x() - x1), dy = std::max(y0 - p.y(), p.y() - y1);
    if (dx <= 0 && dy <= 0) return std::max(dx, dy);
    return std::hypot(std::max(dx, 0.0), std::max(dy, 0.0));
  };
}

SignedDistance circleDistance(double cx, double cy, double r) {
  return [=](const Vec2& p) { return std::hypot(p.x() - cx, p.y() - cy) - r; };
}

cutting::TriMesh distmesh2d(const SignedDistance& fd, const DistMeshOptions& o) {
  const double h0 = o.h0;
  const double geps = 1e-3 * h0, deps = std::sqrt(2.2e-16) * h0;
  // 1. Equilateral grid of points inside the domain, plus the fixed points.
  std::vector<Vec2> p = o.fixed;
  const int nfix = static_cast<int>(p.size());
  const double dy = h0 * std::sqrt(3.0) / 2;
  int row = 0;
  for (double y = o.box_min.y(); y <= o.box_max.y() + 1e-12; y += dy, ++row)
    for (double x = o.box_min.x() + (row % 2 ? h0 / 2 : 0); x <= o.box_max.x() + 1e-12; x += h0) {
      const Vec2 q(x, y);
      if (fd(q) >= geps) continue;
      bool dup = false;
      for (int i = 0; i < nfix; ++i) dup = dup || (p[i] - q).norm() < 1e-9 * h0;
      if (!dup) p.push_back(q);
    }
  const int n = static_cast<int>(p.size());
  std::vector<Vec2> pold(n, Vec2::Constant(1e300));
  std::vector<std::array<int, 3>> tris;
  std::vector<std::pair<int, int>> bars;
  for (int it = 0; it < o.max_iterations; ++it) {
    // 2. Re-triangulate when points moved more than ttol * h0.
    double moved = 0;
    for (int i = 0; i < n; ++i) moved = std::max(moved, (p[i] - pold[i]).norm());
    if (moved > o.ttol * h0) {
      pold = p;
      tris.clear();
      for (const auto& t : delaunay(p)) {
        const Vec2 c = (p[t[0]] + p[t[1]] + p[t[2]]) / 3.0;
        if (fd(c) < -geps) tris.push_back(t);
      }
      std::map<std::pair<int, int>, int> seen;
      bars.clear();
      for (const auto& t : tris)
        for (int k = 0; k < 3; ++k) {
          auto e = std::minmax(t[k], t[(k + 1) % 3]);
          if (seen.emplace(std::pair<int, int>(e.first, e.second), 1).second) bars.push_back({e.first, e.second});
        }
    }
    // 3. Bar forces: repulsive only, rest length scaled so the truss pushes outwards.
    double sumL2 = 0;
    std::vector<double> L(bars.size());
    for (std::size_t b = 0; b < bars.size(); ++b) {
      L[b] = (p[bars[b].first] - p[bars[b].second]).norm();
      sumL2 += L[b] * L[b];
    }
    const double L0 = o.fscale * std::sqrt(sumL2 / static_cast<double>(std::max<std::size_t>(bars.size(), 1)));
    std::vector<Vec2> ftot(n, Vec2::Zero());
    for (std::size_t b = 0; b < bars.size(); ++b) {
      const double F = std::max(L0 - L[b], 0.0);
      if (L[b] <= 0) continue;
      const Vec2 fv = F / L[b] * (p[bars[b].first] - p[bars[b].second]);
      ftot[bars[b].first] += fv;
      ftot[bars[b].second] -= fv;
    }
    for (int i = 0; i < nfix; ++i) ftot[i].setZero();
    double maxMove = 0;
    for (int i = 0; i < n; ++i) {
      p[i] += o.deltat * ftot[i];
      // 4. Project points that left the domain back onto its boundary.
      const double d = fd(p[i]);
      if (d > 0) {
        const Vec2 g((fd(p[i] + Vec2(deps, 0)) - d) / deps, (fd(p[i] + Vec2(0, deps)) - d) / deps);
        p[i] -= d * g / std::max(g.squaredNorm(), 1e-300);
      } else if (i >= nfix) {
        if (d < -geps) maxMove = std::max(maxMove, o.deltat * ftot[i].norm());
      }
    }
    if (maxMove < o.dptol * h0 && it > 0) break;
  }
  // Final triangulation.
  tris.clear();
  for (const auto& t : delaunay(p)) {
    const Vec2 c = (p[t[0]] + p[t[1]] + p[t[2]]) / 3.0;
    if (fd(c) < -geps) tris.push_back(t);
  }
  // Keep used points only.
  std::vector<int> id(n, -1);
  int m = 0;
  for (const auto& t : tris)
    for (int v : t)
      if (id[v] < 0) id[v] = m++;
  cutting::TriMesh mesh;
  mesh.X.setZero(m, 3);
  for (int i = 0; i < n; ++i)
    if (id[i] >= 0) mesh.X.row(id[i]) << p[i].x(), p[i].y(), 0.0;
  mesh.F.resize(static_cast<int>(tris.size()), 3);
  for (int f = 0; f < static_cast<int>(tris.size()); ++f)
    for (int k = 0; k < 3; ++k) mesh.F(f, k) = id[tris[f][k]];
  mesh.material.setConstant(static_cast<int>(tris.size()), 1);
  return mesh;
}

}  // namespace hysim::tools
