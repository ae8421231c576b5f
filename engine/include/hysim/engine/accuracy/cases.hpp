#pragma once
// The accuracy study's cases: a body (tet mesh, materials, anchored nodes) and its loads.
// The same case goes to the spring network (every integrator), to CalculiX and to Bullet.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "hysim/cutting/mesh.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/sim/model.hpp"

namespace hysim::engine::accuracy {

struct AccuracyCase {
  std::string name;
  cutting::TetMesh mesh;
  std::vector<sim::Material> materials;
  std::vector<int> fixed;                 // anchored nodes
  Eigen::Vector3d gravity{0, 0, -9810};   // mm/s^2
  double drag_per_s = 0.0;                // the scene's drag (dynamic runs)
  std::vector<int> indenter;              // nodes the indenter moves (empty: no indentation)
  Eigen::Vector3d indent_direction{0, 0, 0};  // unit, into the tissue
  Eigen::Vector3d probe{0, 0, 0};         // the point whose displacement is plotted (beam tip)
};

// A square cantilever clamped at x = 0, lying along +x, gravity along -z: a structured grid
// of cubes of edge `cell`, six tets each.
struct BeamSpec {
  double length_mm = 50.0;
  double width_mm = 10.0;
  double cell_mm = 2.5;
  double young_pa = 500e3;
  double density_g_mm3 = 1.05e-3;
  double gravity_mm_s2 = 9810.0;
};
AccuracyCase beamCase(const BeamSpec& spec);

// R3: Euler-Bernoulli closed forms for the beam (uniform load rho g A).
double beamTipSagMm(const BeamSpec& spec);
double beamFirstFrequencyHz(const BeamSpec& spec);

// The scene's organ (or `mesh_path` meshed differently), its materials, anchors, gravity and
// drag; the indenter is the cavity-surface patch of radius `indenter_radius_mm` on the
// anterior wall (+y), pushed into the wall.
Result<AccuracyCase> organCase(const Scene& scene, const std::string& mesh_path = "",
                               double indenter_radius_mm = 2.5);

// Anchored nodes of `mesh` by the scene's anchor regions (rest positions).
std::vector<int> anchoredNodes(const Scene& scene, const cutting::TetMesh& mesh);

}  // namespace hysim::engine::accuracy
