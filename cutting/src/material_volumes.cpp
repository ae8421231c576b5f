// The volume each material label has in a cut's input and output (Cut3DReport's volume kept).
#include <algorithm>

#include "hysim/cutting/cut3d.hpp"
#include "optimize3d_internal.hpp"
#include "tet_geometry_inline.hpp"

namespace hysim::cutting {
namespace {

MaterialVolume& entryOf(std::vector<MaterialVolume>* volumes, std::int32_t label) {
  auto it = std::lower_bound(volumes->begin(), volumes->end(), label,
                             [](const MaterialVolume& m, std::int32_t l) { return m.label < l; });
  if (it == volumes->end() || it->label != label) it = volumes->insert(it, MaterialVolume{label, 0.0, 0.0});
  return *it;
}

}  // namespace

void addMaterialVolumes(const TetMesh& mesh, double MaterialVolume::*field, std::vector<MaterialVolume>* volumes,
                        const std::vector<std::uint8_t>* skip, const std::vector<std::uint8_t>* keepAnyway) {
  // Sums per label in a small table (labels 0..kSmall-1; others looked up), added in index
  // order within each label.
  constexpr std::int32_t kSmall = 16;
  double small[kSmall] = {};
  bool seen[kSmall] = {};
  const int M = mesh.numTets();
  const bool labelled = mesh.material.size() == M;
  const int skipN = skip != nullptr ? static_cast<int>(skip->size()) : 0;
  const int keepN = keepAnyway != nullptr ? static_cast<int>(keepAnyway->size()) : 0;
  for (int t = 0; t < M; ++t) {
    if (t < skipN && (*skip)[t] && !(t < keepN && (*keepAnyway)[t])) continue;
    const std::int32_t label = labelled ? mesh.material(t) : 0;
    const double v = tetVolumeHere(mesh, t);
    if (label >= 0 && label < kSmall) {
      small[label] += v;
      seen[label] = true;
    } else {
      entryOf(volumes, label).*field += v;
    }
  }
  for (std::int32_t label = 0; label < kSmall; ++label)
    if (seen[label]) entryOf(volumes, label).*field += small[label];
}

std::vector<MaterialVolume> materialVolumes(const TetMesh& before) {
  std::vector<MaterialVolume> volumes;
  addMaterialVolumes(before, &MaterialVolume::before, &volumes);
  return volumes;
}

void addVolumesAfter(const TetMesh& after, std::vector<MaterialVolume>* volumes) {
  addMaterialVolumes(after, &MaterialVolume::after, volumes);
}

std::vector<MaterialVolume> materialVolumes(const TetMesh& before, const TetMesh& after) {
  std::vector<MaterialVolume> volumes = materialVolumes(before);
  addVolumesAfter(after, &volumes);
  return volumes;
}

}  // namespace hysim::cutting
