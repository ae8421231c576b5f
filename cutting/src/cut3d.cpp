// Hybrid cutting of tetrahedral meshes (see cut3d.hpp for the outline): the driver over the
// stages in cut3d/, one file each.
#include "hysim/cutting/cut3d.hpp"

#include <chrono>
#include <string>
#include <utility>
#include <vector>

#include "cut3d/cut3d_stages.hpp"

namespace hysim::cutting {

namespace {

// What is wrong with the input or the options; empty where nothing is.
std::string inputError(const TetMesh& input, const Cut3DOptions& options) {
  const int N0 = input.numNodes(), M0 = input.numTets();
  if (M0 == 0 || N0 == 0) return "cut3d: empty mesh";
  if (input.material.size() != 0 && input.material.size() != M0) return "cut3d: material size differs from #T";
  if (input.T.minCoeff() < 0 || input.T.maxCoeff() >= N0)
    for (int t = 0; t < M0; ++t)
      for (int k = 0; k < 4; ++k)
        if (input.T(t, k) < 0 || input.T(t, k) >= N0)
          return "cut3d: tet " + std::to_string(t) + " has a node index out of range";
  if (!input.X.allFinite()) return "cut3d: non-finite node coordinates";
  if (!(options.snap_region >= 0 && options.snap_region <= 0.5)) return "cut3d: snap_region must be in [0, 0.5]";
  return {};
}

// Volume kept: every tet of the input and the output, per material (the input's already
// summed where the optimisation needed them).
void reportVolumes(const TetMesh& input, const TetMesh& output, std::vector<MaterialVolume> inputVolumes,
                   Cut3DReport* report) {
  if (inputVolumes.empty()) inputVolumes = materialVolumes(input);
  addVolumesAfter(output, &inputVolumes);
  report->material_volumes = std::move(inputVolumes);
  for (const MaterialVolume& m : report->material_volumes) {
    report->volume_before += m.before;
    report->volume_after += m.after;
  }
  report->volume_drift = report->volume_before - report->volume_after;
}

}  // namespace

Result<Cut3DResult> cut3d(const TetMesh& input, const CutSurface& surface, const Cut3DOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (std::string error = inputError(input, options); !error.empty()) return Error{std::move(error)};
  cut3d_detail::Cut3D cut(input, surface, options, start);
  if (!cut.classify()) return Error{"cut3d: degenerate mesh bounding box"};
  cut.snap();
  cut.subdivide();
  cut.separate();
  cut.assemble();
  cut.optimise();
  cut.compact();
  reportVolumes(input, cut.result.mesh, std::move(cut.inputVolumes), &cut.result.report);
  return std::move(cut.result);
}

}  // namespace hysim::cutting
