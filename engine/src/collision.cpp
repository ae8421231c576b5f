#include "hysim/engine/collision.hpp"

#include <fcl/math/bv/utility.h>  // fit(), which BVH_model-inl.h uses without including
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/bvh/detail/BV_fitter_base.h>
#include <fcl/geometry/bvh/detail/BV_splitter_base.h>
#include <fcl/narrowphase/detail/traversal/collision_node.h>
#include <fcl/narrowphase/detail/traversal/distance/mesh_distance_traversal_node.h>

#include <algorithm>
#include <array>
#include <vector>

namespace hysim::engine {

using Bvh = fcl::BVHModel<fcl::AABBd>;

// ---------------------------------------------------------------------------------------
struct SweptWire::Impl {
  std::shared_ptr<Bvh> bvh;
  int points = 0;
};

SweptWire::SweptWire() : impl_(std::make_unique<Impl>()) {}
SweptWire::~SweptWire() = default;
SweptWire::SweptWire(SweptWire&&) noexcept = default;
SweptWire& SweptWire::operator=(SweptWire&&) noexcept = default;

int SweptWire::numPoints() const { return impl_->points; }
int SweptWire::numTriangles() const { return impl_->points > 1 ? 2 * (impl_->points - 1) : 0; }

void SweptWire::reset(int points) {
  impl_->points = std::max(points, 0);
  impl_->bvh.reset();
  if (points < 2) return;
  // Vertices: row 0 = previous wire (0..P-1), row 1 = current wire (P..2P-1).
  std::vector<fcl::Vector3d> vertices(static_cast<size_t>(2 * points), fcl::Vector3d::Zero());
  // Spread the initial vertices so the first build sees a proper strip (refits keep the tree).
  for (int i = 0; i < points; ++i) {
    vertices[static_cast<size_t>(i)] = fcl::Vector3d(i, 0, 0);
    vertices[static_cast<size_t>(points + i)] = fcl::Vector3d(i, 1, 0);
  }
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(static_cast<size_t>(2 * (points - 1)));
  for (int i = 0; i + 1 < points; ++i) {
    const int a = i, b = i + 1, c = points + i, d = points + i + 1;  // a-b previous, c-d current
    triangles.emplace_back(a, b, d);
    triangles.emplace_back(a, d, c);
  }
  impl_->bvh = std::make_shared<Bvh>();
  impl_->bvh->beginModel(static_cast<int>(triangles.size()), static_cast<int>(vertices.size()));
  impl_->bvh->addSubModel(vertices, triangles);
  impl_->bvh->endModel();
}

void SweptWire::update(const WirePoints& previous, const WirePoints& current) {
  Bvh* bvh = impl_->bvh.get();
  const int n = impl_->points;
  if (bvh == nullptr || previous.rows() != n || current.rows() != n) return;
  bvh->beginReplaceModel();
  for (int i = 0; i < n; ++i) bvh->replaceVertex(previous.row(i).transpose());
  for (int i = 0; i < n; ++i) bvh->replaceVertex(current.row(i).transpose());
  bvh->endReplaceModel(true, true);  // refit bottom-up, keep the tree
}

void SweptWire::triangle(int t, Eigen::Vector3d& a, Eigen::Vector3d& b, Eigen::Vector3d& c) const {
  const Bvh& bvh = *impl_->bvh;
  const fcl::Triangle& tri = bvh.tri_indices[t];
  a = bvh.vertices[tri[0]];
  b = bvh.vertices[tri[1]];
  c = bvh.vertices[tri[2]];
}

// ---------------------------------------------------------------------------------------
// FCL's build of an AABB tree (BVHModel::endModel: fit the node's box, split at the mean of
// its triangles' centroids along the box's longest axis, recurse) reads each triangle's three
// vertices through FCL's generic fitter and splitter at every level. These two give the same
// boxes and split rules (the same sums in the same order, so the same tree) from per-triangle
// boxes and coordinate sums computed once when the build starts.
class TriangleBoxes {
 public:
  void set(const fcl::Vector3d* vertices, const fcl::Triangle* tris, int num_tris) {
    lo_.resize(static_cast<size_t>(num_tris));
    hi_.resize(static_cast<size_t>(num_tris));
    sum_.resize(static_cast<size_t>(num_tris));
    for (int t = 0; t < num_tris; ++t) {
      const fcl::Vector3d &a = vertices[tris[t][0]], &b = vertices[tris[t][1]], &c = vertices[tris[t][2]];
      lo_[t] = a.cwiseMin(b).cwiseMin(c);
      hi_[t] = a.cwiseMax(b).cwiseMax(c);
      for (int k = 0; k < 3; ++k) sum_[t][k] = a[k] + b[k] + c[k];  // as FCL's mean rule adds them
    }
  }
  void clear() {
    lo_.clear();
    hi_.clear();
    sum_.clear();
  }
  std::vector<fcl::Vector3d> lo_, hi_, sum_;
};

class BoxFitter final : public fcl::detail::BVFitterBase<fcl::AABBd> {
 public:
  explicit BoxFitter(std::shared_ptr<TriangleBoxes> boxes) : boxes_(std::move(boxes)) {}
  void set(fcl::Vector3d* vertices, fcl::Triangle* tris, fcl::BVHModelType type) override {
    type_ = type;
    vertices_ = vertices;
    tris_ = tris;
  }
  void set(fcl::Vector3d* vertices, fcl::Vector3d* prev, fcl::Triangle* tris, fcl::BVHModelType type) override {
    set(vertices, tris, type);
    prev_ = prev;
  }
  fcl::AABBd fit(unsigned int* primitives, int count) override {
    fcl::AABBd box;  // empty: +max / -max, as FCL's fitter starts
    const TriangleBoxes& b = *boxes_;
    if (type_ != fcl::BVH_MODEL_TRIANGLES || prev_ != nullptr || b.lo_.empty()) {
      // Outside a build (FCL's top-down refit): FCL's own rule over the vertices.
      for (int i = 0; i < count; ++i) {
        const unsigned int p = primitives[i];
        if (type_ == fcl::BVH_MODEL_TRIANGLES) {
          for (int k = 0; k < 3; ++k) {
            box += vertices_[tris_[p][k]];
            if (prev_ != nullptr) box += prev_[tris_[p][k]];
          }
        } else {
          box += vertices_[p];
          if (prev_ != nullptr) box += prev_[p];
        }
      }
      return box;
    }
    for (int i = 0; i < count; ++i) {
      box.min_ = box.min_.cwiseMin(b.lo_[primitives[i]]);
      box.max_ = box.max_.cwiseMax(b.hi_[primitives[i]]);
    }
    return box;
  }
  void clear() override {
    vertices_ = nullptr;
    prev_ = nullptr;
    tris_ = nullptr;
  }

