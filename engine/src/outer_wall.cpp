#include "hysim/engine/outer_wall.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

namespace hysim::engine {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

Eigen::Vector3d row(const cutting::Positions& V, int i) { return V.row(i).transpose(); }

// Closest point of triangle abc to p (Ericson, Real-Time Collision Detection 5.1.5), and which
// feature it lies on: 0 interior, 1-3 vertex a/b/c, 4 edge ab, 5 edge bc, 6 edge ca.
Eigen::Vector3d closestOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                  const Eigen::Vector3d& c, int& feature) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) {
    feature = 1;
    return a;
  }
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) {
    feature = 2;
    return b;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    feature = 4;
    return a + (d1 / (d1 - d3)) * ab;
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) {
    feature = 3;
    return c;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    feature = 6;
    return a + (d2 / (d2 - d6)) * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    feature = 5;
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  }
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0.0)) {  // degenerate triangle: its first vertex will do
    feature = 1;
    return a;
  }
  feature = 0;
  return a + ab * (vb / denom) + ac * (vc / denom);
}

// Moeller-Trumbore: whether the ray meets triangle abc at some t > 0.
bool rayTriangle(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& a,
                 const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d e1 = b - a, e2 = c - a;
  const Eigen::Vector3d h = d.cross(e2);
  const double det = e1.dot(h);
  if (std::abs(det) < 1e-14) return false;  // parallel
  const double inv = 1.0 / det;
  const Eigen::Vector3d s = o - a;
  const double u = inv * s.dot(h);
  if (u < 0.0 || u > 1.0) return false;
  const Eigen::Vector3d q = s.cross(e1);
  const double v = inv * d.dot(q);
  if (v < 0.0 || u + v > 1.0) return false;
  return inv * e2.dot(q) > 1e-9;
}

bool rayBox(const Eigen::Vector3d& o, const Eigen::Vector3d& inv_d, const Eigen::AlignedBox3d& box) {
  double t0 = 0.0, t1 = kInf;
  for (int k = 0; k < 3; ++k) {
    double ta = (box.min()[k] - o[k]) * inv_d[k];
    double tb = (box.max()[k] - o[k]) * inv_d[k];
    if (std::isnan(ta) || std::isnan(tb)) {  // direction 0 along k with o on a slab plane
      if (o[k] < box.min()[k] || o[k] > box.max()[k]) return false;
      continue;
    }
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

}  // namespace

// ---- TriangleBvh ------------------------------------------------------------------------

void TriangleBvh::build(const cutting::Positions& V, const cutting::Tris& F) {
  V_ = V;
  F_ = F;
  nodes_.clear();
  order_.resize(static_cast<size_t>(F.rows()));
  std::vector<Eigen::Vector3d> centroids(static_cast<size_t>(F.rows()));
  for (int f = 0; f < F.rows(); ++f) {
    order_[static_cast<size_t>(f)] = f;
    centroids[static_cast<size_t>(f)] = (row(V, F(f, 0)) + row(V, F(f, 1)) + row(V, F(f, 2))) / 3.0;
  }
  if (F.rows() > 0) buildRange(0, static_cast<int>(F.rows()), centroids);
}

int TriangleBvh::buildRange(int first, int count, std::vector<Eigen::Vector3d>& centroids) {
  const int index = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  nodes_[static_cast<size_t>(index)].first = first;
  nodes_[static_cast<size_t>(index)].count = count;
  if (count > 4) {
    Eigen::AlignedBox3d cbox;
    cbox.setEmpty();
    for (int i = first; i < first + count; ++i) cbox.extend(centroids[static_cast<size_t>(order_[static_cast<size_t>(i)])]);
    int axis = 0;
    cbox.sizes().maxCoeff(&axis);
    const int half = count / 2;
    std::nth_element(order_.begin() + first, order_.begin() + first + half, order_.begin() + first + count,
                     [&](int a, int b) {
                       const double ca = centroids[static_cast<size_t>(a)][axis], cb = centroids[static_cast<size_t>(b)][axis];
                       return ca < cb || (ca == cb && a < b);
                     });
    const int left = buildRange(first, half, centroids);
    const int right = buildRange(first + half, count - half, centroids);
    Node& n = nodes_[static_cast<size_t>(index)];
    n.left = left;
    n.right = right;
    n.count = 0;
  }
  fitNode(index);
  return index;
}

void TriangleBvh::fitNode(int index) {
  Node& n = nodes_[static_cast<size_t>(index)];
  n.box.setEmpty();
  if (n.count > 0) {
    for (int i = n.first; i < n.first + n.count; ++i) {
      const int f = order_[static_cast<size_t>(i)];
      for (int c = 0; c < 3; ++c) n.box.extend(row(V_, F_(f, c)));
    }
  } else {
    n.box.extend(nodes_[static_cast<size_t>(n.left)].box);
    n.box.extend(nodes_[static_cast<size_t>(n.right)].box);
  }
}

void TriangleBvh::refit(const cutting::Positions& V) {
  V_ = V;  // same size: no allocation
  for (int i = static_cast<int>(nodes_.size()) - 1; i >= 0; --i) fitNode(i);
}

int TriangleBvh::nearest(const Eigen::Vector3d& p, Eigen::Vector3d& closest, int& feature) const {
  if (nodes_.empty()) return -1;
  double best2 = kInf;
  int best = -1;
  int stack[kStack];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[static_cast<size_t>(stack[--top])];
    if (n.box.squaredExteriorDistance(p) >= best2) continue;
    if (n.count > 0) {
      for (int i = n.first; i < n.first + n.count; ++i) {
        const int f = order_[static_cast<size_t>(i)];
        int feat = 0;
        const Eigen::Vector3d q = closestOnTriangle(p, row(V_, F_(f, 0)), row(V_, F_(f, 1)), row(V_, F_(f, 2)), feat);
        const double d2 = (q - p).squaredNorm();
        if (d2 < best2) {
          best2 = d2;
          best = f;
          closest = q;
          feature = feat;
        }
      }
      continue;
    }
    if (top + 2 > kStack) continue;  // cannot happen for a median-split tree of < 2^40 faces
    const double dl = nodes_[static_cast<size_t>(n.left)].box.squaredExteriorDistance(p);
    const double dr = nodes_[static_cast<size_t>(n.right)].box.squaredExteriorDistance(p);
    // Nearer child on top: visited first, so the bound shrinks early.
    if (dl <= dr) {
      stack[top++] = n.right;
      stack[top++] = n.left;
    } else {
      stack[top++] = n.left;
      stack[top++] = n.right;
    }
  }
  return best;
}

