#pragma once
// Shaving scenes on a slab of tissue for the engine tests: 30 x 20 x 10 mm, top face at
// z = 0, anchored at the bottom. The scope points along +x with up = +z, so the loop (radius
// 3.5, centre 3 mm below the axis) hangs down; its lowest point is 2 mm below the top.
#include <filesystem>
#include <fstream>
#include <string>

#include "box_mesh.hpp"
#include "hysim/cutting/mesh_io.hpp"

namespace hysim::testing {

inline std::string slabSceneHead(const std::filesystem::path& dir, int steps) {
  cutting::TetMesh slab = boxTetMesh(15, 10, 5, 2.0);
  for (int i = 0; i < slab.numNodes(); ++i) slab.X.row(i) -= Eigen::RowVector3d(15, 10, 10);
  if (!cutting::writeMesh((dir / "slab.msh").string(), slab).ok()) return {};
  return "name: slab\n"
         "mesh: slab.msh\n"
         "materials:\n"
         "  - {name: myoma, label: 1, young_modulus_kpa: 150, density_g_cm3: 1.1}\n"
         "anchors:\n"
         "  - box: {min: [-20, -20, -11], max: [20, 20, -9.5]}\n"
         "simulation: {dt_ms: 1.0, steps: " +
         std::to_string(steps) + ", drag_per_s: 30, gravity_mm_s2: [0, 0, 0]}\n";
}

// One pass through the top layer (pedal down from 0.05 s to 1.05 s) unless pedal is false;
// `extra` is appended to the scene (e.g. "cut: {mode: sync}\n").
inline std::string writeSlabScene(const std::filesystem::path& dir, bool pedal, const std::string& extra = "") {
  const std::string p = pedal ? "true" : "false";
  const std::filesystem::path file = dir / (pedal ? "slab_cut.yaml" : "slab_nocut.yaml");
  std::ofstream(file) << slabSceneHead(dir, 1300) << extra
                      << "tool_path:\n"
                         "  - {t_s: 0.0, tip: [8, 0, 4.5], axis: [1, 0, 0], up: [0, 0, 1]}\n"
                         "  - {t_s: 0.05, tip: [8, 0, 4.5], axis: [1, 0, 0], up: [0, 0, 1], pedal: " << p << "}\n"
                         "  - {t_s: 1.05, tip: [-32, 0, 4.5], axis: [1, 0, 0], up: [0, 0, 1], pedal: " << p << "}\n"
                         "  - {t_s: 1.10, tip: [-32, 0, 4.5], axis: [1, 0, 0], up: [0, 0, 1]}\n";
  return file.string();
}

// Three overlapping passes (the second and third deeper, 2 mm to either side of the first,
// so their sweeps cross the first pass's cut surface, as shaving does), 5200 steps.
inline std::string writeThreePassSlabScene(const std::filesystem::path& dir, const std::string& extra = "") {
  const std::filesystem::path file = dir / "slab_passes.yaml";
  std::ofstream(file) << slabSceneHead(dir, 5200) << extra
                      << "tool_path:\n"
                         "  - {t_s: 0.0, tip: [8, 0, 4.5], axis: [1, 0, 0], up: [0, 0, 1]}\n"
                         "  - {t_s: 0.05, tip: [8, 0, 4.5], axis: [1, 0, 0], up: [0, 0, 1], pedal: true}\n"
                         "  - {t_s: 1.05, tip: [-32, 0, 4.5], axis: [1, 0, 0], up: [0, 0, 1], pedal: true}\n"
                         "  - {t_s: 1.10, tip: [-32, 0, 4.5], axis: [1, 0, 0], up: [0, 0, 1]}\n"
                         "  - {t_s: 1.30, tip: [-32, 0, 14], axis: [1, 0, 0], up: [0, 0, 1]}\n"
                         "  - {t_s: 1.80, tip: [8, 2, 14], axis: [1, 0, 0], up: [0, 0, 1]}\n"
                         "  - {t_s: 2.00, tip: [8, 2, 4.0], axis: [1, 0, 0], up: [0, 0, 1]}\n"
                         "  - {t_s: 2.05, tip: [8, 2, 4.0], axis: [1, 0, 0], up: [0, 0, 1], pedal: true}\n"
                         "  - {t_s: 3.05, tip: [-32, 2, 4.0], axis: [1, 0, 0], up: [0, 0, 1], pedal: true}\n"
                         "  - {t_s: 3.10, tip: [-32, 2, 4.0], axis: [1, 0, 0], up: [0, 0, 1]}\n"
                         "  - {t_s: 3.30, tip: [-32, 2, 14], axis: [1, 0, 0], up: [0, 0, 1]}\n"
                         "  - {t_s: 3.80, tip: [8, -2, 14], axis: [1, 0, 0], up: [0, 0, 1]}\n"
                         "  - {t_s: 4.00, tip: [8, -2, 3.7], axis: [1, 0, 0], up: [0, 0, 1]}\n"
                         "  - {t_s: 4.05, tip: [8, -2, 3.7], axis: [1, 0, 0], up: [0, 0, 1], pedal: true}\n"
                         "  - {t_s: 5.05, tip: [-32, -2, 3.7], axis: [1, 0, 0], up: [0, 0, 1], pedal: true}\n"
                         "  - {t_s: 5.10, tip: [-32, -2, 3.7], axis: [1, 0, 0], up: [0, 0, 1]}\n";
  return file.string();
}

}  // namespace hysim::testing
