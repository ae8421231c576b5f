#pragma once
// `hysim cut IN --plane ... | --surface FILE` for tetrahedral meshes (3D hybrid cutting and
// baselines) and `hysim tables --table 2`. Called from the `cut` / `tables` subcommands
// registered in cli_cut2d.cpp.
#include <string>

namespace hysim::tools {

struct Cut3dArgs {
  std::string in, out, plane, surface, method = "hybrid", stats;
};
int runCut3d(const Cut3dArgs& args);

struct Table2Options {
  std::string json_path;
  int repeats = 5;    // timed runs per cut (median reported)
  int uterus_cuts = 20;
  // PNG pictures of the Table-2 meshes (table2_initial / _standard / _hybrid_a / _hybrid_b.png,
  // 640 x 480): the boundary of each mesh, the pieces of a cut mesh moved apart (tet_picture.hpp).
  std::string pictures_dir;
};
int runTable2(const Table2Options& options);

}  // namespace hysim::tools
