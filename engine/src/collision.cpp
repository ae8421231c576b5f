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

#include "hysim/cutting/tet_faces.hpp"

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
// One hierarchy per chunk of the surface (the faces whose rest centroid lies in one cell of a
// coarse grid), so that a pass rebuilds only the chunks whose faces it changed.
struct Chunk {
  std::shared_ptr<Bvh> bvh;
  std::vector<std::array<int, 3>> faces;  // node ids of its triangles, in hierarchy order
  std::vector<int> nodes;                 // node id of each hierarchy vertex
  bool children_after_parents = false;    // FCL's build order, checked once per build
  std::vector<fcl::Vector3d> refit_x;     // vertex positions the boxes were fitted around
  // For local refits: parent of each box (-1 at the root), the leaf box of each triangle, and
  // the triangles of each vertex (CSR).
  std::vector<int> parent;       // #BV
  std::vector<int> leaf_of_tri;  // #F
  std::vector<int> vtx_start;    // #V + 1
  std::vector<int> vtx_tris;     // 3 #F

  // Leaf box of triangle `tri`: its vertices' refit_x positions grown by the margin, so it
  // holds every vertex that stays within the margin of where it was fitted.
  void fitLeaf(fcl::AABBd& box, int tri, double margin) const {
    const fcl::Triangle& t = bvh->tri_indices[tri];
    const fcl::Vector3d &p = refit_x[t[0]], &q = refit_x[t[1]], &r = refit_x[t[2]];
    const fcl::Vector3d grow = fcl::Vector3d::Constant(margin);
    box.min_ = p.cwiseMin(q).cwiseMin(r) - grow;
    box.max_ = p.cwiseMax(q).cwiseMax(r) + grow;
  }
};

struct TissueCollision::Impl {
  std::vector<Chunk> chunks;  // one per grid cell (most are empty)
  // The grid: set by a build without a renumbering, kept by the builds that follow.
  Eigen::Vector3d origin{0, 0, 0};
  double cell = 1.0;
  Eigen::Vector3i dims{1, 1, 1};
  int num_faces = 0;
  int num_vertices = 0;
  double margin = 0.0;  // mm, leaf boxes are grown by this
  long refits = 0;
  long local_refits = 0;
  long chunks_built = 0;
  long chunks_kept = 0;
  std::vector<int> local;  // #N scratch of build (all -1 between builds)

  int cellOf(const Eigen::Vector3d& c) const {
    int idx[3];
    for (int a = 0; a < 3; ++a) {
      const double f = std::floor((c[a] - origin[a]) / cell);
      idx[a] = static_cast<int>(std::clamp(f, 0.0, static_cast<double>(dims[a] - 1)));
    }
    return (idx[0] * dims[1] + idx[1]) * dims[2] + idx[2];
  }
  Status buildChunk(Chunk& c, const sim::NodeVectors& x);
  void refitChunk(Chunk& c, const sim::NodeVectors& x);
  bool updateChunk(Chunk& c, const sim::NodeVectors& x);
};

TissueCollision::TissueCollision() : impl_(std::make_unique<Impl>()) {}
TissueCollision::~TissueCollision() = default;
TissueCollision::TissueCollision(TissueCollision&&) noexcept = default;
TissueCollision& TissueCollision::operator=(TissueCollision&&) noexcept = default;

int TissueCollision::numFaces() const { return impl_->num_faces; }
int TissueCollision::numVertices() const { return impl_->num_vertices; }
int TissueCollision::numHierarchyVertices() const {
  size_t n = 0;
  for (const Chunk& c : impl_->chunks) n += c.nodes.size();
  return static_cast<int>(n);
}
double TissueCollision::margin() const { return impl_->margin; }
long TissueCollision::numRefits() const { return impl_->refits; }
long TissueCollision::numLocalRefits() const { return impl_->local_refits; }
long TissueCollision::numChunksBuilt() const { return impl_->chunks_built; }
long TissueCollision::numChunksKept() const { return impl_->chunks_kept; }

cutting::Tris allTetFaces(const cutting::TetMesh& mesh) {
  // One slot per face (its lowest), as sorted node ids in lexicographic order.
  std::vector<int> next;
  cutting::matchFacesOfAnyIds(mesh, next);
  std::vector<std::array<int, 3>> faces;
  faces.reserve(next.size() / 2 + 1);
  for (int s = 0; s < static_cast<int>(next.size()); ++s) {
    if (cutting::firstSlotOfFace(next, s) != s) continue;
    const int t = s / 4;
    const int* local = cutting::kTetFace[s % 4];
    std::array<int, 3> key = {mesh.T(t, local[0]), mesh.T(t, local[1]), mesh.T(t, local[2])};
    std::sort(key.begin(), key.end());
    faces.push_back(key);
  }
  std::sort(faces.begin(), faces.end());
  cutting::Tris out(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f) out.row(static_cast<Eigen::Index>(f)) << faces[f][0], faces[f][1], faces[f][2];
  return out;
}

