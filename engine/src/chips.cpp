#include "hysim/engine/chips.hpp"

#include <BulletCollision/CollisionShapes/btShapeHull.h>
#include <btBulletDynamicsCommon.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace hysim::engine {
namespace {

btVector3 toBt(const Eigen::Vector3d& v) {
  return {static_cast<btScalar>(v.x()), static_cast<btScalar>(v.y()), static_cast<btScalar>(v.z())};
}

btTransform toBt(const Eigen::Vector3d& origin, const Eigen::Matrix3d& r) {
  const btMatrix3x3 basis(static_cast<btScalar>(r(0, 0)), static_cast<btScalar>(r(0, 1)), static_cast<btScalar>(r(0, 2)),
                          static_cast<btScalar>(r(1, 0)), static_cast<btScalar>(r(1, 1)), static_cast<btScalar>(r(1, 2)),
                          static_cast<btScalar>(r(2, 0)), static_cast<btScalar>(r(2, 1)), static_cast<btScalar>(r(2, 2)));
  return btTransform(basis, toBt(origin));
}

// A capsule child from a to b (body frame): Bullet's Z capsule is centred and along z.
btTransform segmentFrame(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d d = (b - a).normalized();
  const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), d);
  return toBt(0.5 * (a + b), q.toRotationMatrix());
}

void mix(std::uint64_t& h, const void* data, size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
}

constexpr double kMaxSubstep = 1e-3;    // s
constexpr double kLeaveMarginMm = 10.0;  // outside the cavity's bounding box: gone
constexpr double kMinChipVolume = 1e-3;  // mm^3: smaller pieces are not simulated
constexpr int kMaxHullPoints = 32;       // more hull corners are reduced (contact cost)
// A chip slower than these for kSleepSeconds sleeps (no contact work) until something
// touches it. Bullet's defaults (0.8 and 1.0 for 2 s) are for metres and for scenes that do
// not change every two seconds; chips are millimetres wide and the contact jitter of a
// resting one is a few mm/s. The time is Bullet's global gDeactivationTime (Bullet is used
// for nothing else in the process).
constexpr float kSleepLinearMmS = 2.0f, kSleepAngularRadS = 0.5f, kSleepSeconds = 0.5f;
constexpr double kWakeMarginMm = 2.0;  // chips this close to a new chip's box are woken

}  // namespace

struct ChipWorld::Impl {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};

  // The static cavity wall (vertices and indices referenced by the triangle array).
  std::vector<float> cavity_vertices;  // #V*3
  std::vector<int> cavity_indices;     // #B*3
  std::unique_ptr<btTriangleIndexVertexArray> cavity_array;
  std::unique_ptr<btBvhTriangleMeshShape> cavity_shape;
  std::unique_ptr<btRigidBody> cavity_body;

  // The tool: sheath and loop, kinematic.
  std::unique_ptr<btCapsuleShapeZ> shaft_capsule;
  std::unique_ptr<btCompoundShape> shaft_shape;
  std::unique_ptr<btRigidBody> shaft_body;
  std::vector<std::unique_ptr<btCapsuleShapeZ>> wire;
  std::unique_ptr<btCompoundShape> loop_shape;
  std::unique_ptr<btRigidBody> loop_body;
  haptics::ToolPose from, to;  // tool pose at the start and the end of the coming step
  bool tool_placed = false;

  struct Body {
    std::unique_ptr<btConvexHullShape> shape;
    std::unique_ptr<btRigidBody> body;  // destroyed before its shape
  };
  std::vector<Body> bodies;  // same order as chips_

  // Places the kinematic tool at the pose interpolated at fraction s of the step.
  void placeTool(double s, bool teleport) {
    const Eigen::Vector3d tip = (1.0 - s) * from.tip + s * to.tip;
    const Eigen::Quaterniond qa(from.rotation), qb(to.rotation);
    const Eigen::Matrix3d r = qa.slerp(s, qb).toRotationMatrix();
    const double extension = (1.0 - s) * from.extension_mm + s * to.extension_mm;
    const btTransform shaft = toBt(tip, r);
    const btTransform loop = toBt(tip + extension * r.col(2), r);
    shaft_body->setWorldTransform(shaft);
    loop_body->setWorldTransform(loop);
    if (teleport) {  // no velocity from the jump
      shaft_body->setInterpolationWorldTransform(shaft);
      loop_body->setInterpolationWorldTransform(loop);
    }
  }

  void removeAll() {
    for (Body& b : bodies) world.removeRigidBody(b.body.get());
    bodies.clear();
    for (btRigidBody* b : {cavity_body.get(), shaft_body.get(), loop_body.get()}) {
      if (b != nullptr) world.removeRigidBody(b);
    }
  }
};