bool TriangleBvh::rayHits(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, int skip_face) const {
  if (nodes_.empty()) return false;
  const Eigen::Vector3d inv_d = dir.cwiseInverse();
  int stack[kStack];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[static_cast<size_t>(stack[--top])];
    if (!rayBox(origin, inv_d, n.box)) continue;
    if (n.count > 0) {
      for (int i = n.first; i < n.first + n.count; ++i) {
        const int f = order_[static_cast<size_t>(i)];
        if (f == skip_face) continue;
        if (rayTriangle(origin, dir, row(V_, F_(f, 0)), row(V_, F_(f, 1)), row(V_, F_(f, 2)))) return true;
      }
      continue;
    }
    if (top + 2 > kStack) continue;
    stack[top++] = n.left;
    stack[top++] = n.right;
  }
  return false;
}

// ---- OuterWall --------------------------------------------------------------------------

void OuterWall::build(const cutting::TetMesh& mesh, const std::vector<std::uint8_t>& fixed, double band_mm,
                      double cell_mm) {
  band_ = band_mm;
  cell_ = cell_mm;
  const cutting::Tris boundary = cutting::boundaryFaces(mesh);
  num_boundary_faces_ = static_cast<int>(boundary.rows());
  TriangleBvh all;
  all.build(mesh.X, boundary);

  // Serosal faces: every ray from the face centre into the outward half-space escapes.
  constexpr double kTilt = 0.5235987755982988;  // 30 degrees
  std::vector<int> serosal;
  for (int f = 0; f < boundary.rows(); ++f) {
    const Eigen::Vector3d a = row(mesh.X, boundary(f, 0)), b = row(mesh.X, boundary(f, 1)), c = row(mesh.X, boundary(f, 2));
    Eigen::Vector3d n = (b - a).cross(c - a);
    if (!(n.norm() > 0.0)) continue;
    n.normalize();
    const Eigen::Vector3d centre = (a + b + c) / 3.0;
    const Eigen::Vector3d t1 = (b - a).normalized();
    const Eigen::Vector3d t2 = n.cross(t1);
    const Eigen::Vector3d dirs[5] = {n,
                                     std::cos(kTilt) * n + std::sin(kTilt) * t1,
                                     std::cos(kTilt) * n - std::sin(kTilt) * t1,
                                     std::cos(kTilt) * n + std::sin(kTilt) * t2,
                                     std::cos(kTilt) * n - std::sin(kTilt) * t2};
    bool escapes = true;
    for (const Eigen::Vector3d& d : dirs) {
      if (all.rayHits(centre, d, f)) {
        escapes = false;
        break;
      }
    }
    if (escapes) serosal.push_back(f);
  }

  // Compact vertex numbering.
  std::vector<int> local(static_cast<size_t>(mesh.numNodes()), -1);
  node_.clear();
  F_.resize(static_cast<Eigen::Index>(serosal.size()), 3);
  for (size_t k = 0; k < serosal.size(); ++k) {
    for (int c = 0; c < 3; ++c) {
      const int node = boundary(serosal[k], c);
      if (local[static_cast<size_t>(node)] < 0) {
        local[static_cast<size_t>(node)] = static_cast<int>(node_.size());
        node_.push_back(node);
      }
      F_(static_cast<Eigen::Index>(k), c) = local[static_cast<size_t>(node)];
    }
  }
  V_.resize(static_cast<Eigen::Index>(node_.size()), 3);
  static_ = true;
  for (size_t s = 0; s < node_.size(); ++s) {
    V_.row(static_cast<Eigen::Index>(s)) = mesh.X.row(node_[s]);
    if (static_cast<size_t>(node_[s]) >= fixed.size() || !fixed[static_cast<size_t>(node_[s])]) static_ = false;
  }

  // Face neighbours across each edge (for the edges' pseudo-normals).
  neighbour_.assign(static_cast<size_t>(3 * F_.rows()), -1);
  std::map<std::pair<int, int>, int> edge_slot;
  for (int f = 0; f < F_.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int u = F_(f, k), v = F_(f, (k + 1) % 3);
      const auto key = std::make_pair(std::min(u, v), std::max(u, v));
      auto it = edge_slot.find(key);
      if (it == edge_slot.end()) {
        edge_slot.emplace(key, 3 * f + k);
      } else {
        neighbour_[static_cast<size_t>(3 * f + k)] = it->second / 3;
        neighbour_[static_cast<size_t>(it->second)] = f;
      }
    }
  }
  vertex_face_start_.assign(static_cast<size_t>(V_.rows()) + 1, 0);
  for (int f = 0; f < F_.rows(); ++f)
    for (int c = 0; c < 3; ++c) ++vertex_face_start_[static_cast<size_t>(F_(f, c)) + 1];
  for (size_t v = 0; v + 1 < vertex_face_start_.size(); ++v) vertex_face_start_[v + 1] += vertex_face_start_[v];
  vertex_faces_.assign(static_cast<size_t>(3 * F_.rows()), -1);
  {
    std::vector<int> fill(vertex_face_start_.begin(), vertex_face_start_.end() - 1);
    for (int f = 0; f < F_.rows(); ++f)
      for (int c = 0; c < 3; ++c) vertex_faces_[static_cast<size_t>(fill[static_cast<size_t>(F_(f, c))]++)] = f;
  }
  bvh_.build(V_, F_);

  // Grid: a cell needs no query when its centre is more than band + slack + half its
  // diagonal inside (the signed distance changes by at most the distance the point or the
  // surface moves).
  needs_query_.clear();
  grid_size_.setZero();
  grid_valid_ = false;
  if (F_.rows() == 0) return;
  grid_slack_ = static_ ? 0.0 : cell_;
  grid_V_ = V_;
  const Eigen::Vector3d lo = V_.colwise().minCoeff().transpose();
  const Eigen::Vector3d hi = V_.colwise().maxCoeff().transpose();
  grid_origin_ = lo - Eigen::Vector3d::Constant(cell_);
  for (int k = 0; k < 3; ++k) grid_size_[k] = static_cast<int>(std::ceil((hi[k] - lo[k]) / cell_)) + 2;
  needs_query_.assign(static_cast<size_t>(grid_size_.prod()), 1);
  const double half_diagonal = 0.5 * std::sqrt(3.0) * cell_;
  for (int i = 0; i < grid_size_[0]; ++i) {
    for (int j = 0; j < grid_size_[1]; ++j) {
      for (int k = 0; k < grid_size_[2]; ++k) {
        const Eigen::Vector3d centre = grid_origin_ + cell_ * Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5);
        const bool far = signedDistance(centre) - half_diagonal >= band_ + grid_slack_;
        needs_query_[static_cast<size_t>((i * grid_size_[1] + j) * grid_size_[2] + k)] = far ? 0 : 1;
      }
    }
  }
  grid_valid_ = true;
}

