#include "hysim/engine/accuracy/bullet_peer.hpp"

#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

namespace hysim::engine::accuracy {

struct BulletPeer::World {
  btSoftBodyRigidBodyCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btSoftRigidDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
  btSoftBody* body = nullptr;
  ~World() {
    if (body != nullptr) {
      world.removeSoftBody(body);
      delete body;
    }
  }
};

BulletPeer::BulletPeer(const AccuracyCase& c, const sim::Model& model, const BulletOptions& options,
                       const sim::NodeVectors* start)
    : world_(std::make_unique<World>()), options_(options) {
  World& w = *world_;
  btSoftBodyWorldInfo& info = w.world.getWorldInfo();
  info.m_gravity = btVector3(c.gravity.x(), c.gravity.y(), c.gravity.z());
  info.air_density = 0;
  info.water_density = 0;
  info.m_sparsesdf.Initialize();
  w.world.setGravity(info.m_gravity);
  const int n = model.num_nodes;
  std::vector<btVector3> x(n);
  std::vector<btScalar> m(n);
  for (int i = 0; i < n; ++i) {
    x[i] = btVector3(c.mesh.X(i, 0), c.mesh.X(i, 1), c.mesh.X(i, 2));
    m[i] = model.fixed[i] ? 0 : model.mass[i];
  }
  w.body = new btSoftBody(&info, n, x.data(), m.data());
  btSoftBody::Material* mat = w.body->m_materials[0];
  mat->m_kLST = static_cast<btScalar>(options.link_stiffness);
  for (int s = 0; s < model.springs.rows(); ++s) w.body->appendLink(model.springs(s, 0), model.springs(s, 1), mat);
  w.body->m_cfg.piterations = options.position_iterations;
  w.body->m_cfg.kDP = static_cast<btScalar>(1.0 - 1.0 / (1.0 + options.dt * options.drag_per_s));
  if (start != nullptr) {
    for (int i = 0; i < n; ++i) {
      const btVector3 p((*start)(i, 0), (*start)(i, 1), (*start)(i, 2));
      w.body->m_nodes[i].m_x = p;
      w.body->m_nodes[i].m_q = p;
    }
  }
  w.body->m_cfg.collisions = 0;  // no contacts in these cases
  w.world.addSoftBody(w.body);
}

BulletPeer::~BulletPeer() = default;

void BulletPeer::step() { world_->world.stepSimulation(static_cast<btScalar>(options_.dt), 0); }

void BulletPeer::positions(sim::NodeVectors& x) const {
  const btSoftBody& b = *world_->body;
  x.resize(b.m_nodes.size(), 3);
  for (int i = 0; i < b.m_nodes.size(); ++i) x.row(i) << b.m_nodes[i].m_x.x(), b.m_nodes[i].m_x.y(), b.m_nodes[i].m_x.z();
}

}  // namespace hysim::engine::accuracy