ChipWorld::ChipWorld(const ChipSettings& settings, const Eigen::Vector3d& gravity_mm_s2, double dt_s,
                     const ChipToolGeometry& tool)
    : settings_(settings), gravity_(gravity_mm_s2), dt_(dt_s), impl_(std::make_unique<Impl>()) {
  substeps_ = std::max(1, static_cast<int>(std::ceil(dt_ / kMaxSubstep - 1e-9)));
  Impl& m = *impl_;
  gDeactivationTime = kSleepSeconds;
  m.world.setGravity(toBt(gravity_));
  chips_.reserve(static_cast<size_t>(settings_.max_chips) + 1);
  m.bodies.reserve(static_cast<size_t>(settings_.max_chips) + 1);

  auto kinematic = [&](btCollisionShape* shape) {
    btRigidBody::btRigidBodyConstructionInfo info(0.0, nullptr, shape);
    info.m_friction = static_cast<btScalar>(settings_.friction);
    auto body = std::make_unique<btRigidBody>(info);
    body->setCollisionFlags(body->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
    body->setActivationState(DISABLE_DEACTIVATION);
    m.world.addRigidBody(body.get());
    return body;
  };
  // Sheath: a capsule of the sheath's radius from the tip back along -z (body frame).
  const double half = 0.5 * tool.shaft_length_mm;
  m.shaft_capsule = std::make_unique<btCapsuleShapeZ>(static_cast<btScalar>(tool.shaft_radius_mm),
                                                      static_cast<btScalar>(tool.shaft_length_mm));
  m.shaft_shape = std::make_unique<btCompoundShape>(false, 1);
  m.shaft_shape->addChildShape(toBt(Eigen::Vector3d(0, 0, -half), Eigen::Matrix3d::Identity()), m.shaft_capsule.get());
  m.shaft_body = kinematic(m.shaft_shape.get());
  // Loop: thin capsules along the wire at extension 0; the body slides out with the extension.
  Eigen::Matrix<double, Eigen::Dynamic, 3> points;
  loopPoints(tool.loop, haptics::ToolPose{}, points);
  m.loop_shape = std::make_unique<btCompoundShape>(false, static_cast<int>(points.rows()));
  for (Eigen::Index i = 0; i + 1 < points.rows(); ++i) {
    const Eigen::Vector3d a = points.row(i).transpose(), b = points.row(i + 1).transpose();
    m.wire.push_back(std::make_unique<btCapsuleShapeZ>(static_cast<btScalar>(tool.loop.wire_radius_mm),
                                                       static_cast<btScalar>((b - a).norm())));
    m.loop_shape->addChildShape(segmentFrame(a, b), m.wire.back().get());
  }
  m.loop_body = kinematic(m.loop_shape.get());
  m.placeTool(0.0, true);
}

ChipWorld::~ChipWorld() { impl_->removeAll(); }

void ChipWorld::setCavity(const sim::NodeVectors& x, const cutting::Tris& faces) {
  Impl& m = *impl_;
  if (m.cavity_body) m.world.removeRigidBody(m.cavity_body.get());
  m.cavity_body.reset();
  m.cavity_shape.reset();
  m.cavity_array.reset();
  m.cavity_vertices.clear();
  m.cavity_indices.clear();
  has_cavity_ = faces.rows() > 0;
  if (!has_cavity_) return;
  std::vector<int> local(static_cast<size_t>(x.rows()), -1);
  bounds_min_.setConstant(std::numeric_limits<double>::infinity());
  bounds_max_ = -bounds_min_;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    for (int c = 0; c < 3; ++c) {
      const int node = faces(f, c);
      if (local[node] < 0) {
        local[node] = static_cast<int>(m.cavity_vertices.size() / 3);
        for (int k = 0; k < 3; ++k) m.cavity_vertices.push_back(static_cast<float>(x(node, k)));
        bounds_min_ = bounds_min_.cwiseMin(x.row(node).transpose());
        bounds_max_ = bounds_max_.cwiseMax(x.row(node).transpose());
      }
      m.cavity_indices.push_back(local[node]);
    }
  }
  btIndexedMesh mesh;
  mesh.m_numTriangles = static_cast<int>(faces.rows());
  mesh.m_triangleIndexBase = reinterpret_cast<const unsigned char*>(m.cavity_indices.data());
  mesh.m_triangleIndexStride = 3 * sizeof(int);
  mesh.m_numVertices = static_cast<int>(m.cavity_vertices.size() / 3);
  mesh.m_vertexBase = reinterpret_cast<const unsigned char*>(m.cavity_vertices.data());
  mesh.m_vertexStride = 3 * sizeof(float);
  mesh.m_indexType = PHY_INTEGER;
  mesh.m_vertexType = PHY_FLOAT;
  m.cavity_array = std::make_unique<btTriangleIndexVertexArray>();
  m.cavity_array->addIndexedMesh(mesh, PHY_INTEGER);
  m.cavity_shape = std::make_unique<btBvhTriangleMeshShape>(m.cavity_array.get(), true);
  btRigidBody::btRigidBodyConstructionInfo info(0.0, nullptr, m.cavity_shape.get());
  info.m_friction = static_cast<btScalar>(settings_.friction);
  m.cavity_body = std::make_unique<btRigidBody>(info);
  m.world.addRigidBody(m.cavity_body.get());
}

