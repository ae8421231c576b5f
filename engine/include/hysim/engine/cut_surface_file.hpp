#pragma once
// Cut surfaces from files, for `hysim cut --surface` and the fuzz targets: the triangles of
// a .msh/.vtk mesh, or any surface assimp reads (STL, OBJ, PLY, glTF).
#include <string>

#include "hysim/cutting/cut_surface.hpp"
#include "hysim/cutting/result.hpp"

namespace hysim::engine {

// .msh and .vtk through the mesh readers (their triangles), anything else through
// loadSurface; errors name the file.
Result<cutting::CutSurface> loadCutSurface(const std::string& path);

}  // namespace hysim::engine
