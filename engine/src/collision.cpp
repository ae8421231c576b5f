#include "hysim/engine/collision.hpp"

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/narrowphase/collision.h>

#include <algorithm>
#include <array>
#include <vector>

namespace hysim::engine {

struct TissueCollision::Impl {
  std::shared_ptr<fcl::BVHModel<fcl::AABBd>> bvh;
  std::vector<fcl::Vector3d> vertices;  // #N, reused by every refit
  int num_faces = 0;
};

TissueCollision::TissueCollision() : impl_(std::make_unique<Impl>()) {}
TissueCollision::~TissueCollision() = default;
TissueCollision::TissueCollision(TissueCollision&&) noexcept = default;
TissueCollision& TissueCollision::operator=(TissueCollision&&) noexcept = default;

int TissueCollision::numFaces() const { return impl_->num_faces; }

Status TissueCollision::build(const cutting::TetMesh& mesh, const sim::NodeVectors& x) {
  // Unique faces (sorted node triples) of all tets.
  std::vector<std::array<int, 3>> faces;
  faces.reserve(static_cast<size_t>(mesh.numTets()) * 4);
  constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  for (int t = 0; t < mesh.numTets(); ++t) {
    for (const auto& f : kFace) {
      std::array<int, 3> key = {mesh.T(t, f[0]), mesh.T(t, f[1]), mesh.T(t, f[2])};
      std::sort(key.begin(), key.end());
      faces.push_back(key);
    }
  }
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(faces.size());
  for (const auto& f : faces) triangles.emplace_back(f[0], f[1], f[2]);

  impl_->vertices.resize(static_cast<size_t>(x.rows()));
  for (Eigen::Index i = 0; i < x.rows(); ++i) impl_->vertices[static_cast<size_t>(i)] = x.row(i).transpose();
  impl_->bvh = std::make_shared<fcl::BVHModel<fcl::AABBd>>();
  if (impl_->bvh->beginModel(static_cast<int>(triangles.size()), static_cast<int>(x.rows())) != fcl::BVH_OK ||
      impl_->bvh->addSubModel(impl_->vertices, triangles) != fcl::BVH_OK || impl_->bvh->endModel() != fcl::BVH_OK) {
    impl_->bvh.reset();
    return Error{"collision: cannot build the tissue's bounding volume hierarchy"};
  }
  impl_->num_faces = static_cast<int>(triangles.size());
  return Status::Ok();
}

void TissueCollision::refit(const sim::NodeVectors& x) {
  if (!impl_->bvh || static_cast<size_t>(x.rows()) != impl_->vertices.size()) return;
  for (Eigen::Index i = 0; i < x.rows(); ++i) impl_->vertices[static_cast<size_t>(i)] = x.row(i).transpose();
  impl_->bvh->beginReplaceModel();
  impl_->bvh->replaceSubModel(impl_->vertices);
  impl_->bvh->endReplaceModel(true, true);  // refit bottom-up, keep the tree
}

bool TissueCollision::touches(const Eigen::Matrix<double, Eigen::Dynamic, 3>& wire, double radius) const {
  if (!impl_->bvh) return false;
  fcl::CollisionRequestd request(1, false);
  fcl::CollisionResultd result;
  const fcl::Transform3d identity = fcl::Transform3d::Identity();
  for (Eigen::Index i = 0; i + 1 < wire.rows(); ++i) {
    const Eigen::Vector3d a = wire.row(i).transpose(), b = wire.row(i + 1).transpose();
    const Eigen::Vector3d d = b - a;
    const double len = d.norm();
    // FCL's capsule lies along its z axis, centred at the origin.
    fcl::Capsuled capsule(radius, len);
    fcl::Transform3d pose = fcl::Transform3d::Identity();
    pose.translation() = 0.5 * (a + b);
    if (len > 1e-12) {
      pose.linear() = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), d / len).toRotationMatrix();
    }
    result.clear();
    if (fcl::collide(&capsule, pose, impl_->bvh.get(), identity, request, result) > 0) return true;
  }
  return false;
}

}  // namespace hysim::engine