int ChipWorld::addChip(const ChipShape& shape) {
  if (!(shape.volume_mm3 >= kMinChipVolume) || !(shape.mass_g > 0.0) || shape.vertices.rows() < 4) return -1;
  Impl& m = *impl_;
  Impl::Body b;
  b.shape = std::make_unique<btConvexHullShape>();
  for (Eigen::Index v = 0; v < shape.vertices.rows(); ++v) {
    b.shape->addPoint(toBt(shape.vertices.row(v).transpose() - shape.centre), false);
  }
  b.shape->recalcLocalAabb();
  b.shape->optimizeConvexHull();  // only the hull's corners remain
  if (b.shape->getNumPoints() > kMaxHullPoints) {
    // A rounded chip has many corners, and every contact query walks all of them: keep the
    // hull's support points in a fixed set of directions (Bullet's btShapeHull, <= 42).
    btShapeHull simple(b.shape.get());
    if (simple.buildHull(0.0f) && simple.numVertices() >= 4) {
      auto reduced = std::make_unique<btConvexHullShape>();
      for (int i = 0; i < simple.numVertices(); ++i) reduced->addPoint(simple.getVertexPointer()[i], false);
      reduced->recalcLocalAabb();
      reduced->optimizeConvexHull();
      b.shape = std::move(reduced);
    }
  }
  if (b.shape->getNumPoints() < 4) return -1;
  const btScalar mass = static_cast<btScalar>(shape.mass_g);
  btVector3 inertia(0, 0, 0);
  b.shape->calculateLocalInertia(mass, inertia);
  btRigidBody::btRigidBodyConstructionInfo info(mass, nullptr, b.shape.get(), inertia);
  info.m_startWorldTransform = toBt(shape.centre, Eigen::Matrix3d::Identity());
  // Bullet damps as v *= (1 - d)^dt: d = 1 - exp(-rate) gives v *= exp(-rate dt).
  info.m_linearDamping = static_cast<btScalar>(1.0 - std::exp(-settings_.drag_per_s));
  info.m_angularDamping = static_cast<btScalar>(1.0 - std::exp(-settings_.angular_drag_per_s));
  info.m_friction = static_cast<btScalar>(settings_.friction);
  info.m_restitution = 0.0;
  info.m_linearSleepingThreshold = kSleepLinearMmS;
  info.m_angularSleepingThreshold = kSleepAngularRadS;
  b.body = std::make_unique<btRigidBody>(info);
  m.world.addRigidBody(b.body.get());
  // Gravity less buoyancy (the cavity is filled with distension fluid).
  const double density = shape.mass_g / shape.volume_mm3;  // g/mm^3
  const double buoyancy = 1.0 - 1e-3 * settings_.fluid_density_g_cm3 / density;
  b.body->setGravity(toBt(buoyancy * gravity_));
  b.body->setLinearVelocity(toBt(shape.velocity));

  ChipBody chip;
  chip.id = next_id_++;
  chip.volume_mm3 = shape.volume_mm3;
  chip.mass_g = shape.mass_g;
  chip.position = shape.centre;
  chip.velocity = shape.velocity;
  const Eigen::Index nv = shape.vertices.rows();
  chip.surface.positions.resize(static_cast<size_t>(nv) * 3);
  for (Eigen::Index v = 0; v < nv; ++v) {
    for (int c = 0; c < 3; ++c) {
      chip.surface.positions[3 * v + c] = static_cast<float>(shape.vertices(v, c) - shape.centre[c]);
    }
  }
  chip.surface.triangles.reserve(static_cast<size_t>(shape.triangles.rows()) * 3);
  for (Eigen::Index f = 0; f < shape.triangles.rows(); ++f) {
    for (int c = 0; c < 3; ++c) chip.surface.triangles.push_back(static_cast<std::uint32_t>(shape.triangles(f, c)));
  }
  chip.surface.material = shape.material;
  chip.surface.material.resize(static_cast<size_t>(nv), render::SurfaceMaterial::Cut);
  // The cut took away the material of the new chip: chips that rested on it wake up.
  btVector3 lo, hi;
  b.body->getAabb(lo, hi);
  const btVector3 margin(kWakeMarginMm, kWakeMarginMm, kWakeMarginMm);
  for (Impl::Body& other : m.bodies) {
    btVector3 olo, ohi;
    other.body->getAabb(olo, ohi);
    if (TestAabbAgainstAabb2(lo - margin, hi + margin, olo, ohi)) other.body->activate(true);
  }
  m.bodies.push_back(std::move(b));
  chips_.push_back(std::move(chip));
  ++version_;
  while (static_cast<int>(chips_.size()) > settings_.max_chips) {
    removeChip(0);
    ++removed_over_cap_;
  }
  return chips_.back().id;
}