Status TissueCollision::Impl::buildChunk(Chunk& c, const sim::NodeVectors& x) {
  c.bvh.reset();
  c.nodes.clear();
  if (c.faces.empty()) return Status::Ok();
  // Compact numbering: only the faces' nodes are vertices of the hierarchy (refit() copies
  // each vertex every step).
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(c.faces.size());
  for (const std::array<int, 3>& f : c.faces) {
    int v[3];
    for (int k = 0; k < 3; ++k) {
      int& l = local[static_cast<size_t>(f[k])];
      if (l < 0) {
        l = static_cast<int>(c.nodes.size());
        c.nodes.push_back(f[k]);
      }
      v[k] = l;
    }
    triangles.emplace_back(v[0], v[1], v[2]);
  }
  for (int node : c.nodes) local[static_cast<size_t>(node)] = -1;
  std::vector<fcl::Vector3d> vertices(c.nodes.size());
  for (size_t i = 0; i < c.nodes.size(); ++i) vertices[i] = x.row(c.nodes[i]).transpose();
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
    c.nodes.clear();
    return Error{"collision: cannot build the tissue's bounding volume hierarchy"};
  }
  const int num_bvs = bvh->getNumBVs();
  c.children_after_parents = true;
  for (int b = 0; b < num_bvs; ++b) {
    const fcl::BVNode<fcl::AABBd>& n = bvh->getBV(b);
    if (!n.isLeaf() && (n.leftChild() <= b || n.rightChild() <= b || n.rightChild() >= num_bvs)) {
      c.children_after_parents = false;
    }
  }
  c.parent.assign(static_cast<size_t>(num_bvs), -1);
  c.leaf_of_tri.assign(triangles.size(), -1);
  for (int b = 0; b < num_bvs; ++b) {
    const fcl::BVNode<fcl::AABBd>& n = bvh->getBV(b);
    if (n.isLeaf()) {
      c.leaf_of_tri[static_cast<size_t>(n.primitiveId())] = b;
    } else if (c.children_after_parents) {
      c.parent[static_cast<size_t>(n.leftChild())] = b;
      c.parent[static_cast<size_t>(n.rightChild())] = b;
    }
  }
  c.vtx_start.assign(c.nodes.size() + 1, 0);
  for (const fcl::Triangle& t : triangles)
    for (int k = 0; k < 3; ++k) ++c.vtx_start[t[k] + 1];
  for (size_t i = 0; i < c.nodes.size(); ++i) c.vtx_start[i + 1] += c.vtx_start[i];
  c.vtx_tris.assign(3 * triangles.size(), -1);
  std::vector<int> fill(c.vtx_start.begin(), c.vtx_start.end() - 1);
  for (size_t f = 0; f < triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) c.vtx_tris[static_cast<size_t>(fill[triangles[f][k]]++)] = static_cast<int>(f);
  c.bvh = std::move(bvh);
  c.refit_x = std::move(vertices);
  ++chunks_built;
  refitChunk(c, x);  // grow the boxes by the margin
  return Status::Ok();
}

