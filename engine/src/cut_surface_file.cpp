#include "hysim/engine/cut_surface_file.hpp"

#include "hysim/cutting/mesh_io.hpp"
#include "hysim/engine/simulation.hpp"

namespace hysim::engine {
namespace {

bool isMeshFile(const std::string& path) {
  if (path.size() <= 4) return false;
  const std::string ext = path.substr(path.size() - 4);
  return ext == ".msh" || ext == ".vtk";
}

// A surface assimp read, as the position and triangle arrays CutSurface takes.
Result<cutting::CutSurface> fromSurfaceMesh(const std::string& path, const render::SurfaceMesh& mesh) {
  cutting::Positions X(static_cast<Eigen::Index>(mesh.positions.size() / 3), 3);
  for (Eigen::Index i = 0; i < X.rows(); ++i)
    for (int k = 0; k < 3; ++k) X(i, k) = mesh.positions[3 * i + k];
  cutting::Tris F(static_cast<Eigen::Index>(mesh.triangles.size() / 3), 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) F(f, k) = static_cast<std::int32_t>(mesh.triangles[3 * f + k]);
  auto s = cutting::CutSurface::triangles(X, F);
  if (!s.ok()) return Error{path + ": " + s.error()};
  return s;
}

}  // namespace

Result<cutting::CutSurface> loadCutSurface(const std::string& path) {
  if (isMeshFile(path)) {
    auto tri = cutting::readTriMesh(path);
    if (!tri.ok()) return Error{tri.error()};
    auto s = cutting::CutSurface::triangles(tri->X, tri->F);
    if (!s.ok()) return Error{path + ": " + s.error()};
    return s;
  }
  auto mesh = loadSurface(path, render::SurfaceMaterial{});
  if (!mesh.ok()) return Error{mesh.error()};
  return fromSurfaceMesh(path, *mesh);
}

}  // namespace hysim::engine
