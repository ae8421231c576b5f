#pragma once
// The peer of the accuracy study: Bullet's classic soft body (btSoftBody, position-based
// links) loaded with the case's nodes, masses, anchors and one link per tet edge, stepped
// at a fixed dt. Its link stiffness is a dimensionless factor in [0, 1] per solver
// iteration, not a spring constant: the report says so next to its numbers.
#include <memory>
#include <vector>

#include "hysim/engine/accuracy/cases.hpp"
#include "hysim/sim/model.hpp"

namespace hysim::engine::accuracy {

struct BulletOptions {
  double dt = 1e-3;            // s
  int position_iterations = 4; // btSoftBody::Config::piterations
  double link_stiffness = 1.0; // Material::m_kLST in [0, 1]
  double drag_per_s = 0.0;     // the case's drag, as Config::kDP = 1 - 1 / (1 + dt drag)
};

class BulletPeer {
 public:
  // `mass` and `fixed` per node, as the spring model has them (so masses match exactly); the
  // links' rest lengths from the mesh, the nodes then moved to `start` when given.
  BulletPeer(const AccuracyCase& c, const sim::Model& model, const BulletOptions& options,
             const sim::NodeVectors* start = nullptr);
  ~BulletPeer();
  BulletPeer(const BulletPeer&) = delete;
  BulletPeer& operator=(const BulletPeer&) = delete;

  void step();                                     // one dt
  void positions(sim::NodeVectors& x) const;       // current node positions (mm)

 private:
  struct World;
  std::unique_ptr<World> world_;
  BulletOptions options_;
};

}  // namespace hysim::engine::accuracy