Eigen::Vector3d OuterWall::faceNormal(int f) const {
  const Eigen::Vector3d a = row(V_, F_(f, 0));
  const Eigen::Vector3d n = (row(V_, F_(f, 1)) - a).cross(row(V_, F_(f, 2)) - a);
  const double len = n.norm();
  return len > 0.0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

Eigen::Vector3d OuterWall::vertexNormal(int v) const {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int k = vertex_face_start_[static_cast<size_t>(v)]; k < vertex_face_start_[static_cast<size_t>(v) + 1]; ++k) {
    const int f = vertex_faces_[static_cast<size_t>(k)];
    int c = 0;
    while (c < 2 && F_(f, c) != v) ++c;
    const Eigen::Vector3d p = row(V_, v);
    const Eigen::Vector3d e1 = row(V_, F_(f, (c + 1) % 3)) - p, e2 = row(V_, F_(f, (c + 2) % 3)) - p;
    const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
    sum += angle * faceNormal(f);
  }
  return sum;
}

void OuterWall::update(const sim::NodeVectors& x) {
  if (static_ || F_.rows() == 0) return;
  double moved2 = 0.0;
  for (Eigen::Index s = 0; s < V_.rows(); ++s) {
    const int node = node_[static_cast<size_t>(s)];
    if (node >= 0 && node < x.rows()) V_.row(s) = x.row(node);
    moved2 = std::max(moved2, (V_.row(s) - grid_V_.row(s)).squaredNorm());
  }
  grid_valid_ = !needs_query_.empty() && moved2 <= grid_slack_ * grid_slack_;
  bvh_.refit(V_);
}

