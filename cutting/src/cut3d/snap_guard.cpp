// What the snapping stage asks of a node: may it move there (the guard), its boundary faces
// and its feature edges.
#include <algorithm>

#include "cut3d_stages.hpp"
#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::cutting::cut3d_detail {

namespace {

inline std::uint64_t mix64(std::uint64_t x) {
  x ^= x >> 30;
  x *= 0xBF58476D1CE4E5B9ull;
  x ^= x >> 27;
  x *= 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Quick test for the usual case, an interior node: is every face containing n shared by an
// even number of n's tets? XOR of a 64-bit hash of each face (by its other two nodes) over
// the star: zero when every face occurs an even number of times; a face used once (a
// boundary face; there are at least three around a boundary node) leaves a random non-zero
// value (zero only with probability 2^-64).
bool evenFacePairs(const Work& w, int n, const std::vector<std::int32_t>& starOff, const StarVector& starTet) {
  std::uint64_t acc = 0;
  for (int s = starOff[n]; s < starOff[n + 1]; ++s) {
    const auto& tv = w.tet(starTet[s]);
    // The three edges of the tet without n: the faces with n, by their other two nodes.
    for (const auto& e : kFacePairs[findLocal(tv, n)]) {
      const std::uint32_t a = static_cast<std::uint32_t>(tv[e[0]]), b = static_cast<std::uint32_t>(tv[e[1]]);
      acc ^= mix64((static_cast<std::uint64_t>(std::min(a, b)) << 32) | std::max(a, b));
    }
  }
  return acc == 0;
}

// Whether f(p, q) holds for every tet of n's star: its corners now (p) and with n at
// `target` (q).
template <class F>
bool everyMovedTet(const Work& w, const StarLists& stars, int n, const Vec3& target, F&& f) {
  for (int s = stars.off[n]; s < stars.off[n + 1]; ++s) {
    const Tet& tv = w.tet(stars.star[s]);
    Vec3 p[4], q[4];
    for (int k = 0; k < 4; ++k) {
      p[k] = w.x(tv[k]);
      q[k] = tv[k] == n ? target : p[k];
    }
    if (!f(p, q)) return false;
  }
  return true;
}

}  // namespace

// Moving node n to `target` keeps every tet of its star positive, not flat and not badly
// degraded (q* below min(before, min_quality)), and every edge of n at least
// min_edge_fraction of its length. (Cheapest test first; each edge of n once although
// several tets share it.)
bool Cut3D::guardOk(int n, const Vec3& target) {
  if (!guardVolumes(n, target)) return false;
  const Vec3 old = w.x(n);
  guardNbrs.clear();
  bool ok = true;
  for (int s = stars.off[n]; s < stars.off[n + 1] && ok; ++s)
    for (const int v : w.tet(stars.star[s])) {
      if (v == n || guardSeen[v]) continue;
      guardSeen[v] = 1;
      guardNbrs.push_back(v);
      const Vec3& pv = w.x(v);
      if ((pv - target).norm() < options.min_edge_fraction * (pv - old).norm()) {
        ok = false;
        break;
      }
    }
  for (const int v : guardNbrs) guardSeen[v] = 0;
  return ok && guardQuality(n, target);
}

bool Cut3D::guardVolumes(int n, const Vec3& target) const {
  return everyMovedTet(w, stars, n, target, [](const Vec3* p, const Vec3* q) {
    const double v0 = signedVolume(p[0], p[1], p[2], p[3]);
    const double v1 = signedVolume(q[0], q[1], q[2], q[3]);
    return v1 > 1e-3 * v0;
  });
}

bool Cut3D::guardQuality(int n, const Vec3& target) const {
  return everyMovedTet(w, stars, n, target, [this](const Vec3* p, const Vec3* q) {
    const double qa = radiusRatio(q[0], q[1], q[2], q[3]);
    return !(qa < options.min_quality && qa < radiusRatio(p[0], p[1], p[2], p[3]));
  });
}

// The faces go to `out` (cleared first): scratch vectors owned by the callers, so that no
// call allocates once they have grown.
void Cut3D::boundaryFacesOf(int n, std::vector<BFace>& out) {
  BoundaryFaceCache& c = bfCache;
  if (c.start[n] < 0 && evenFacePairs(w, n, stars.off, stars.star)) {
    c.start[n] = static_cast<std::int32_t>(c.pool.size());  // interior: no boundary face
    c.count[n] = 0;
  }
  if (c.start[n] < 0) findBoundaryFaces(n);
  out.clear();
  for (int q = c.start[n]; q < c.start[n] + c.count[n]; ++q) {
    const BoundaryFaceCache::Topo& f = c.pool[q];
    out.push_back({f.u, f.v, Vec3((w.x(f.i1) - w.x(f.i0)).cross(w.x(f.i2) - w.x(f.i0))).normalized()});
  }
}

// Faces with n used by one tet of its star, into the cache.
void Cut3D::findBoundaryFaces(int n) {
  BoundaryFaceCache& c = bfCache;
  c.seen.clear();
  // Local numbers of n's neighbours; faceAt: (pair of them) -> index in seen.
  c.nbrs.clear();
  for (int s = stars.off[n]; s < stars.off[n + 1]; ++s)
    for (const int v : w.tet(stars.star[s]))
      if (v != n && c.local[v] < 0) {
        c.local[v] = static_cast<std::int32_t>(c.nbrs.size());
        c.nbrs.push_back(v);
      }
  const size_t L = c.nbrs.size();
  if (c.faceAt.size() < L * L) c.faceAt.resize(L * L, -1);  // all -1 between calls
  for (int s = stars.off[n]; s < stars.off[n + 1]; ++s) {
    const Tet tv = w.tet(stars.star[s]);
    const int ln = findLocal(tv, n);
    for (int f = 0; f < 4; ++f) {
      if (f == ln) continue;
      const int i0 = tv[kFace[f][0]], i1 = tv[kFace[f][1]], i2 = tv[kFace[f][2]];
      std::int32_t o[2], m = 0;
      for (int v : {i0, i1, i2})
        if (v != n) o[m++] = v;
      if (o[0] > o[1]) std::swap(o[0], o[1]);
      const std::int32_t a = c.local[o[0]], b = c.local[o[1]];
      std::int32_t& at = c.faceAt[std::min(a, b) * L + std::max(a, b)];
      if (at >= 0) {
        ++c.seen[at].count;
      } else {
        at = static_cast<std::int32_t>(c.seen.size());
        c.seen.push_back({o[0], o[1], i0, i1, i2, 1});
      }
    }
  }
  for (const auto& q : c.seen) {
    const std::int32_t a = c.local[q.u], b = c.local[q.v];
    c.faceAt[std::min(a, b) * L + std::max(a, b)] = -1;
  }
  for (int v : c.nbrs) c.local[v] = -1;
  c.start[n] = static_cast<std::int32_t>(c.pool.size());
  for (const auto& q : c.seen)
    if (q.count == 1) c.pool.push_back({q.i0, q.i1, q.i2, q.u, q.v});
  c.count[n] = static_cast<std::int32_t>(c.pool.size()) - c.start[n];
}

// A node may slide along its feature edges and stays on the feature lines (a corner or a
// bent ridge only a short way: feature_slide_fraction of the edge, 0 = never).
FeatureEdges Cut3D::featureEdgesOf(int n) {
  FeatureEdges fe;
  std::vector<BFace>& bf = bfCache.featureFaces;
  boundaryFacesOf(n, bf);
  auto& edges = bfCache.edges;
  edges.clear();
  auto add = [&](std::int32_t v, const Vec3& nrm) {
    for (auto& e : edges)
      if (e.v == v) {
        if (e.count < 2) e.normal[e.count] = nrm;
        ++e.count;
        return;
      }
    edges.push_back({v, 1, {nrm, Vec3::Zero()}});
  };
  for (const auto& f : bf) {
    add(f.u, f.normal);
    add(f.v, f.normal);
  }
  for (const auto& e : edges) {
    if (e.count != 2) return FeatureEdges{};
    if (e.normal[0].dot(e.normal[1]) < cosFeature) fe.to.push_back(e.v);
  }
  if (fe.to.size() == 2) {
    const Vec3 d0 = (w.x(fe.to[0]) - w.x(n)).normalized(), d1 = (w.x(fe.to[1]) - w.x(n)).normalized();
    fe.straight = d0.dot(d1) < -cosFeature;
  }
  fe.polyhedral = !fe.to.empty() && polyhedralCorner(n, bf);
  return fe;
}

// A corner of flat facets (every boundary face around n coplanar with another one, as on a
// box): sliding it would bend a facet and change the volume, so it does not slide. A face's
// twin may also be a boundary face of its other two nodes.
bool Cut3D::polyhedralCorner(int n, const std::vector<BFace>& bf) {
  bool polyhedral = true;
  for (size_t i = 0; i < bf.size() && polyhedral; ++i) {
    bool twin = false;
    for (size_t j = 0; j < bf.size() && !twin; ++j) twin = j != i && bf[i].normal.dot(bf[j].normal) > 1.0 - 1e-9;
    for (const int m : {bf[i].u, bf[i].v}) {
      if (twin) break;
      boundaryFacesOf(m, bfCache.neighbourFaces);
      for (const auto& g : bfCache.neighbourFaces)
        if (g.u != n && g.v != n && bf[i].normal.dot(g.normal) > 1.0 - 1e-9) twin = true;
    }
    polyhedral = twin;
  }
  return polyhedral;
}

}  // namespace hysim::cutting::cut3d_detail