Status TissueCollision::build(const cutting::Tris& faces, const sim::NodeVectors& x, double margin_mm,
                              const cutting::Positions* rest, const std::vector<int>* renumber) {
  Impl& m = *impl_;
  const double margin = std::max(margin_mm, 0.0);
  const size_t N = static_cast<size_t>(x.rows());
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int c = 0; c < 3; ++c)
      if (faces(f, c) < 0 || faces(f, c) >= x.rows()) {
        m.chunks.clear();
        m.num_faces = m.num_vertices = 0;
        return Error{"collision: face " + std::to_string(f) + " names a missing node"};
      }
  const bool use_rest = rest != nullptr && rest->rows() == x.rows();
  auto centroidAt = [&](const auto& at, Eigen::Index f) {
    return Eigen::Vector3d((at.row(faces(f, 0)) + at.row(faces(f, 1)) + at.row(faces(f, 2))).transpose() / 3.0);
  };
  auto centroid = [&](Eigen::Index f) { return use_rest ? centroidAt(*rest, f) : centroidAt(x, f); };
  // Keep the previous chunks only for a renumbered surface with the same margin and grid.
  const bool incremental = renumber != nullptr && margin == m.margin && !m.chunks.empty();
  m.margin = margin;
  if (!incremental) {
    m.chunks.clear();
    if (faces.rows() > 0) {
      Eigen::Vector3d lo = centroid(0), hi = lo;
      for (Eigen::Index f = 1; f < faces.rows(); ++f) {
        const Eigen::Vector3d c = centroid(f);
        lo = lo.cwiseMin(c);
        hi = hi.cwiseMax(c);
      }
      const Eigen::Vector3d ext = (hi - lo).cwiseMax(1e-6);
      m.cell = std::max(ext.maxCoeff() / kChunksAlongLongestAxis, 1e-6);
      m.origin = lo;
      for (int a = 0; a < 3; ++a) m.dims[a] = std::max(1, static_cast<int>(std::ceil(ext[a] / m.cell)));
    } else {
      m.dims = Eigen::Vector3i::Ones();
    }
    m.chunks.resize(static_cast<size_t>(m.dims.prod()));
  }
  // The new faces of each chunk, in face order.
  const size_t K = m.chunks.size();
  std::vector<int> chunk_of(static_cast<size_t>(faces.rows()));
  std::vector<int> start(K + 1, 0);
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    chunk_of[static_cast<size_t>(f)] = m.cellOf(centroid(f));
    ++start[static_cast<size_t>(chunk_of[static_cast<size_t>(f)]) + 1];
  }
  for (size_t k = 0; k < K; ++k) start[k + 1] += start[k];
  std::vector<std::array<int, 3>> sorted(static_cast<size_t>(faces.rows()));
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (Eigen::Index f = 0; f < faces.rows(); ++f)
      sorted[static_cast<size_t>(fill[static_cast<size_t>(chunk_of[static_cast<size_t>(f)])]++)] = {
          faces(f, 0), faces(f, 1), faces(f, 2)};
  }
  m.local.assign(N, -1);
  m.num_faces = static_cast<int>(faces.rows());
  for (size_t k = 0; k < K; ++k) {
    Chunk& c = m.chunks[k];
    const std::array<int, 3>* first = sorted.data() + start[k];
    const size_t count = static_cast<size_t>(start[k + 1] - start[k]);
    // Unchanged: the same faces in the same order, up to the renumbering of their nodes.
    bool same = incremental && c.bvh != nullptr && c.faces.size() == count && c.children_after_parents;
    for (size_t i = 0; i < count && same; ++i)
      for (int j = 0; j < 3 && same; ++j) {
        const int old = c.faces[i][j];
        same = old >= 0 && old < static_cast<int>(renumber->size()) && (*renumber)[static_cast<size_t>(old)] == first[i][j];
      }
    if (same) {
      // Followed as update() follows a step: the vertices move to x, those that left their
      // margin get their leaves refitted (a full refit of the chunk costs ~20x more).
      for (int& node : c.nodes) node = (*renumber)[static_cast<size_t>(node)];
      std::copy(first, first + count, c.faces.begin());
      ++m.chunks_kept;
      m.updateChunk(c, x);
      continue;
    }
    c.faces.assign(first, first + count);
    if (Status st = m.buildChunk(c, x); !st.ok()) {
      m.chunks.clear();
      m.num_faces = m.num_vertices = 0;
      return st;
    }
  }
  // Distinct vertices over all chunks (a node on a chunk border is a vertex of each).
  m.num_vertices = 0;
  for (const Chunk& c : m.chunks)
    for (int node : c.nodes)
      if (m.local[static_cast<size_t>(node)] < 0) {
        m.local[static_cast<size_t>(node)] = 0;
        ++m.num_vertices;
      }
  for (const Chunk& c : m.chunks)
    for (int node : c.nodes) m.local[static_cast<size_t>(node)] = -1;
  ++m.refits;
  return Status::Ok();
}