void ChipWorld::removeChip(size_t index) {
  Impl& m = *impl_;
  m.world.removeRigidBody(m.bodies[index].body.get());
  m.bodies.erase(m.bodies.begin() + static_cast<std::ptrdiff_t>(index));
  chips_.erase(chips_.begin() + static_cast<std::ptrdiff_t>(index));
  ++version_;
}

void ChipWorld::moveTool(const haptics::ToolPose& pose) {
  Impl& m = *impl_;
  m.from = m.tool_placed ? m.to : pose;
  m.to = pose;
  m.tool_placed = true;
  if (chips_.empty()) m.placeTool(1.0, true);  // nothing to push: no step, no velocity
}

void ChipWorld::step() {
  if (chips_.empty()) return;
  Impl& m = *impl_;
  const btScalar h = static_cast<btScalar>(dt_ / substeps_);
  for (int s = 1; s <= substeps_; ++s) {
    m.placeTool(static_cast<double>(s) / substeps_, false);
    m.world.stepSimulation(h, 0);  // one step of exactly h (no internal accumulator)
  }
  readBack();
  // Chips that left the cavity (or blew up) are gone.
  for (size_t i = chips_.size(); i-- > 0;) {
    const Eigen::Vector3d& p = chips_[i].position;
    const bool outside = has_cavity_ && ((p.array() < bounds_min_.array() - kLeaveMarginMm).any() ||
                                         (p.array() > bounds_max_.array() + kLeaveMarginMm).any());
    if (outside || !p.allFinite()) {
      removeChip(i);
      ++removed_outside_;
    }
  }
}

void ChipWorld::readBack() {
  for (size_t i = 0; i < chips_.size(); ++i) {
    const btRigidBody& body = *impl_->bodies[i].body;
    const btTransform& t = body.getWorldTransform();
    ChipBody& c = chips_[i];
    for (int r = 0; r < 3; ++r) {
      c.position[r] = t.getOrigin()[r];
      c.velocity[r] = body.getLinearVelocity()[r];
      for (int k = 0; k < 3; ++k) c.rotation(r, k) = t.getBasis()[r][k];
    }
    c.sleeping = body.getActivationState() == ISLAND_SLEEPING;
  }
}

std::uint64_t ChipWorld::hash(std::uint64_t h) const {
  for (const ChipBody& c : chips_) {
    mix(h, &c.id, sizeof c.id);
    mix(h, c.position.data(), 3 * sizeof(double));
    mix(h, c.rotation.data(), 9 * sizeof(double));
    mix(h, c.velocity.data(), 3 * sizeof(double));
  }
  return h;
}

}  // namespace hysim::engine
