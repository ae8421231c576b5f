#pragma once
// Meshing a parametric organ (organ.hpp) with CGAL Mesh_3, and the cache that makes the
// second load of the same organ instant. The mesh is deterministic: the same organ gives the
// same file, byte for byte, on the same build.
#include <functional>
#include <string>

#include "hysim/cutting/mesh.hpp"
#include "hysim/cutting/result.hpp"
#include "hysim/engine/organ.hpp"

namespace hysim::engine {

// Meshing's stages, in order, for a progress bar.
enum class MeshStage { Refine, Perturb, Exude, Done };
const char* meshStageName(MeshStage stage);

// Delaunay refinement of the organ's labelled domain with its graded sizing, then sliver
// perturbation and exudation. Labels: organ.hpp. `onStage` is called as each stage begins.
Result<cutting::TetMesh> meshOrgan(const OrganSpec& organ, const std::function<void(MeshStage)>& onStage = {});

// Removes tets below `min_quality` (radius ratio) with two or more faces on the boundary:
// the flat surface slivers refinement leaves on curved boundaries. Returns how many went.
int peelBoundarySlivers(cutting::TetMesh& mesh, double min_quality);

// Renumbers nodes along a Morton curve of their positions, and tets by their smallest node:
// neighbours in space become neighbours in memory, which the force loop's caches feel.
void orderForLocality(cutting::TetMesh& mesh);

// Where meshed organs are kept: $HYSIM_CACHE_DIR, else $XDG_CACHE_HOME/hysim, else
// $HOME/.cache/hysim, else the system's temporary folder; then `organs/`.
std::string defaultOrganCacheDir();

struct OrganMeshOptions {
  std::string cache_dir;     // empty: defaultOrganCacheDir()
  bool progress = true;      // a progress bar on stderr when meshing takes over a second
  bool use_cache = true;     // false: always mesh (the file is still written to the cache)
};

struct OrganMeshFile {
  std::string path;          // the cached mesh
  bool cached = false;       // it was there already
  double seconds = 0.0;      // meshing time (0 when cached)
};

// The organ's mesh file, meshed now unless the cache has it. The cache key is organKey and
// the mesher's version; the file is written to a temporary name and renamed, so a meshing
// cut short leaves nothing behind.
Result<OrganMeshFile> organMeshFile(const OrganSpec& organ, const OrganMeshOptions& options = {});

}  // namespace hysim::engine