 private:
  std::shared_ptr<TriangleBoxes> boxes_;
  fcl::BVHModelType type_ = fcl::BVH_MODEL_UNKNOWN;
  fcl::Vector3d* vertices_ = nullptr;
  fcl::Vector3d* prev_ = nullptr;
  fcl::Triangle* tris_ = nullptr;
};

class MeanSplitter final : public fcl::detail::BVSplitterBase<fcl::AABBd> {
 public:
  explicit MeanSplitter(std::shared_ptr<TriangleBoxes> boxes) : boxes_(std::move(boxes)) {}
  void set(fcl::Vector3d* vertices, fcl::Triangle* tris, fcl::BVHModelType type) override {
    type_ = type;
    vertices_ = vertices;
    if (type == fcl::BVH_MODEL_TRIANGLES) boxes_->set(vertices, tris, num_tris_);
  }
  void setNumTriangles(int n) { num_tris_ = n; }
  void computeRule(const fcl::AABBd& bv, unsigned int* primitives, int count) override {
    // FCL's SPLIT_METHOD_MEAN for AABB: the longest axis (x, then y on ties), the mean of
    // the centroids' coordinates along it.
    int axis = 2;
    if (bv.width() >= bv.height() && bv.width() >= bv.depth()) {
      axis = 0;
    } else if (bv.height() >= bv.width() && bv.height() >= bv.depth()) {
      axis = 1;
    }
    axis_ = axis;
    double sum = 0;
    if (type_ == fcl::BVH_MODEL_TRIANGLES) {
      const std::vector<fcl::Vector3d>& s = boxes_->sum_;
      for (int i = 0; i < count; ++i) sum += s[primitives[i]][axis];
      sum /= 3;
    } else {
      for (int i = 0; i < count; ++i) sum += vertices_[primitives[i]][axis];
    }
    value_ = sum / count;
  }
  bool apply(const fcl::Vector3d& q) const override { return q[axis_] > value_; }
  void clear() override { boxes_->clear(); }

