#pragma once
// Chips: pieces of tissue a cut set free, simulated as rigid bodies (Bullet). Each chip is
// its convex hull; it sinks through the distension fluid (gravity less buoyancy, strong
// linear and angular drag), collides with the cavity wall (a static triangle mesh of the
// tissue's boundary, rebuilt after each cut) and with the resectoscope (kinematic bodies:
// the sheath as a capsule, the loop wire as a chain of thin capsules). Bullet stays behind
// this interface (a private dependency of the engine).
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "hysim/cutting/mesh.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/tool.hpp"
#include "hysim/haptics/trajectory.hpp"
#include "hysim/render/snapshot.hpp"
#include "hysim/sim/model.hpp"

namespace hysim::engine {

// A new chip, in world coordinates at the moment it comes free.
struct ChipShape {
  Eigen::Matrix<double, Eigen::Dynamic, 3> vertices;  // #V x 3 surface vertices, mm
  Eigen::Matrix<int, Eigen::Dynamic, 3> triangles;    // #F x 3 into vertices, outward
  std::vector<render::SurfaceMaterial> material;      // #V (drawing only)
  Eigen::Vector3d centre{0, 0, 0};                    // centre of mass, mm
  Eigen::Vector3d velocity{0, 0, 0};                  // mm/s
  double volume_mm3 = 0.0;
  double mass_g = 0.0;
};

// A simulated chip. Its frame has the origin at the centre of mass and the world's axes at
// the moment it came free.
struct ChipBody {
  int id = 0;                                         // 0, 1, 2... in order of creation
  double volume_mm3 = 0.0;
  double mass_g = 0.0;
  Eigen::Vector3d position{0, 0, 0};                  // centre of mass, mm
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // body -> world
  Eigen::Vector3d velocity{0, 0, 0};                  // mm/s
  bool sleeping = false;                              // at rest (Bullet deactivated it)
  render::SurfaceMesh surface;                        // body frame
};

// Sheath and loop of the resectoscope as the chips see them.
struct ChipToolGeometry {
  double shaft_radius_mm = 4.0;
  double shaft_length_mm = 60.0;  // behind the tip
  LoopGeometry loop;
};

class ChipWorld {
 public:
  // gravity in mm/s^2; dt the simulation's fixed step (s), split into substeps of <= 1 ms.
  ChipWorld(const ChipSettings& settings, const Eigen::Vector3d& gravity_mm_s2, double dt_s,
            const ChipToolGeometry& tool);
  ~ChipWorld();
  ChipWorld(const ChipWorld&) = delete;
  ChipWorld& operator=(const ChipWorld&) = delete;

  // The static cavity: boundary triangles (#B x 3 rows of x) in the positions x (#N x 3).
  // Allocates (a cut step). Chips stay asleep: addChip wakes those near the cut.
  void setCavity(const sim::NodeVectors& x, const cutting::Tris& faces);
  // Adds a chip; the oldest goes when there are more than max_chips. Wakes the chips within
  // 2 mm of its bounding box (the tissue they lay on may have been cut away). Allocates.
  int addChip(const ChipShape& shape);
  // The tool pose at the end of the coming step (the kinematic bodies move there during it).
  void moveTool(const haptics::ToolPose& pose);
  // Advances the chips by dt; chips that left the cavity (their centre more than 10 mm
  // outside the cavity's bounding box) are removed. Allocates nothing in steady state
  // (Bullet's arrays only grow).
  void step();

  const std::vector<ChipBody>& chips() const { return chips_; }
  int numChips() const { return static_cast<int>(chips_.size()); }
  int version() const { return version_; }  // changes when chips are added or removed
  int removedOutside() const { return removed_outside_; }  // chips that left the cavity
  int removedOverCap() const { return removed_over_cap_; }  // oldest, beyond max_chips
  int substeps() const { return substeps_; }
  // Continues an FNV-1a hash over the chips' ids and poses (bit patterns).
  std::uint64_t hash(std::uint64_t h) const;

 private:
  struct Impl;
  void removeChip(size_t index);
  void readBack();

  ChipSettings settings_;
  Eigen::Vector3d gravity_{0, 0, 0};
  double dt_ = 1e-3;
  int substeps_ = 1;
  std::unique_ptr<Impl> impl_;
  std::vector<ChipBody> chips_;
  int next_id_ = 0;
  int version_ = 0;
  int removed_outside_ = 0, removed_over_cap_ = 0;
  Eigen::Vector3d bounds_min_{0, 0, 0}, bounds_max_{0, 0, 0};
  bool has_cavity_ = false;
};

}  // namespace hysim::engine
