// cgal_mesh: a two-material tet mesh made by CGAL Mesh_3 (Delaunay refinement of an implicit
// domain), for the corpus of meshes from other meshers (tests/data/corpus, tools/make-corpus).
// The domain is an ellipsoid (label 1) holding an off-centre sphere (label 2, a myoma-like
// inclusion), so the mesh has a curved outer boundary and a curved material interface.
// Output: Gmsh MSH 2.2 ASCII, tets only, physical tag = label, positively oriented.
// Deterministic: the domain and every random draw of Mesh_3 use fixed seeds, and no step has a
// time limit.
//
// Usage: cgal_mesh OUT.msh [--size H] [--no-optimise]
//   --size H        facet and cell size bound in mm (default 3.2)
//   --no-optimise   skip sliver perturbation and exudation (the raw Delaunay refinement)
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Random.h>
#include <CGAL/make_mesh_3.h>

#include <CLI/CLI.hpp>
#include <array>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <vector>

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Domain = CGAL::Labeled_mesh_domain_3<K>;
using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr>;
using Criteria = CGAL::Mesh_criteria_3<Tr>;

// Ellipsoid semi-axes and the inclusion (mm): an organ-sized body, the inclusion near the wall.
constexpr double kA = 28, kB = 20, kC = 16;
constexpr double kIncX = 9, kIncY = -3, kIncZ = 2, kIncR = 7;

int label(const Point& p) {
  const double dx = p.x() - kIncX, dy = p.y() - kIncY, dz = p.z() - kIncZ;
  if (dx * dx + dy * dy + dz * dz < kIncR * kIncR) return 2;
  const double e = (p.x() / kA) * (p.x() / kA) + (p.y() / kB) * (p.y() / kB) + (p.z() / kC) * (p.z() / kC);
  return e < 1 ? 1 : 0;
}

C3t3 makeMesh(double size, bool optimise) {
  namespace params = CGAL::parameters;
  // The domain's own generator is seeded; this one covers any draw from the default generator.
  CGAL::get_default_random() = CGAL::Random(1);
  Domain domain(params::function = std::function<int(const Point&)>(label),
                params::bounding_object = K::Sphere_3(CGAL::ORIGIN, 31.0 * 31.0),
                params::relative_error_bound = 1e-6);
  Criteria criteria(params::facet_angle = 25, params::facet_size = size, params::facet_distance = 0.06 * size,
                    params::cell_radius_edge_ratio = 3, params::cell_size = size);
  // Time limit 0: no limit (the default, the refinement's own time, makes the result depend
  // on the machine's speed).
  if (optimise)
    return CGAL::make_mesh_3<C3t3>(domain, criteria, params::perturb(params::time_limit = 0),
                                   params::exude(params::time_limit = 0));
  return CGAL::make_mesh_3<C3t3>(domain, criteria, params::no_perturb(), params::no_exude());
}

// MSH 2.2: the vertices of the complex's cells, numbered from 1 in first-use order.
bool writeMsh(const C3t3& c3t3, const std::string& path) {
  std::map<Tr::Vertex_handle, int> index;
  std::vector<Point> points;
  std::vector<std::array<int, 5>> tets;  // four 1-based nodes, label
  for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c) {
    std::array<int, 5> t{};
    for (int k = 0; k < 4; ++k) {
      auto [it, added] = index.emplace(c->vertex(k), static_cast<int>(points.size()) + 1);
      if (added) points.push_back(c->vertex(k)->point().point());
      t[k] = it->second;
    }
    t[4] = c3t3.subdomain_index(c);
    // hysim wants (b - a) . ((c - a) x (d - a)) > 0; swap two nodes where CGAL's order differs.
    const Point& a = points[t[0] - 1];
    if (CGAL::orientation(a, points[t[1] - 1], points[t[2] - 1], points[t[3] - 1]) != CGAL::POSITIVE)
      std::swap(t[2], t[3]);
    tets.push_back(t);
  }
  std::ofstream out(path);
  if (!out) return false;
  char line[160];
  out << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n" << points.size() << "\n";
  for (size_t i = 0; i < points.size(); ++i) {
    std::snprintf(line, sizeof line, "%zu %.17g %.17g %.17g\n", i + 1, points[i].x(), points[i].y(), points[i].z());
    out << line;
  }
  out << "$EndNodes\n$Elements\n" << tets.size() << "\n";
  for (size_t e = 0; e < tets.size(); ++e) {
    const auto& t = tets[e];
    out << e + 1 << " 4 2 " << t[4] << " " << t[4] << " " << t[0] << " " << t[1] << " " << t[2] << " " << t[3] << "\n";
  }
  out << "$EndElements\n";
  return static_cast<bool>(out);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"cgal_mesh: a two-material ellipsoid tet mesh by CGAL Mesh_3, written as MSH 2.2"};
  std::string out;
  double size = 3.2;
  bool noOptimise = false;
  app.add_option("out", out, "output .msh file")->required();
  app.add_option("--size", size, "facet and cell size bound (mm)")->check(CLI::PositiveNumber);
  app.add_flag("--no-optimise", noOptimise, "skip sliver perturbation and exudation");
  CLI11_PARSE(app, argc, argv);
  const C3t3 c3t3 = makeMesh(size, !noOptimise);
  if (!writeMsh(c3t3, out)) {
    std::cerr << "cgal_mesh: cannot write " << out << "\n";
    return 1;
  }
  std::printf("cgal_mesh: wrote %s (%zu tets)\n", out.c_str(), static_cast<size_t>(c3t3.number_of_cells_in_complex()));
  return 0;
}
