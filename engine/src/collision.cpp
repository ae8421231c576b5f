#include "hysim/engine/collision.hpp"

#include <fcl/math/bv/utility.h>  // fit(), which BVH_model-inl.h uses without including
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/bvh/detail/BV_fitter_base.h>
#include <fcl/geometry/bvh/detail/BV_splitter_base.h>
#include <fcl/narrowphase/detail/traversal/collision_node.h>
#include <fcl/narrowphase/detail/traversal/distance/mesh_distance_traversal_node.h>

#include <algorithm>
#include <array>
#include <limits>
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
// The tissue hierarchy is built here rather than by FCL's BVHModel::endModel, which reads
// each triangle's vertices through FCL's generic fitter and splitter (virtual calls, and
// fcl::Triangle::operator[] out of line in libfcl) at every level: that was ~1.4 ms of a
// pass's ~1.5 ms collision build. TreeBuilder makes the same tree as endModel with FCL's
// SPLIT_METHOD_MEAN for AABB (node numbering, primitive order, boxes): fit the node's box to
// its triangles, split at the mean of their centroids along the box's longest axis (x, then
// y on ties), centroid > mean to the right, an empty side replaced by halving; left child
// first. Per-triangle boxes, coordinate sums and centroids are computed once, with the same
// sums in the same order as FCL, so every comparison gives the same answer
// (TissueCollision::matchesFclBuild checks the whole tree against endModel's).
struct BvhWriter {};

}  // namespace hysim::engine

namespace fcl {
// BVHModel befriends every specialisation of MakeParentRelativeRecurseImpl; this one (for a
// tag type of ours, which FCL never instantiates) is how the builder below writes the
// model's private tree arrays (bvs, primitive_indices, num_bvs).
template <>
struct MakeParentRelativeRecurseImpl<double, hysim::engine::BvhWriter> {
  static BVNode<AABBd>* nodes(BVHModel<AABBd>& m) { return m.bvs; }
  static unsigned int* primitives(BVHModel<AABBd>& m) { return m.primitive_indices; }
  // Allocates the tree arrays of a model that beginModel + addSubModel filled (what
  // endModel would allocate), before the builder writes them.
  static void allocate(BVHModel<AABBd>& m) {
    const int n = 2 * m.num_tris - 1;
    m.bvs = new BVNode<AABBd>[static_cast<size_t>(n)];
    m.primitive_indices = new unsigned int[static_cast<size_t>(n)];
    m.num_bvs_allocated = n;
    m.num_bvs = 0;
  }
  static void finish(BVHModel<AABBd>& m, int num_bvs) {
    m.num_bvs = num_bvs;
    m.build_state = BVH_BUILD_STATE_PROCESSED;
  }
};
}  // namespace fcl

namespace hysim::engine {
namespace {

using BvhAccess = fcl::MakeParentRelativeRecurseImpl<double, BvhWriter>;

class TreeBuilder {
 public:
  // Builds the tree of `bvh` (after beginModel + addSubModel with its triangles). parent
  // (#BV) and leaf_of_tri (#F) receive each node's parent and each triangle's leaf.
  void build(Bvh& bvh, std::vector<int>& parent, std::vector<int>& leaf_of_tri) {
    const int nt = bvh.num_tris;
    tris_.resize(static_cast<size_t>(nt));
    const fcl::Vector3d* v = bvh.vertices;
    fcl::Vector3d lo = fcl::Vector3d::Constant(std::numeric_limits<double>::max());  // FCL's empty box
    fcl::Vector3d hi = fcl::Vector3d::Constant(-std::numeric_limits<double>::max());
    for (int t = 0; t < nt; ++t) {
      const fcl::Triangle& tri = bvh.tri_indices[t];
      const fcl::Vector3d &a = v[tri[0]], &b = v[tri[1]], &c = v[tri[2]];
      Tri& d = tris_[static_cast<size_t>(t)];
      for (int k = 0; k < 3; ++k) {
        d.lo[k] = std::min(std::min(a[k], b[k]), c[k]);
        d.hi[k] = std::max(std::max(a[k], b[k]), c[k]);
        d.sum[k] = a[k] + b[k] + c[k];  // as FCL's mean rule adds them
        d.centroid[k] = d.sum[k] / 3.0;  // as recursiveBuildTree's (p1 + p2 + p3) / 3.0
        lo[k] = std::min(lo[k], d.lo[k]);
        hi[k] = std::max(hi[k], d.hi[k]);
      }
    }
    BvhAccess::allocate(bvh);
    nodes_ = BvhAccess::nodes(bvh);
    prims_ = BvhAccess::primitives(bvh);
    for (int i = 0; i < nt; ++i) prims_[i] = static_cast<unsigned int>(i);
    parent.assign(2 * static_cast<size_t>(nt) - 1, -1);
    leaf_of_tri.assign(static_cast<size_t>(nt), -1);
    parent_ = parent.data();
    leaf_of_tri_ = leaf_of_tri.data();
    num_bvs_ = 1;
    recurse(0, 0, nt, lo, hi);
    BvhAccess::finish(bvh, num_bvs_);
  }

 private:
  struct Tri {
    double lo[3], hi[3], sum[3], centroid[3];  // box, coordinate sums, sums / 3.0
  };

