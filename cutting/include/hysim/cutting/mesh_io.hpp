#pragma once
// Mesh files: Gmsh MSH 2.2 ASCII (read/write; physical tag = material) and legacy VTK
// ASCII unstructured grid (read/write). Errors name the file and line.
#include <string>
#include <variant>

#include "hysim/cutting/mesh.hpp"

namespace hysim::cutting {

// Reads a tet mesh: the file's tetrahedra (MSH type 4 / VTK cell type 10). Other element
// types of the format are ignored (in MSH files their node counts are checked); a type the
// format does not define is an error. Unused nodes are kept. Fails on a file without
// tetrahedra. The file must be a regular file of at most kMaxMeshFileBytes (input_file.hpp),
// with coordinates within +-kMaxCoordinateMm; VTK files must be legacy versions 1.0 to 5.1.
Result<TetMesh> readTetMesh(const std::string& path);
// Reads a triangle mesh: the file's triangles (MSH type 2 / VTK cell type 5).
Result<TriMesh> readTriMesh(const std::string& path);
// The same readers over a file's text already in memory (fuzzing, tests): `path` chooses the
// format by its extension (or the text's first line) and names the input in messages.
Result<TetMesh> parseTetMesh(const std::string& path, const std::string& text);
Result<TriMesh> parseTriMesh(const std::string& path, const std::string& text);

// Format chosen by extension: .msh or .vtk.
Status writeMesh(const std::string& path, const TetMesh& mesh);
Status writeMesh(const std::string& path, const TriMesh& mesh);

}  // namespace hysim::cutting
