#pragma once
// Scenes: YAML files instructors write (schema: scenes/README.md). Loading checks every key
// and value; errors name the file, the line and the key.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "hysim/cutting/result.hpp"
#include "hysim/engine/assessment.hpp"
#include "hysim/engine/organ.hpp"
#include "hysim/haptics/trajectory.hpp"
#include "hysim/sim/model.hpp"

namespace hysim::engine {

// A region whose mesh nodes are anchored (held fixed): the tissue around the modelled part.
struct AnchorRegion {
  enum class Kind { Box, Sphere, OutsideEllipsoid };
  Kind kind = Kind::Box;
  Eigen::Vector3d a{0, 0, 0};  // box: min corner; sphere/ellipsoid: centre
  Eigen::Vector3d b{0, 0, 0};  // box: max corner; ellipsoid: semi-axes; sphere: (radius, -, -)
  bool contains(const Eigen::Vector3d& p) const;
};

struct ContactSettings {
  bool enabled = true;
  double stiffness_n_per_mm = 0.02;  // penalty stiffness per surface node
  double damping_n_s_per_mm = 0.0;   // penalty damping per surface node (normal velocity)
  double shaft_radius_mm = 4.0;      // resectoscope sheath (26 Fr)
  double shaft_length_mm = 60.0;     // modelled length behind the tip
  double loop_radius_mm = 3.5;       // electrode loop, as a sphere for contact until cutting arrives
  double loop_reach_mm = 12.0;       // loop centre ahead of the tip at extension 0
  double loop_drop_mm = 3.0;         // loop centre below the axis (towards -up)
};

// Safety checks that become events in the report (and warnings for the trainee).
struct SafetySettings {
  // A perforation event: the active loop's wire comes closer than this to the outer
  // (serosal) surface of the uterus, or beyond it.
  double perforation_margin_mm = 2.0;
};

struct CameraSettings {
  double lens_deg = 30.0;  // fore-oblique lens angle: 0, 12 or 30 in practice
  double fov_deg = 90.0;
  double light = 1.0;
};

struct RenderSettings {
  int width = 640;
  int height = 480;
  int every = 50;  // render a frame every k steps
};

// Free pieces of tissue a cut sets loose (not connected to anchored tissue). Either way their
// volume counts as resected; `Simulate` also keeps them as rigid bodies in the cavity.
struct ChipSettings {
  enum class Mode { Remove, Simulate };
  Mode mode = Mode::Remove;
  int max_chips = 16;                 // simulated at once; the oldest goes beyond this
  double drag_per_s = 10.0;           // linear velocity decays as exp(-drag t) (distension fluid)
  double angular_drag_per_s = 20.0;   // same for the angular velocity
  double fluid_density_g_cm3 = 1.0;   // buoyancy: a chip sinks with g (1 - rho_fluid / rho_chip)
  double friction = 0.8;              // Coulomb friction coefficient on the wall and the tool
  // false (the default): the cut's optimisation leaves the pieces it cuts off (the chips) as
  // the cut made them and works on the anchored tissue only (Cut3DOptions::anchored_nodes;
  // faster). The chips' volumes are then the cut's own. true: the chips are optimised too.
  bool optimize = false;
};

// When a shaving pass's cut reaches the simulation: the cut runs on the cut worker from the
// step the loop leaves the tissue, and its result replaces the tissue K steps later
// (commit_steps), whatever the worker's timing (a late worker makes that step wait: a stall).
// Sync runs the same job on the simulation thread at the exit step (a reference: the same
// state sequence, to the last bit).
struct CutSettings {
  enum class Mode { Async, Sync };
  Mode mode = Mode::Async;
  int commit_steps = 20;
};

// How the simulated tool follows the device. Spring: the tool's tip is a proxy that a
// spring-damper pulls towards the device's tip while the tissue pushes it back (virtual
// coupling); the hand feels the spring. Its gains default to the device's stiffest spring and
// twice the passivity bound (haptics::couplingGains); a value > 0 here replaces one.
// Rigid: the tool is where the device is, and the hand feels the tissue's reaction directly.
struct CouplingSettings {
  enum class Mode { Spring, Rigid };
  Mode mode = Mode::Spring;
  double stiffness_n_per_mm = 0.0;  // 0: the device's max_stiffness_n_per_mm
  double damping_n_s_per_mm = 0.0;  // 0: k T (T the device's period): twice the passivity bound
};

struct Scene {
  std::string path;        // the scene file
  std::string name;
  std::string description;
  std::string figo_type;   // "0".."7" or "2-5"; empty: not given
  std::string difficulty;  // beginner, intermediate or advanced; empty: not given
  AssessmentSettings assessment;
  std::string mesh_path;   // resolved against the scene file's folder; empty: the organ's, meshed at load
  OrganSpec organ;         // the `organ:` section (organ.given), instead of `mesh`
  bool auto_tool_path = false;  // `tool_path: auto`: planned for the organ's myomas (shaving_path.hpp)
  std::string tool_mesh_path;  // optional; empty = no tool surface drawn
  std::vector<sim::Material> materials;
  std::vector<AnchorRegion> anchors;
  sim::ModelOptions sim;
  int steps = 1000;
  std::vector<haptics::Keyframe> tool_path;
  ContactSettings contact;
  SafetySettings safety;
  CameraSettings camera;
  RenderSettings render;
  ChipSettings chips;
  CutSettings cut;
  CouplingSettings coupling;
};

// Parses and checks a scene file. Does not load the meshes (see Simulation::create).
Result<Scene> loadScene(const std::string& path);
// The same over a scene file's text already in memory (fuzzing, tests): `path` names it in
// messages, and relative mesh paths are resolved against its folder.
Result<Scene> parseScene(const std::string& text, const std::string& path);

}  // namespace hysim::engine