  // Node `id` over prims_[first, first + count), whose triangles' boxes span [lo, hi] (a box
  // is a min/max, the same in any order: the parent's partition gathers the children's).
  void recurse(int id, int first, int count, const fcl::Vector3d& lo, const fcl::Vector3d& hi) {
    unsigned int* const prims = prims_ + first;
    fcl::BVNode<fcl::AABBd>& node = nodes_[id];
    node.bv.min_ = lo;
    node.bv.max_ = hi;
    node.first_primitive = first;
    node.num_primitives = count;
    if (count == 1) {
      node.first_child = -static_cast<int>(prims[0]) - 1;
      leaf_of_tri_[prims[0]] = id;
      return;
    }
    const double w = hi[0] - lo[0], h = hi[1] - lo[1], d = hi[2] - lo[2];
    int axis = 2;
    if (w >= h && w >= d) {
      axis = 0;
    } else if (h >= w && h >= d) {
      axis = 1;
    }
    const Tri* const tris = tris_.data();
    double sum = 0;
    for (int i = 0; i < count; ++i) sum += tris[prims[i]].sum[axis];
    sum /= 3;
    const double value = sum / count;
    const int left = num_bvs_;
    node.first_child = left;
    num_bvs_ += 2;
    parent_[left] = id;
    parent_[left + 1] = id;
    // FCL's partition (centroid (p1 + p2 + p3) / 3.0 > mean: right), the children's boxes on the way.
    // Without branches (the side is a coin toss for the predictor): a triangle going left
    // swaps with the first one on the right (a no-op otherwise).
    constexpr double kMax = std::numeric_limits<double>::max();
    double llo[3] = {kMax, kMax, kMax}, lhi[3] = {-kMax, -kMax, -kMax};
    double rlo[3] = {kMax, kMax, kMax}, rhi[3] = {-kMax, -kMax, -kMax};
    int c1 = 0;
    for (int i = 0; i < count; ++i) {
      const unsigned int p = prims[i];
      const Tri& t = tris[p];
      const bool right = t.centroid[axis] > value;
      for (int k = 0; k < 3; ++k) {
        llo[k] = std::min(llo[k], right ? kMax : t.lo[k]);
        lhi[k] = std::max(lhi[k], right ? -kMax : t.hi[k]);
        rlo[k] = std::min(rlo[k], right ? t.lo[k] : kMax);
        rhi[k] = std::max(rhi[k], right ? t.hi[k] : -kMax);
      }
      const unsigned int q = prims[c1];
      prims[i] = right ? p : q;
      prims[c1] = right ? q : p;
      c1 += right ? 0 : 1;
    }
    if (c1 == 0 || c1 == count) {  // all on one side: halves, boxes refitted
      c1 = count / 2;
      for (int k = 0; k < 3; ++k) {
        llo[k] = rlo[k] = kMax;
        lhi[k] = rhi[k] = -kMax;
      }
      for (int i = 0; i < count; ++i) {
        const Tri& t = tris[prims[i]];
        double* const a = i < c1 ? llo : rlo;
        double* const b = i < c1 ? lhi : rhi;
        for (int k = 0; k < 3; ++k) {
          a[k] = std::min(a[k], t.lo[k]);
          b[k] = std::max(b[k], t.hi[k]);
        }
      }
    }
    recurse(left, first, c1, fcl::Vector3d(llo[0], llo[1], llo[2]), fcl::Vector3d(lhi[0], lhi[1], lhi[2]));
    recurse(left + 1, first + c1, count - c1, fcl::Vector3d(rlo[0], rlo[1], rlo[2]),
            fcl::Vector3d(rhi[0], rhi[1], rhi[2]));
  }

  std::vector<Tri> tris_;
  fcl::BVNode<fcl::AABBd>* nodes_ = nullptr;
  unsigned int* prims_ = nullptr;
  int* parent_ = nullptr;
  int* leaf_of_tri_ = nullptr;
  int num_bvs_ = 0;
};

}  // namespace

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
  Impl& m = *impl_;
  if (bvh->beginModel(static_cast<int>(triangles.size()), static_cast<int>(vertices.size())) != fcl::BVH_OK ||
      bvh->addSubModel(vertices, triangles) != fcl::BVH_OK) {
    impl_->nodes.clear();
    return Error{"collision: cannot build the tissue's bounding volume hierarchy"};
  }
  // endModel's tree (see TreeBuilder), children numbered after their parent.
  TreeBuilder().build(*bvh, m.parent, m.leaf_of_tri);
  m.children_after_parents = true;
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

bool TissueCollision::matchesFclBuild() const {
  const Bvh* mine = impl_->bvh.get();
  if (mine == nullptr) return impl_->num_faces == 0;
  // FCL's own build of the same triangles at the same vertices (where the boxes were fitted).
  Bvh fcl_model;  // default: BVFitter, BVSplitter with SPLIT_METHOD_MEAN
  std::vector<fcl::Vector3d> vertices(impl_->refit_x.begin(), impl_->refit_x.end());
  std::vector<fcl::Triangle> triangles(mine->tri_indices, mine->tri_indices + mine->num_tris);
  if (fcl_model.beginModel(mine->num_tris, mine->num_vertices) != fcl::BVH_OK ||
      fcl_model.addSubModel(vertices, triangles) != fcl::BVH_OK || fcl_model.endModel() != fcl::BVH_OK) {
    return false;
  }
  if (fcl_model.getNumBVs() != mine->getNumBVs()) return false;
  Bvh& a = const_cast<Bvh&>(*mine);
  for (int b = 0; b < fcl_model.getNumBVs(); ++b) {
    const fcl::BVNode<fcl::AABBd>& p = fcl_model.getBV(b);
    const fcl::BVNode<fcl::AABBd>& q = a.getBV(b);
    if (p.first_child != q.first_child || p.first_primitive != q.first_primitive ||
        p.num_primitives != q.num_primitives) {
      return false;
    }
  }
  const unsigned int* pa = BvhAccess::primitives(fcl_model);
  const unsigned int* pb = BvhAccess::primitives(a);
  return std::equal(pa, pa + mine->num_tris, pb);
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