void OuterWall::remapNodes(const std::vector<int>& old_to_new) {
  for (int& node : node_) {
    node = node >= 0 && static_cast<size_t>(node) < old_to_new.size() ? old_to_new[static_cast<size_t>(node)] : -1;
  }
}

double OuterWall::signedDistance(const Eigen::Vector3d& p) const {
  Eigen::Vector3d closest;
  int feature = 0;
  const int f = bvh_.nearest(p, closest, feature);
  if (f < 0) return kInf;
  // Sign from the angle-weighted pseudo-normal of the nearest feature (Baerentzen & Aanaes):
  // exact for a closed surface, and right near an open one's interior.
  Eigen::Vector3d n;
  if (feature == 0) {
    n = faceNormal(f);
  } else if (feature <= 3) {
    n = vertexNormal(F_(f, feature - 1));
  } else {
    const int other = neighbour_[static_cast<size_t>(3 * f + feature - 4)];
    n = faceNormal(f) + faceNormal(other >= 0 ? other : f);
  }
  const double d = (p - closest).norm();
  return (p - closest).dot(n) > 0.0 ? -d : d;
}

bool OuterWall::farInside(const Eigen::Vector3d& p) const {
  if (!grid_valid_) return false;
  const Eigen::Vector3d g = (p - grid_origin_) / cell_;
  int idx[3];
  for (int k = 0; k < 3; ++k) {
    if (!(g[k] >= 0.0) || g[k] >= grid_size_[k]) return false;
    idx[k] = static_cast<int>(g[k]);
  }
  return needs_query_[static_cast<size_t>((idx[0] * grid_size_[1] + idx[1]) * grid_size_[2] + idx[2])] == 0;
}

double OuterWall::clearance(const Eigen::Vector3d& p) const {
  if (farInside(p)) return band_;
  return signedDistance(p);
}

}  // namespace hysim::engine