void TissueCollision::Impl::refitChunk(Chunk& c, const sim::NodeVectors& x) {
  Bvh* bvh = c.bvh.get();
  if (bvh == nullptr) return;
  fcl::Vector3d* v = bvh->vertices;
  for (size_t i = 0; i < c.nodes.size(); ++i) c.refit_x[i] = v[i] = x.row(c.nodes[i]).transpose();
  if (!c.children_after_parents) {
    // FCL's own refit (exact boxes; margin ignored, update() then refits every step).
    // replaceVertex() writes in place; beginReplaceModel() only frees prev_vertices, which a
    // replace-refitted model never has.
    bvh->beginReplaceModel();
    for (size_t i = 0; i < c.nodes.size(); ++i) bvh->replaceVertex(c.refit_x[i]);
    bvh->endReplaceModel(true, true);  // refit bottom-up, keep the tree
    return;
  }
  // The same bottom-up refit as FCL's endReplaceModel(true, true), as one loop (FCL numbers
  // a node's children after it, so a backward sweep sees children first; checked by build()),
  // with the leaf boxes grown by the margin.
  for (int b = bvh->getNumBVs() - 1; b >= 0; --b) {
    fcl::BVNode<fcl::AABBd>& n = bvh->getBV(b);
    if (n.isLeaf()) {
      c.fitLeaf(n.bv, n.primitiveId(), margin);
    } else {
      const fcl::AABBd& a = bvh->getBV(n.leftChild()).bv;
      const fcl::AABBd& d = bvh->getBV(n.rightChild()).bv;
      n.bv.min_ = a.min_.cwiseMin(d.min_);
      n.bv.max_ = a.max_.cwiseMax(d.max_);
    }
  }
}

void TissueCollision::refit(const sim::NodeVectors& x) {
  Impl& m = *impl_;
  ++m.refits;
  for (Chunk& c : m.chunks) m.refitChunk(c, x);
}

bool TissueCollision::Impl::updateChunk(Chunk& c, const sim::NodeVectors& x) {
  Bvh* bvh = c.bvh.get();
  if (bvh == nullptr) return false;
  if (!c.children_after_parents || margin <= 0.0) {
    refitChunk(c, x);
    return true;
  }
  // The narrow phase reads the vertices, so they always move. A vertex that has left its
  // margin is fitted anew where it is now: the leaves of its triangles are refitted and
  // their ancestors grown to hold them (up to the first that already does). Ancestors only
  // grow, so they stay valid; refit() tightens them again.
  fcl::Vector3d* v = bvh->vertices;
  const double limit = margin * margin;
  bool moved = false;
  for (size_t i = 0; i < c.nodes.size(); ++i) {
    v[i] = x.row(c.nodes[i]).transpose();
    if ((v[i] - c.refit_x[i]).squaredNorm() <= limit) continue;
    moved = true;
    ++local_refits;
    c.refit_x[i] = v[i];
    for (int k = c.vtx_start[i]; k < c.vtx_start[i + 1]; ++k) {
      const int tri = c.vtx_tris[static_cast<size_t>(k)];
      const int leaf = c.leaf_of_tri[static_cast<size_t>(tri)];
      fcl::AABBd& box = bvh->getBV(leaf).bv;
      c.fitLeaf(box, tri, margin);
      for (int p = c.parent[static_cast<size_t>(leaf)]; p >= 0; p = c.parent[static_cast<size_t>(p)]) {
        fcl::AABBd& up = bvh->getBV(p).bv;
        if (up.contain(box)) break;
        up.min_ = up.min_.cwiseMin(box.min_);
        up.max_ = up.max_.cwiseMax(box.max_);
      }
    }
  }
  return moved;
}

bool TissueCollision::update(const sim::NodeVectors& x) {
  bool moved = false;
  for (Chunk& c : impl_->chunks) moved = impl_->updateChunk(c, x) || moved;
  return moved;
}

bool TissueCollision::touches(const SweptWire& sweep, double radius) const {
  Bvh* wire = sweep.impl_->bvh.get();
  if (wire == nullptr) return false;
  // Start from the threshold: box pairs farther apart than the radius are pruned, and the
  // first pair of triangles that touches (distance 0) prunes everything left.
  const double threshold = std::max(radius, 0.0) + 1e-12;  // touching counts (radius 0: crossing)
  const fcl::AABBd& wire_box = wire->getBV(0).bv;
  for (const Chunk& c : impl_->chunks) {
    Bvh* tissue = c.bvh.get();
    if (tissue == nullptr) continue;
    // A chunk whose root box is that far from the wire's holds no triangle closer.
    if (tissue->getBV(0).bv.distance(wire_box) >= threshold) continue;
    // The traversal node is built here rather than through fcl::distance(), whose AABB path
    // copies both models per call. Identity poses: initialize() transforms nothing.
    fcl::detail::MeshDistanceTraversalNode<fcl::AABBd> node;
    fcl::Transform3d tf_tissue = fcl::Transform3d::Identity(), tf_wire = fcl::Transform3d::Identity();
    fcl::DistanceRequestd request(false);  // no nearest points
    fcl::DistanceResultd result;
    result.min_distance = threshold;
    if (!fcl::detail::initialize(node, *tissue, tf_tissue, *wire, tf_wire, request, result)) continue;
    fcl::detail::distance(&node);
    if (result.min_distance < threshold) return true;
  }
  return false;
}

}  // namespace hysim::engine