 private:
  std::shared_ptr<TriangleBoxes> boxes_;
  fcl::BVHModelType type_ = fcl::BVH_MODEL_UNKNOWN;
  fcl::Vector3d* vertices_ = nullptr;
  int num_tris_ = 0;
  int axis_ = 0;
  double value_ = 0.0;
};

// ---------------------------------------------------------------------------------------
struct TissueCollision::Impl {
  std::shared_ptr<Bvh> bvh;
  std::vector<int> nodes;  // #V node ids of the hierarchy's vertices
  int num_faces = 0;
  bool children_after_parents = false;  // FCL's build order, checked once per build
  double margin = 0.0;                  // mm, leaf boxes are grown by this
  std::vector<fcl::Vector3d> refit_x;   // #V vertex positions the boxes were fitted around
  long refits = 0;
  long local_refits = 0;
  // For local refits: parent of each box (-1 at the root), the leaf box of each triangle, and
  // the triangles of each vertex (CSR).
  std::vector<int> parent;       // #BV
  std::vector<int> leaf_of_tri;  // #F
  std::vector<int> vtx_start;    // #V + 1
  std::vector<int> vtx_tris;     // 3 #F

  // Leaf box of triangle `tri`: its vertices' refit_x positions grown by the margin, so it
  // holds every vertex that stays within the margin of where it was fitted.
  void fitLeaf(fcl::AABBd& box, int tri) const {
    const fcl::Triangle& t = bvh->tri_indices[tri];
    const fcl::Vector3d &p = refit_x[t[0]], &q = refit_x[t[1]], &r = refit_x[t[2]];
    const fcl::Vector3d grow = fcl::Vector3d::Constant(margin);
    box.min_ = p.cwiseMin(q).cwiseMin(r) - grow;
    box.max_ = p.cwiseMax(q).cwiseMax(r) + grow;
  }
};

TissueCollision::TissueCollision() : impl_(std::make_unique<Impl>()) {}
TissueCollision::~TissueCollision() = default;
TissueCollision::TissueCollision(TissueCollision&&) noexcept = default;
TissueCollision& TissueCollision::operator=(TissueCollision&&) noexcept = default;

int TissueCollision::numFaces() const { return impl_->num_faces; }
int TissueCollision::numVertices() const { return static_cast<int>(impl_->nodes.size()); }
double TissueCollision::margin() const { return impl_->margin; }
long TissueCollision::numRefits() const { return impl_->refits; }
long TissueCollision::numLocalRefits() const { return impl_->local_refits; }

cutting::Tris allTetFaces(const cutting::TetMesh& mesh) {
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
  cutting::Tris out(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f) out.row(static_cast<Eigen::Index>(f)) << faces[f][0], faces[f][1], faces[f][2];
  return out;
}

Status TissueCollision::build(const cutting::Tris& faces, const sim::NodeVectors& x, double margin_mm) {
  impl_->bvh.reset();
  impl_->margin = std::max(margin_mm, 0.0);
  impl_->nodes.clear();
  impl_->num_faces = 0;
  // Compact numbering: only the faces' nodes are vertices of the hierarchy (the boundary has
  // far fewer nodes than the mesh, and refit() copies each vertex every step).
  std::vector<int> local(static_cast<size_t>(x.rows()), -1);
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(static_cast<size_t>(faces.rows()));
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    int v[3];
    for (int c = 0; c < 3; ++c) {
      const int node = faces(f, c);
      if (node < 0 || node >= x.rows()) return Error{"collision: face " + std::to_string(f) + " names a missing node"};
      if (local[static_cast<size_t>(node)] < 0) {
        local[static_cast<size_t>(node)] = static_cast<int>(impl_->nodes.size());
        impl_->nodes.push_back(node);
      }
      v[c] = local[static_cast<size_t>(node)];
    }
    triangles.emplace_back(v[0], v[1], v[2]);
  }
  if (triangles.empty()) return Status::Ok();  // nothing to touch
  std::vector<fcl::Vector3d> vertices(impl_->nodes.size());
  for (size_t i = 0; i < impl_->nodes.size(); ++i) vertices[i] = x.row(impl_->nodes[i]).transpose();
  auto bvh = std::make_shared<Bvh>();
  {
    auto boxes = std::make_shared<TriangleBoxes>();
    auto splitter = std::make_shared<MeanSplitter>(boxes);
    splitter->setNumTriangles(static_cast<int>(triangles.size()));
    bvh->bv_splitter = splitter;
    bvh->bv_fitter = std::make_shared<BoxFitter>(boxes);
  }
  if (bvh->beginModel(static_cast<int>(triangles.size()), static_cast<int>(vertices.size())) != fcl::BVH_OK ||
      bvh->addSubModel(vertices, triangles) != fcl::BVH_OK || bvh->endModel() != fcl::BVH_OK) {
    impl_->nodes.clear();
    return Error{"collision: cannot build the tissue's bounding volume hierarchy"};
  }
  impl_->children_after_parents = true;
  for (int b = 0; b < bvh->getNumBVs(); ++b) {
    const fcl::BVNode<fcl::AABBd>& n = bvh->getBV(b);
    if (!n.isLeaf() && (n.leftChild() <= b || n.rightChild() <= b || n.rightChild() >= bvh->getNumBVs())) {
      impl_->children_after_parents = false;
    }
  }
  Impl& m = *impl_;
  m.parent.assign(static_cast<size_t>(bvh->getNumBVs()), -1);
  m.leaf_of_tri.assign(triangles.size(), -1);
  for (int b = 0; b < bvh->getNumBVs(); ++b) {
    const fcl::BVNode<fcl::AABBd>& n = bvh->getBV(b);
    if (n.isLeaf()) {
      m.leaf_of_tri[static_cast<size_t>(n.primitiveId())] = b;
    } else if (m.children_after_parents) {
      m.parent[static_cast<size_t>(n.leftChild())] = b;
      m.parent[static_cast<size_t>(n.rightChild())] = b;
    }
  }
  m.vtx_start.assign(m.nodes.size() + 1, 0);
  for (const fcl::Triangle& t : triangles)
    for (int c = 0; c < 3; ++c) ++m.vtx_start[t[c] + 1];
  for (size_t i = 0; i < m.nodes.size(); ++i) m.vtx_start[i + 1] += m.vtx_start[i];
  m.vtx_tris.assign(3 * triangles.size(), -1);
  std::vector<int> fill(m.vtx_start.begin(), m.vtx_start.end() - 1);
  for (size_t f = 0; f < triangles.size(); ++f)
    for (int c = 0; c < 3; ++c) m.vtx_tris[static_cast<size_t>(fill[triangles[f][c]]++)] = static_cast<int>(f);
  impl_->bvh = std::move(bvh);
  impl_->num_faces = static_cast<int>(triangles.size());
  impl_->refit_x = std::move(vertices);
  refit(x);  // grow the boxes by the margin
  return Status::Ok();
}

