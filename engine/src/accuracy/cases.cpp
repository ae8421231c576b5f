#include "hysim/engine/accuracy/cases.hpp"
#include "hysim/engine/organ_mesh.hpp"

#include <cmath>
#include <numbers>

#include "hysim/cutting/mesh_io.hpp"
#include "hysim/engine/tissue.hpp"

namespace hysim::engine::accuracy {
namespace {

// Six tets of the cube with corners c[0..7] (bit 0 = +x, bit 1 = +y, bit 2 = +z): the paths
// from corner 0 to corner 7 along the axes (Kuhn); neighbouring cubes share their faces.
void addCube(const int c[8], const cutting::Positions& X, std::vector<Eigen::Vector4i>& tets) {
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (const auto& p : perms) {
    const int v1 = 1 << p[0], v2 = v1 | (1 << p[1]);
    Eigen::Vector4i t(c[0], c[v1], c[v2], c[7]);
    const Eigen::Vector3d a = X.row(t[0]), b = X.row(t[1]), d = X.row(t[2]), e = X.row(t[3]);
    if ((b - a).dot((d - a).cross(e - a)) < 0.0) std::swap(t[2], t[3]);
    tets.push_back(t);
  }
}

}  // namespace

AccuracyCase beamCase(const BeamSpec& spec) {
  const int nx = std::max(1, static_cast<int>(std::lround(spec.length_mm / spec.cell_mm)));
  const int ny = std::max(1, static_cast<int>(std::lround(spec.width_mm / spec.cell_mm)));
  const int nz = ny;
  auto id = [&](int i, int j, int k) { return (k * (ny + 1) + j) * (nx + 1) + i; };
  AccuracyCase c;
  c.name = "beam";
  c.mesh.X.resize((nx + 1) * (ny + 1) * (nz + 1), 3);
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i)
        c.mesh.X.row(id(i, j, k)) = Eigen::RowVector3d(i * spec.length_mm / nx, (j * spec.width_mm / ny) - 0.5 * spec.width_mm,
                                                       (k * spec.width_mm / nz) - 0.5 * spec.width_mm);
  std::vector<Eigen::Vector4i> tets;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        int corners[8];
        for (int b = 0; b < 8; ++b) corners[b] = id(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
        addCube(corners, c.mesh.X, tets);
      }
  c.mesh.T.resize(static_cast<int>(tets.size()), 4);
  for (size_t t = 0; t < tets.size(); ++t) c.mesh.T.row(static_cast<int>(t)) = tets[t].transpose();
  c.mesh.material = cutting::Labels::Constant(c.mesh.numTets(), 1);
  sim::Material mat;
  mat.name = "beam";
  mat.label = 1;
  mat.young_modulus_pa = spec.young_pa;
  mat.density_g_mm3 = spec.density_g_mm3;
  c.materials = {mat};
  for (int i = 0; i < c.mesh.numNodes(); ++i)
    if (c.mesh.X(i, 0) == 0.0) c.fixed.push_back(i);
  c.gravity = Eigen::Vector3d(0, 0, -spec.gravity_mm_s2);
  c.probe = Eigen::Vector3d(spec.length_mm, 0, 0);
  return c;
}

double beamTipSagMm(const BeamSpec& s) {
  // w = q L^4 / (8 E I), q = rho g b^2, I = b^4 / 12.
  const double b2 = s.width_mm * s.width_mm;
  return 1.5 * s.density_g_mm3 * s.gravity_mm_s2 * std::pow(s.length_mm, 4) / (s.young_pa * b2);
}

double beamFirstFrequencyHz(const BeamSpec& s) {
  // f1 = (beta1 L)^2 / (2 pi L^2) sqrt(E I / (rho A)), beta1 L = 1.8751.
  const double beta = 1.875104068711961;
  const double ei_over_rho_a = s.young_pa * s.width_mm * s.width_mm / (12.0 * s.density_g_mm3);
  return beta * beta / (2.0 * std::numbers::pi * s.length_mm * s.length_mm) * std::sqrt(ei_over_rho_a);
}

std::vector<int> anchoredNodes(const Scene& scene, const cutting::TetMesh& mesh) {
  std::vector<int> fixed;
  for (int i = 0; i < mesh.numNodes(); ++i)
    if (anchoredAt(scene, mesh.X.row(i).transpose())) fixed.push_back(i);
  return fixed;
}

namespace {

// Free nodes on the boundary within `radius` of the anterior cavity wall's centre (the free
// boundary node furthest along +y near the x = 0, z = 0 line).
std::vector<int> anteriorIndenter(const cutting::TetMesh& mesh, const std::vector<int>& fixed, double radius) {
  std::vector<std::uint8_t> is_fixed(mesh.numNodes(), 0), on_boundary(mesh.numNodes(), 0);
  for (int i : fixed) is_fixed[i] = 1;
  const cutting::Tris faces = cutting::boundaryFaces(mesh);
  for (int f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) on_boundary[faces(f, k)] = 1;
  int centre = -1;
  for (int i = 0; i < mesh.numNodes(); ++i) {
    if (is_fixed[i] || !on_boundary[i] || std::abs(mesh.X(i, 0)) > 4.0 || std::abs(mesh.X(i, 2)) > 6.0) continue;
    if (centre < 0 || mesh.X(i, 1) > mesh.X(centre, 1)) centre = i;
  }
  std::vector<int> nodes;
  if (centre < 0) return nodes;
  for (int i = 0; i < mesh.numNodes(); ++i)
    if (!is_fixed[i] && on_boundary[i] && (mesh.X.row(i) - mesh.X.row(centre)).norm() <= radius) nodes.push_back(i);
  return nodes;
}

}  // namespace

Result<AccuracyCase> organCase(const Scene& scene, const std::string& mesh_path, double indenter_radius_mm) {
  std::string path = mesh_path.empty() ? scene.mesh_path : mesh_path;
  if (path.empty() && scene.organ.given) {  // a generated organ: its cached mesh
    auto meshed = organMeshFile(scene.organ);
    if (!meshed.ok()) return Error{scene.path + ": " + meshed.error()};
    path = meshed->path;
  }
  auto mesh = cutting::readTetMesh(path);
  if (!mesh.ok()) return Error{mesh.error()};
  AccuracyCase c;
  c.name = "organ";
  c.mesh = std::move(mesh.value());
  c.materials = scene.materials;
  c.fixed = anchoredNodes(scene, c.mesh);
  c.gravity = scene.sim.gravity;
  c.drag_per_s = scene.sim.drag_per_s;
  c.indenter = anteriorIndenter(c.mesh, c.fixed, indenter_radius_mm);
  c.indent_direction = Eigen::Vector3d(0, 1, 0);
  if (c.indenter.empty()) return Error{"organ: no free cavity-surface node on the anterior wall to indent"};
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (int i : c.indenter) centre += c.mesh.X.row(i).transpose();
  c.probe = centre / static_cast<double>(c.indenter.size());
  return c;
}

}  // namespace hysim::engine::accuracy
