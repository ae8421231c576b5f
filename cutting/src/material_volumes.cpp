// The volume each material label has in a cut's input and output (Cut3DReport's volume kept).
#include <algorithm>

#include "hysim/cutting/cut3d.hpp"

namespace hysim::cutting {
namespace {

// Adds each tet's volume to its label's entry; the label of the last tet is looked up first
// because neighbouring tets mostly share a material.
void addVolumes(const TetMesh& mesh, double MaterialVolume::*field, std::vector<MaterialVolume>* volumes) {
  size_t last = 0;
  for (int t = 0; t < mesh.numTets(); ++t) {
    const std::int32_t label = mesh.material.size() == mesh.numTets() ? mesh.material(t) : 0;
    if (last >= volumes->size() || (*volumes)[last].label != label) {
      auto it = std::lower_bound(volumes->begin(), volumes->end(), label,
                                 [](const MaterialVolume& m, std::int32_t l) { return m.label < l; });
      if (it == volumes->end() || it->label != label) it = volumes->insert(it, MaterialVolume{label, 0.0, 0.0});
      last = static_cast<size_t>(it - volumes->begin());
    }
    (*volumes)[last].*field += tetVolume(mesh, t);
  }
}

}  // namespace

std::vector<MaterialVolume> materialVolumes(const TetMesh& before, const TetMesh& after) {
  std::vector<MaterialVolume> volumes;
  addVolumes(before, &MaterialVolume::before, &volumes);
  addVolumes(after, &MaterialVolume::after, &volumes);
  return volumes;
}

}  // namespace hysim::cutting