void TissueCollision::refit(const sim::NodeVectors& x) {
  Impl& m = *impl_;
  Bvh* bvh = m.bvh.get();
  if (bvh == nullptr) return;
  ++m.refits;
  fcl::Vector3d* v = bvh->vertices;
  for (size_t i = 0; i < m.nodes.size(); ++i) m.refit_x[i] = v[i] = x.row(m.nodes[i]).transpose();
  if (!m.children_after_parents) {
    // FCL's own refit (exact boxes; margin ignored, update() then refits every step).
    // replaceVertex() writes in place; beginReplaceModel() only frees prev_vertices, which a
    // replace-refitted model never has.
    bvh->beginReplaceModel();
    for (size_t i = 0; i < m.nodes.size(); ++i) bvh->replaceVertex(m.refit_x[i]);
    bvh->endReplaceModel(true, true);  // refit bottom-up, keep the tree
    return;
  }
  // The same bottom-up refit as FCL's endReplaceModel(true, true), as one loop (FCL numbers
  // a node's children after it, so a backward sweep sees children first; checked by build()),
  // with the leaf boxes grown by the margin.
  for (int b = bvh->getNumBVs() - 1; b >= 0; --b) {
    fcl::BVNode<fcl::AABBd>& n = bvh->getBV(b);
    if (n.isLeaf()) {
      m.fitLeaf(n.bv, n.primitiveId());
    } else {
      const fcl::AABBd& a = bvh->getBV(n.leftChild()).bv;
      const fcl::AABBd& c = bvh->getBV(n.rightChild()).bv;
      n.bv.min_ = a.min_.cwiseMin(c.min_);
      n.bv.max_ = a.max_.cwiseMax(c.max_);
    }
  }
}

