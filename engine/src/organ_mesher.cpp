// The CGAL Mesh_3 side of organ meshing, alone in its own library: CGAL's compile flags and
// its long compile stay out of the rest of the engine.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Random.h>
#include <CGAL/make_mesh_3.h>

#include <algorithm>
#include <map>

#include "hysim/engine/organ_mesh.hpp"

namespace hysim::engine {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Domain = CGAL::Labeled_mesh_domain_3<K>;
using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr>;
using Criteria = CGAL::Mesh_criteria_3<Tr>;

Eigen::Vector3d toEigen(const Point& p) { return {p.x(), p.y(), p.z()}; }

// Delaunay refinement leaves edges well below its bounds, and more so where the bound is large:
// the bounds are scaled so that the mean edge comes out near the size asked (measured on the
// generated scenes: x1.2 near a myoma, x1.45 in the far wall).
double sizeScale(const OrganSpec& organ, double size) {
  const double span = std::max(organ.mesh.coarse_mm - organ.mesh.fine_mm, 1e-9);
  return 1.2 + 0.25 * std::clamp((size - organ.mesh.fine_mm) / span, 0.0, 1.0);
}
// Perturbation and exudation stop when no dihedral angle is below these (degrees). Perturbing
// towards a radius ratio instead gave q*_min 0.07-0.10 but took 2.5-29 s, unpredictably.
constexpr double kPerturbBoundDeg = 12.0;
constexpr double kSliverBoundDeg = 20.0;
// Surface slivers below this radius ratio are removed (organ_cleanup.cpp).
constexpr double kPeelBelowQuality = 0.12;

// CGAL's size bounds are circumradii: of the surface Delaunay balls (facets) and of the
// cells. An equilateral triangle's is 0.577 of its edge and a regular tet's 0.612.
struct SizeBound {
  const OrganSpec* organ;
  const std::vector<PlacedMyoma>* placed;
  double circumradius_per_edge;
  double operator()(const Point& p, int, const Domain::Index&) const {
    const double size = organSizeAt(*organ, *placed, toEigen(p));
    return circumradius_per_edge * sizeScale(*organ, size) * size;
  }
};

// Tets in first-use order of their vertices, positively oriented, labelled by subdomain.
cutting::TetMesh toTetMesh(const C3t3& c3t3) {
  std::map<Tr::Vertex_handle, int> index;
  std::vector<Point> points;
  std::vector<std::array<int, 5>> tets;
  for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c) {
    std::array<int, 5> t{};
    for (int k = 0; k < 4; ++k) {
      auto [it, added] = index.emplace(c->vertex(k), static_cast<int>(points.size()));
      if (added) points.push_back(c->vertex(k)->point().point());
      t[static_cast<size_t>(k)] = it->second;
    }
    t[4] = c3t3.subdomain_index(c);
    if (CGAL::orientation(points[t[0]], points[t[1]], points[t[2]], points[t[3]]) != CGAL::POSITIVE) std::swap(t[2], t[3]);
    tets.push_back(t);
  }
  cutting::TetMesh mesh;
  mesh.X.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i) mesh.X.row(static_cast<Eigen::Index>(i)) = toEigen(points[i]).transpose();
  mesh.T.resize(static_cast<Eigen::Index>(tets.size()), 4);
  mesh.material.resize(static_cast<Eigen::Index>(tets.size()));
  for (size_t e = 0; e < tets.size(); ++e) {
    for (int k = 0; k < 4; ++k) mesh.T(static_cast<Eigen::Index>(e), k) = tets[e][static_cast<size_t>(k)];
    mesh.material(static_cast<Eigen::Index>(e)) = tets[e][4];
  }
  return mesh;
}

}  // namespace

Result<cutting::TetMesh> meshOrgan(const OrganSpec& organ, const std::function<void(MeshStage)>& onStage) {
  namespace params = CGAL::parameters;
  auto stage = [&](MeshStage s) {
    if (onStage) onStage(s);
  };
  const std::vector<PlacedMyoma> placed = placeMyomas(organ);
  const double radius = organBoundingRadius(organ, placed);
  // The domain's own generator is seeded; this covers any draw from the default generator.
  CGAL::get_default_random() = CGAL::Random(1);
  auto label = [&organ, &placed](const Point& p) { return organLabel(organ, placed, toEigen(p)); };
  Domain domain(params::function = std::function<int(const Point&)>(label),
                params::bounding_object = K::Sphere_3(CGAL::ORIGIN, radius * radius),
                params::relative_error_bound = 1e-6);
  const Criteria criteria(params::facet_angle = 25, params::facet_size = SizeBound{&organ, &placed, 0.577},
                          params::facet_distance = 0.25, params::cell_radius_edge_ratio = 2.5,
                          params::cell_size = SizeBound{&organ, &placed, 0.612});
  stage(MeshStage::Refine);
  C3t3 c3t3 = CGAL::make_mesh_3<C3t3>(domain, criteria, params::no_perturb(), params::no_exude());
  // No time limits: a limit would make the mesh depend on the machine's speed. The sliver
  // bounds (dihedral angles, degrees) let both stages end.
  stage(MeshStage::Perturb);
  CGAL::perturb_mesh_3(c3t3, domain, params::time_limit = 0, params::sliver_bound = kPerturbBoundDeg);
  stage(MeshStage::Exude);
  CGAL::exude_mesh_3(c3t3, params::time_limit = 0, params::sliver_bound = kSliverBoundDeg);
  stage(MeshStage::Done);
  if (c3t3.number_of_cells_in_complex() == 0) return Error{"meshing the organ gave no tetrahedra"};
  cutting::TetMesh mesh = toTetMesh(c3t3);
  peelBoundarySlivers(mesh, kPeelBelowQuality);
  if (mesh.numTets() == 0) return Error{"meshing the organ gave no tetrahedra"};
  orderForLocality(mesh);
  return mesh;
}

}  // namespace hysim::engine
