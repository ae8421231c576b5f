#pragma once
// Paper-table reproduction (Table 1: 2D hybrid cutting against standard subdivision).
#include <string>

#include "hysim/cutting/mesh.hpp"

namespace hysim::tools {

// The Table-1 test meshes made with DistMesh: 1 (about 59 triangles, mean edge ~16.3) and
// 2 (about 298 triangles, mean edge ~3.45).
cutting::TriMesh table1Mesh(int which);

struct Table1Options {
  std::string json_path;      // write the rows as JSON here (optional)
  std::string pictures_dir;   // PNG pictures of each mesh before/after (optional)
  std::string meshes_dir;     // write the meshes (.msh) here (optional)
  int repeats = 200;          // timings are medians over this many runs
};

// Prints the table; returns the process exit status (0 ok, 1 error, 2 acceptance failed).
int runTable1(const Table1Options& options);

}  // namespace hysim::tools