bool TissueCollision::update(const sim::NodeVectors& x) {
  Impl& m = *impl_;
  Bvh* bvh = m.bvh.get();
  if (bvh == nullptr) return false;
  if (!m.children_after_parents || m.margin <= 0.0) {
    refit(x);
    return true;
  }
  // The narrow phase reads the vertices, so they always move. A vertex that has left its
  // margin is fitted anew where it is now: the leaves of its triangles are refitted and
  // their ancestors grown to hold them (up to the first that already does). Ancestors only
  // grow, so they stay valid; refit() tightens them again.
  fcl::Vector3d* v = bvh->vertices;
  const double limit = m.margin * m.margin;
  bool moved = false;
  for (size_t i = 0; i < m.nodes.size(); ++i) {
    v[i] = x.row(m.nodes[i]).transpose();
    if ((v[i] - m.refit_x[i]).squaredNorm() <= limit) continue;
    moved = true;
    ++m.local_refits;
    m.refit_x[i] = v[i];
    for (int k = m.vtx_start[i]; k < m.vtx_start[i + 1]; ++k) {
      const int leaf = m.leaf_of_tri[static_cast<size_t>(m.vtx_tris[static_cast<size_t>(k)])];
      fcl::AABBd& box = bvh->getBV(leaf).bv;
      m.fitLeaf(box, m.vtx_tris[static_cast<size_t>(k)]);
      for (int p = m.parent[static_cast<size_t>(leaf)]; p >= 0; p = m.parent[static_cast<size_t>(p)]) {
        fcl::AABBd& up = bvh->getBV(p).bv;
        if (up.contain(box)) break;
        up.min_ = up.min_.cwiseMin(box.min_);
        up.max_ = up.max_.cwiseMax(box.max_);
      }
    }
  }
  return moved;
}

bool TissueCollision::touches(const SweptWire& sweep, double radius) const {
  Bvh* tissue = impl_->bvh.get();
  Bvh* wire = sweep.impl_->bvh.get();
  if (tissue == nullptr || wire == nullptr) return false;
  // The traversal node is built here rather than through fcl::distance(), whose AABB path
  // copies both models per call. Identity poses: initialize() transforms nothing.
  fcl::detail::MeshDistanceTraversalNode<fcl::AABBd> node;
  fcl::Transform3d tf_tissue = fcl::Transform3d::Identity(), tf_wire = fcl::Transform3d::Identity();
  fcl::DistanceRequestd request(false);  // no nearest points
  fcl::DistanceResultd result;
  // Start from the threshold: box pairs farther apart than the radius are pruned, and the
  // first pair of triangles that touches (distance 0) prunes everything left.
  const double threshold = std::max(radius, 0.0) + 1e-12;  // touching counts (radius 0: crossing)
  result.min_distance = threshold;
  if (!fcl::detail::initialize(node, *tissue, tf_tissue, *wire, tf_wire, request, result)) return false;
  fcl::detail::distance(&node);
  return result.min_distance < threshold;
}

}  // namespace hysim::engine
