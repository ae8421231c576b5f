#include "hysim/cutting/cut_surface.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <utility>

namespace hysim::cutting {

namespace {

// `v` / |v| without overflow or underflow in |v|: the plain quotient where the norm is well
// inside the double range (bit for bit what callers always got), else v is first scaled by
// its largest component, so that a normal like (0, 0, 1e300) is still a direction.
// Returns false for a zero or non-finite vector.
bool safeNormalized(const Eigen::Vector3d& v, Eigen::Vector3d& out) {
  if (!v.allFinite()) return false;
  const double len = v.norm();
  if (std::isfinite(len) && len > 1e-150) {
    out = v / len;
    return true;
  }
  const double largest = v.cwiseAbs().maxCoeff();
  if (!(largest > 0)) return false;
  const Eigen::Vector3d scaled = v / largest;
  out = scaled / scaled.norm();
  return true;
}

}  // namespace

Result<CutSurface> CutSurface::plane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal) {
  if (!point.allFinite() || !normal.allFinite()) return Error{"cut plane: non-finite point or normal"};
  if (point.cwiseAbs().maxCoeff() > kMaxCoordinateMm) {
    return Error{"cut plane: point coordinate beyond +-1e30 mm (larger values overflow distances)"};
  }
  CutSurface s;
  if (!safeNormalized(normal, s.normal_)) return Error{"cut plane: zero normal"};
  s.is_plane_ = true;
  s.point_ = point;
  return s;
}

Result<std::vector<CutSurface::Tri>> CutSurface::collect(const Positions& X, const Tris& F, std::vector<int>* kept) {
  std::vector<Tri> tri;  // in input order (degenerate ones dropped)
  tri.reserve(static_cast<size_t>(F.rows()));
  if (kept) kept->assign(static_cast<size_t>(F.rows()), -1);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k)
      if (F(f, k) < 0 || F(f, k) >= X.rows())
        return Error{"cut surface: triangle " + std::to_string(f) + " has a node index out of range"};
    Tri t;
    t.a = X.row(F(f, 0)).transpose();
    t.b = X.row(F(f, 1)).transpose();
    t.c = X.row(F(f, 2)).transpose();
    if (!t.a.allFinite() || !t.b.allFinite() || !t.c.allFinite())
      return Error{"cut surface: triangle " + std::to_string(f) + " has non-finite coordinates"};
    if (std::max({t.a.cwiseAbs().maxCoeff(), t.b.cwiseAbs().maxCoeff(), t.c.cwiseAbs().maxCoeff()}) > kMaxCoordinateMm)
      return Error{"cut surface: triangle " + std::to_string(f) + " has a coordinate beyond +-1e30 mm"};
    const Eigen::Vector3d n = (t.b - t.a).cross(t.c - t.a);
    const double scale = std::max({(t.b - t.a).squaredNorm(), (t.c - t.a).squaredNorm(), (t.c - t.b).squaredNorm()});
    if (!(n.norm() > 1e-12 * scale)) continue;  // degenerate
    t.n = n.normalized();
    if (kept) (*kept)[static_cast<size_t>(f)] = static_cast<int>(tri.size());
    tri.push_back(t);
  }
  if (tri.empty()) return Error{"cut surface: no non-degenerate triangle"};
  return tri;
}

void CutSurface::finish(const std::vector<Tri>& tri) {
  const int count = static_cast<int>(tri.size());
  // Per triangle, once: its box, a + b + c (the split key) and its centroid (a + b + c) / 3,
  // the same values the tree build used to recompute at every level.
  BuildScratch scratch;
  scratch.lo.resize(count);
  scratch.hi.resize(count);
  scratch.sum.resize(count);
  scratch.centre.resize(count);
  scratch.keyed.resize(count);
  for (int i = 0; i < count; ++i) {
    const Tri& t = tri[i];
    scratch.lo[i] = t.a.cwiseMin(t.b).cwiseMin(t.c);
    scratch.hi[i] = t.a.cwiseMax(t.b).cwiseMax(t.c);
    scratch.sum[i] = t.a + t.b + t.c;
    scratch.centre[i] = scratch.sum[i] / 3.0;
  }
  nodes_.reserve(2 * tri.size());
  build(0, count, scratch);
  bounds_ = nodes_[0].box;
  // The triangles in tree order (leaf ranges contiguous), with what the segment test needs.
  leafTri_.reserve(count);
  for (int i = 0; i < count; ++i) {
    const Tri& t = tri[order_[i]];
    leafTri_.push_back({t, t.n.dot((t.b - t.a).cross(t.c - t.a))});
  }
  finishWalkData();
}

void CutSurface::finishWalkData() {
  childBoxes_.resize(nodes_.size());
  for (size_t id = 0; id < nodes_.size(); ++id) {
    const Node& node = nodes_[id];
    ChildBoxes& c = childBoxes_[id];
    if (node.left < 0) {  // unused; written so that every entry has a value
      c = ChildBoxes{};
      continue;
    }
    for (int k = 0; k < 3; ++k) {
      c.lo[k][0] = nodes_[node.left].box.min()[k];
      c.lo[k][1] = nodes_[node.right].box.min()[k];
      c.hi[k][0] = nodes_[node.left].box.max()[k];
      c.hi[k][1] = nodes_[node.right].box.max()[k];
    }
  }
  nearPairs_.resize(leafTri_.size());
  planePairs_.resize(leafTri_.size());
  for (size_t i = 0; i < leafTri_.size(); ++i) {
    const Tri& t = leafTri_[i].t;
    const Eigen::Vector3d ab = t.b - t.a, ac = t.c - t.a;
    NearPairs& pp = nearPairs_[i];
    PlanePairs& pl = planePairs_[i];
    for (int k = 0; k < 3; ++k) {
      pp.a[k][0] = pp.a[k][1] = t.a[k];
      pp.b[k][0] = pp.b[k][1] = t.b[k];
      pp.c[k][0] = pp.c[k][1] = t.c[k];
      pp.e[k][0] = ab[k];
      pp.e[k][1] = ac[k];
      pl.p0[k][0] = pl.p0[k][1] = t.a[k];
      pl.n[k][0] = pl.n[k][1] = t.n[k];
    }
  }
}

Result<CutSurface> CutSurface::triangles(const Positions& X, const Tris& F) {
  auto tri = collect(X, F, nullptr);
  if (!tri.ok()) return Error{tri.error()};
  CutSurface s;
  s.is_plane_ = false;
  const int count = static_cast<int>(tri->size());
  s.order_.resize(count);
  for (int i = 0; i < count; ++i) s.order_[i] = i;
  s.finish(*tri);
  return s;
}

Tris CutSurface::stripTriangles(int rows, int row_size) {
  Tris F(2 * static_cast<Eigen::Index>(std::max(rows - 1, 0)) * std::max(row_size - 1, 0), 3);
  for (int r = 0, f = 0; r + 1 < rows; ++r)
    for (int i = 0; i + 1 < row_size; ++i) {
      const int a = r * row_size + i, b = a + 1, c = a + row_size, d = c + 1;
      F.row(f++) << a, b, d;
      F.row(f++) << a, d, c;
    }
  return F;
}

Result<CutSurface> CutSurface::strip(const Positions& X, int rows, int row_size) {
  if (rows < 2 || row_size < 2 || X.rows() != static_cast<Eigen::Index>(rows) * row_size)
    return Error{"cut surface: a strip needs at least 2 x 2 vertices, " + std::to_string(rows) + " x " +
                 std::to_string(row_size) + " for " + std::to_string(X.rows()) + " vertices"};
  std::vector<int> kept;
  auto tri = collect(X, stripTriangles(rows, row_size), &kept);
  if (!tri.ok()) return Error{tri.error()};
  CutSurface s;
  s.is_plane_ = false;
  s.order_.reserve(tri->size());
  // The tree follows a recursive bisection of the grid across its longer side (in space,
  // between the middles of opposite sides); a leaf holds one or two quads' kept triangles.
  auto at = [&](int r, int i) { return Eigen::Vector3d(X.row(static_cast<Eigen::Index>(r) * row_size + i).transpose()); };
  s.nodes_.reserve(2 * tri->size());
  auto node = [&](auto&& self, int r0, int r1, int c0, int c1) -> int {
    const int id = static_cast<int>(s.nodes_.size());
    s.nodes_.emplace_back();
    const int nr = r1 - r0, nc = c1 - c0;
    if (nr * nc <= 2) {
      Eigen::AlignedBox3d box;  // empty
      s.nodes_[id].begin = static_cast<int>(s.order_.size());
      for (int r = r0; r < r1; ++r)
        for (int c = c0; c < c1; ++c)
          for (int h = 0; h < 2; ++h) {
            const int k = kept[2 * (r * (row_size - 1) + c) + h];
            if (k < 0) continue;
            s.order_.push_back(k);
            const Tri& t = (*tri)[k];
            box.extend(t.a).extend(t.b).extend(t.c);
          }
      s.nodes_[id].end = static_cast<int>(s.order_.size());
      s.nodes_[id].box = box;
      return id;
    }
    const int rm = (r0 + r1) / 2, cm = (c0 + c1) / 2;
    const double along_rows = (at(r1, cm) - at(r0, cm)).norm(), along_cols = (at(rm, c1) - at(rm, c0)).norm();
    const bool split_rows = nc == 1 || (nr > 1 && along_rows >= along_cols);
    const int left = split_rows ? self(self, r0, rm, c0, c1) : self(self, r0, r1, c0, cm);
    const int right = split_rows ? self(self, rm, r1, c0, c1) : self(self, r0, r1, cm, c1);
    s.nodes_[id].left = left;
    s.nodes_[id].right = right;
    s.nodes_[id].box = s.nodes_[left].box.merged(s.nodes_[right].box);
    return id;
  };
  node(node, 0, rows - 1, 0, row_size - 1);
  s.bounds_ = s.nodes_[0].box;
  s.leafTri_.reserve(tri->size());
  for (int k : s.order_) {
    const Tri& t = (*tri)[k];
    s.leafTri_.push_back({t, t.n.dot((t.b - t.a).cross(t.c - t.a))});
  }
  s.finishWalkData();
  return s;
}

int CutSurface::build(int begin, int end, BuildScratch& scratch) {
  const int id = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  if (end - begin <= 4) {
    // A leaf: the box of its triangles (min/max: the same values in any order of extension).
    Eigen::Vector3d lo = scratch.lo[order_[begin]], hi = scratch.hi[order_[begin]];
    for (int i = begin + 1; i < end; ++i) {
      lo = lo.cwiseMin(scratch.lo[order_[i]]);
      hi = hi.cwiseMax(scratch.hi[order_[i]]);
    }
    nodes_[id].box = Eigen::AlignedBox3d(lo, hi);
    nodes_[id].begin = begin;
    nodes_[id].end = end;
    return id;
  }
  // Split at the median centroid along the longest axis of the centroids' box.
  Eigen::Vector3d clo = scratch.centre[order_[begin]], chi = clo;
  for (int i = begin + 1; i < end; ++i) {
    const Eigen::Vector3d& c = scratch.centre[order_[i]];
    clo = clo.cwiseMin(c);
    chi = chi.cwiseMax(c);
  }
  int axis;
  (chi - clo).maxCoeff(&axis);
  const int mid = (begin + end) / 2;
  // nth_element on (key, triangle) pairs: the same comparisons and moves as on order_ with
  // the keys looked up, so the same order, without the indirection.
  std::pair<double, int>* keyed = scratch.keyed.data();
  for (int i = begin; i < end; ++i) keyed[i] = {scratch.sum[order_[i]][axis], order_[i]};
  std::nth_element(keyed + begin, keyed + mid, keyed + end,
                   [](const std::pair<double, int>& x, const std::pair<double, int>& y) { return x.first < y.first; });
  for (int i = begin; i < end; ++i) order_[i] = keyed[i].second;
  const int left = build(begin, mid, scratch);
  const int right = build(mid, end, scratch);
  nodes_[id].left = left;
  nodes_[id].right = right;
  // The box of the children's boxes: that of all the range's triangles.
  nodes_[id].box = Eigen::AlignedBox3d(nodes_[left].box.min().cwiseMin(nodes_[right].box.min()),
                                       nodes_[left].box.max().cwiseMax(nodes_[right].box.max()));
  return id;
}

namespace {
// AlignedBox::squaredExteriorDistance without branches (the tree walks test many boxes):
// the same terms summed in the same order (a zero term leaves the sum unchanged), so the
// same value bit for bit, NaN coordinates included (they add nothing).
// (0 + a0^2 is a0^2 bit for bit: a square is +0, positive or NaN. With SSE2, x and y in one
// register: maxpd(v, 0) is v > 0 ? v : 0 per lane, NaN included, and the sum keeps the order
// (a0^2 + a1^2) + a2^2.)
inline double boxDistance2(const Eigen::AlignedBox3d& box, const Eigen::Vector3d& p) {
#if defined(__SSE2__)
  const __m128d zero = _mm_setzero_pd();
  const __m128d pxy = _mm_loadu_pd(p.data());
  const __m128d below = _mm_sub_pd(_mm_loadu_pd(box.min().data()), pxy);
  const __m128d above = _mm_sub_pd(pxy, _mm_loadu_pd(box.max().data()));
  const __m128d aux = _mm_add_pd(_mm_max_pd(below, zero), _mm_max_pd(above, zero));
  const __m128d sq = _mm_mul_pd(aux, aux);
  const __m128d belowZ = _mm_sub_sd(_mm_load_sd(box.min().data() + 2), _mm_load_sd(p.data() + 2));
  const __m128d aboveZ = _mm_sub_sd(_mm_load_sd(p.data() + 2), _mm_load_sd(box.max().data() + 2));
  const __m128d auxZ = _mm_add_sd(_mm_max_sd(belowZ, zero), _mm_max_sd(aboveZ, zero));
  const __m128d sum = _mm_add_sd(_mm_add_sd(sq, _mm_unpackhi_pd(sq, sq)), _mm_mul_sd(auxZ, auxZ));
  const double dist2 = _mm_cvtsd_f64(sum);
#ifdef HYSIM_CHECK_EXACT
  {
    double ref = 0;
    for (int k = 0; k < 3; ++k) {
      const double b = box.min()[k] - p[k], a = p[k] - box.max()[k];
      const double x = (b > 0 ? b : 0.0) + (a > 0 ? a : 0.0);
      ref += x * x;
    }
    if (std::memcmp(&ref, &dist2, sizeof dist2) != 0) std::abort();
  }
#endif
  return dist2;
#else
  double dist2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double below = box.min()[k] - p[k], above = p[k] - box.max()[k];
    const double aux = (below > 0 ? below : 0.0) + (above > 0 ? above : 0.0);
    dist2 += aux * aux;
  }
  return dist2;
#endif
}

// AlignedBox::intersects for two non-empty boxes (min <= max on every axis).
inline bool boxesMeet(const Eigen::AlignedBox3d& box, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  return box.min()[0] <= hi[0] && lo[0] <= box.max()[0] && box.min()[1] <= hi[1] && lo[1] <= box.max()[1] &&
         box.min()[2] <= hi[2] && lo[2] <= box.max()[2];
}
}  // namespace


// Both children's box distances at once: per lane the terms of boxDistance2 in its order,
// ((x^2 + y^2) + z^2 with each term max(min - p, 0) + max(p - max, 0)), so the same values bit
// for bit. The farther child onto the stack when within `limit`; the nearer one returned when
// within it (-1 otherwise): the walk visits it next, as when it was pushed last and popped at
// once (its check when popped, distance > limit, failed then: the limit had not changed).
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline int CutSurface::stepChildren(int id, const double* xx, double limit, int* stack, double* stackDist,
                                     int& top) const {
  const Node& node = nodes_[id];
  double dl, dr;
#if !defined(__SSE2__) || defined(HYSIM_CHECK_EXACT)
  const Eigen::Vector3d x(xx[0], xx[2], xx[4]);
#endif
#if defined(__SSE2__)
  const ChildBoxes& c = childBoxes_[id];
  const __m128d zero = _mm_setzero_pd();
  __m128d aux[3];
  for (int k = 0; k < 3; ++k) {
    const __m128d p = _mm_load_pd(xx + 2 * k);
    const __m128d below = _mm_sub_pd(_mm_load_pd(c.lo[k]), p), above = _mm_sub_pd(p, _mm_load_pd(c.hi[k]));
    aux[k] = _mm_add_pd(_mm_max_pd(below, zero), _mm_max_pd(above, zero));
  }
  const __m128d sum = _mm_add_pd(_mm_add_pd(_mm_mul_pd(aux[0], aux[0]), _mm_mul_pd(aux[1], aux[1])),
                                 _mm_mul_pd(aux[2], aux[2]));
  dl = _mm_cvtsd_f64(sum);
  dr = _mm_cvtsd_f64(_mm_unpackhi_pd(sum, sum));
#ifdef HYSIM_CHECK_EXACT
  {
    const double rl = boxDistance2(nodes_[node.left].box, x), rr = boxDistance2(nodes_[node.right].box, x);
    if (std::memcmp(&rl, &dl, sizeof dl) != 0 || std::memcmp(&rr, &dr, sizeof dr) != 0) std::abort();
  }
#endif
#else
  dl = boxDistance2(nodes_[node.left].box, x);
  dr = boxDistance2(nodes_[node.right].box, x);
#endif
  const bool leftFirst = dl <= dr;
  const double dFar = leftFirst ? dr : dl, dNear = leftFirst ? dl : dr;
  if (dFar <= limit) {
    stack[top] = leftFirst ? node.right : node.left;
    stackDist[top++] = dFar;
  }
  return dNear <= limit ? (leftFirst ? node.left : node.right) : -1;
}

// Which of inner node id's children's boxes meet the box [lo, hi] (bit 0: the left, bit 1: the
// right): boxesMeet's comparisons (min <= hi and lo <= max on every axis, false with a NaN),
// for both children at once.
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline int CutSurface::childrenMeet(int id, const double* lohi) const {
#if !defined(__SSE2__) || defined(HYSIM_CHECK_EXACT)
  const Eigen::Vector3d lo(lohi[0], lohi[2], lohi[4]), hi(lohi[6], lohi[8], lohi[10]);
#endif
#if defined(__SSE2__)
  const ChildBoxes& c = childBoxes_[id];
  __m128d meets[3];
  for (int k = 0; k < 3; ++k)
    meets[k] = _mm_and_pd(_mm_cmple_pd(_mm_load_pd(c.lo[k]), _mm_load_pd(lohi + 6 + 2 * k)),
                          _mm_cmple_pd(_mm_load_pd(lohi + 2 * k), _mm_load_pd(c.hi[k])));
  const int mask = _mm_movemask_pd(_mm_and_pd(_mm_and_pd(meets[0], meets[1]), meets[2]));
#ifdef HYSIM_CHECK_EXACT
  if (mask != (int(boxesMeet(nodes_[nodes_[id].left].box, lo, hi)) | int(boxesMeet(nodes_[nodes_[id].right].box, lo, hi)) << 1))
    std::abort();
#endif
  return mask;
#else
  return int(boxesMeet(nodes_[nodes_[id].left].box, lo, hi)) | int(boxesMeet(nodes_[nodes_[id].right].box, lo, hi)) << 1;
#endif
}

namespace {
// The nearest point of triangle (a, b, c) to p, by the Voronoi-region walk (Ericson,
// Real-Time Collision Detection, 5.1.5), with its edges ab = b - a, ac = c - a, bc = c - b
// given; inlined into the leaf loops of builds without SSE2, which call it millions of times.
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline Eigen::Vector3d closestPointWithEdges(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                             const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                             const Eigen::Vector3d& ab, const Eigen::Vector3d& ac,
                                             const Eigen::Vector3d& bc) {
  const Eigen::Vector3d ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * bc;
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// closestPointWithEdges with the edges computed here.
inline Eigen::Vector3d closestPointOnTriangleInline(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                                    const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  return closestPointWithEdges(p, a, b, c, b - a, c - a, c - b);
}
}  // namespace

#if defined(__SSE2__)
// closestPointWithEdges for the point with coordinates xx (each twice): the dot products in
// pairs, (ab.dot(v), ac.dot(v)) for v = p - a, p - b, p - c, each summed as Eigen's 3-vector
// dot, (e0 v0 + e1 v1) + e2 v2, from the same differences p - vertex: the same values, so the
// same point bit for bit.
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline Eigen::Vector3d CutSurface::closestPointPaired(const double* xx, int i) const {
  const NearPairs& pp = nearPairs_[i];
  // The triangle's vertices and edges from the first of each pair (c - b formed here, the
  // same operation on the same values as closestPointOnTriangle's).
  auto first = [](const double (*v)[2]) { return Eigen::Vector3d(v[0][0], v[1][0], v[2][0]); };
  auto second = [](const double (*v)[2]) { return Eigen::Vector3d(v[0][1], v[1][1], v[2][1]); };
  struct {
    Eigen::Vector3d a, b, c, ab, ac;
  } t{first(pp.a), first(pp.b), first(pp.c), first(pp.e), second(pp.e)};
  auto dots = [&](const double (*v)[2]) {
    __m128d s[3];
    for (int k = 0; k < 3; ++k)
      s[k] = _mm_mul_pd(_mm_load_pd(pp.e[k]), _mm_sub_pd(_mm_load_pd(xx + 2 * k), _mm_load_pd(v[k])));
    return _mm_add_pd(_mm_add_pd(s[0], s[1]), s[2]);
  };
  const __m128d d12 = dots(pp.a);
  const double d1 = _mm_cvtsd_f64(d12), d2 = _mm_cvtsd_f64(_mm_unpackhi_pd(d12, d12));
  if (d1 <= 0 && d2 <= 0) return t.a;
  const __m128d d34 = dots(pp.b);
  const double d3 = _mm_cvtsd_f64(d34), d4 = _mm_cvtsd_f64(_mm_unpackhi_pd(d34, d34));
  if (d3 >= 0 && d4 <= d3) return t.b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return t.a + (d1 / (d1 - d3)) * t.ab;
  const __m128d d56 = dots(pp.c);
  const double d5 = _mm_cvtsd_f64(d56), d6 = _mm_cvtsd_f64(_mm_unpackhi_pd(d56, d56));
  if (d6 >= 0 && d5 <= d6) return t.c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return t.a + (d2 / (d2 - d6)) * t.ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return t.b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (t.c - t.b);
  const double denom = 1.0 / (va + vb + vc);
  return t.a + t.ab * (vb * denom) + t.ac * (vc * denom);
}
#endif

#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline Eigen::Vector3d CutSurface::nearestOnLeaf(const double* xx, const Eigen::Vector3d& x, int i) const {
#if defined(__SSE2__)
  (void)x;
  const Eigen::Vector3d q = closestPointPaired(xx, i);
#else
  (void)xx;
  const Tri& t = leafTri_[i].t;
  const Eigen::Vector3d q = closestPointOnTriangleInline(x, t.a, t.b, t.c);
#endif
#ifdef HYSIM_CHECK_EXACT
  {
    const Tri& t = leafTri_[i].t;
    const Eigen::Vector3d ref = closestPointOnTriangleInline(x, t.a, t.b, t.c);
    if (std::memcmp(ref.data(), q.data(), sizeof(double) * 3) != 0) std::abort();
  }
#endif
  return q;
}

Eigen::Vector3d closestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c) {
  return closestPointOnTriangleInline(p, a, b, c);
}

double CutSurface::signedDistance(const Eigen::Vector3d& x, Eigen::Vector3d* closest) const {
  return signedDistanceNear(x, std::numeric_limits<double>::infinity(), closest);
}

// The stack holds each node with its box distance (computed when its parent pushed it: the
// same value as computing it again when popped).
// (The walk is that of pushing the root, then popping a node, skipping it when its distance
// is above the bound, else testing a leaf's triangles or pushing an inner node's children
// within the bound, the nearer last; the nearer child, popped at once, is visited without the
// stack.)
template <class Leaf>
void CutSurface::walkNear(const Eigen::Vector3d& x, const double* xx, const double& bound, Leaf&& leaf) const {
  int stack[128];
  double stackDist[128];
  int top = 0;
  int id = boxDistance2(nodes_[0].box, x) > bound ? -1 : 0;
  for (;;) {
    if (id < 0) {
      if (top == 0) break;
      --top;
      if (stackDist[top] > bound) continue;  // (equal: a tie with a lower index may be there)
      id = stack[top];
    }
    const Node& node = nodes_[id];
    if (node.left < 0) {
      if (leaf(node.begin, node.end)) return;
      id = -1;
    } else if (top + 2 <= 128) {
      id = stepChildren(id, xx, bound, stack, stackDist, top);
    } else {
      id = -1;
    }
  }
}

double CutSurface::signedDistanceNear(const Eigen::Vector3d& x, double r, Eigen::Vector3d* closest) const {
  if (is_plane_) {
    const double d = normal_.dot(x - point_);
    if (closest) *closest = x - d * normal_;
    return d;
  }
  // Start with the bound r^2 (a margin for rounding) instead of infinity: boxes and triangles
  // farther than r are skipped; the nearest triangle, within r, is found as before (ties: the
  // lower index), so the result is the same.
  double best = std::isfinite(r) ? r * r * (1.0 + 1e-6) + std::numeric_limits<double>::min()
                                 : std::numeric_limits<double>::infinity();
  int bestTri = -1, bestLeaf = -1;  // input index (for ties), place in leafTri_
  Eigen::Vector3d bestPoint = x;
  alignas(16) const double xx[6] = {x[0], x[0], x[1], x[1], x[2], x[2]};
  walkNear(x, xx, best, [&](int begin, int end) {
    for (int i = begin; i < end; ++i) {
      const Eigen::Vector3d q = nearestOnLeaf(xx, x, i);
      const double d2 = (q - x).squaredNorm();
      // (Ties: the lower triangle index, whatever the order of the walk.)
      if (d2 < best || (d2 == best && order_[i] < bestTri)) {
        best = d2;
        bestTri = order_[i];
        bestLeaf = i;
        bestPoint = q;
      }
    }
    return false;
  });
  if (bestTri < 0 && std::isfinite(r)) return signedDistanceNear(x, std::numeric_limits<double>::infinity(), closest);
  if (closest) *closest = bestPoint;
  if (bestTri < 0) return std::numeric_limits<double>::infinity();
  const double d = std::sqrt(best);
  const Tri& t = leafTri_[bestLeaf].t;
  return t.n.dot(x - t.a) < 0 ? -d : d;
}

bool CutSurface::intersectSegment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double eps, Hit* hit) const {
  auto tryPlane = [&](const Eigen::Vector3d& n, const Eigen::Vector3d& p0, double* t, double* da, double* db) {
    *da = n.dot(a - p0);
    *db = n.dot(b - p0);
    if (!((*da > eps && *db < -eps) || (*da < -eps && *db > eps))) return false;
    *t = *da / (*da - *db);
    return true;
  };
  if (is_plane_) {
    double t, da, db;
    if (!tryPlane(normal_, point_, &t, &da, &db)) return false;
    hit->t = t;
    hit->point = a + t * (b - a);
    hit->normal = normal_;
    hit->da = da;
    hit->db = db;
    return true;
  }
  const Eigen::Vector3d segLo = a.cwiseMin(b), segHi = a.cwiseMax(b);
  alignas(16) const double ends[6] = {a[0], b[0], a[1], b[1], a[2], b[2]};  // a and b, axis by axis
  alignas(16) const double segBox[12] = {segLo[0], segLo[0], segLo[1], segLo[1], segLo[2], segLo[2],
                                         segHi[0], segHi[0], segHi[1], segHi[1], segHi[2], segHi[2]};
  bool found = false;
  double bestT = 2.0;
  // (The walk of pushing the root when its box meets the segment's, then popping a node,
  // testing a leaf's triangles or pushing an inner node's children whose boxes meet the
  // segment's, the left first; the right child, popped at once, is visited without the stack.)
  int stack[128];
  int top = 0;
  int id = boxesMeet(nodes_[0].box, segLo, segHi) ? 0 : -1;
  for (;;) {
    if (id < 0) {
      if (top == 0) break;
      id = stack[--top];
    }
    const Node& node = nodes_[id];
    if (node.left < 0) {
      id = -1;
      for (int i = node.begin; i < node.end; ++i) {
        const Tri& tr = leafTri_[i].t;
        double t, da, db;
#if defined(__SSE2__)
        {
          // tryPlane with both ends at once: lane 0 a, lane 1 b, each n.dot(end - p0) as Eigen's
          // 3-vector dot sums it, (n0 d0 + n1 d1) + n2 d2, so the same values bit for bit.
          const PlanePairs& pp = planePairs_[i];
          __m128d d[3];
          for (int k = 0; k < 3; ++k)
            d[k] = _mm_mul_pd(_mm_load_pd(pp.n[k]), _mm_sub_pd(_mm_load_pd(ends + 2 * k), _mm_load_pd(pp.p0[k])));
          const __m128d dd = _mm_add_pd(_mm_add_pd(d[0], d[1]), d[2]);
          da = _mm_cvtsd_f64(dd);
          db = _mm_cvtsd_f64(_mm_unpackhi_pd(dd, dd));
#ifdef HYSIM_CHECK_EXACT
          const double ra = tr.n.dot(a - tr.a), rb = tr.n.dot(b - tr.a);
          if (std::memcmp(&ra, &da, sizeof da) != 0 || std::memcmp(&rb, &db, sizeof db) != 0) std::abort();
#endif
          if (!((da > eps && db < -eps) || (da < -eps && db > eps))) continue;
          t = da / (da - db);
          if (t >= bestT) continue;
        }
#else
        if (!tryPlane(tr.n, tr.a, &t, &da, &db) || t >= bestT) continue;
#endif
        const Eigen::Vector3d p = a + t * (b - a);
        // Inclusive inside test by signed sub-triangle areas along the normal.
        const double area = leafTri_[i].area;
        const double slack = -1e-12 * area;
        // (Each area tested as soon as it is known: the same values, fewer computed.)
        if (tr.n.dot((tr.b - p).cross(tr.c - p)) < slack) continue;
        if (tr.n.dot((tr.c - p).cross(tr.a - p)) < slack) continue;
        if (tr.n.dot((tr.a - p).cross(tr.b - p)) < slack) continue;
        found = true;
        bestT = t;
        hit->t = t;
        hit->point = p;
        hit->normal = tr.n;
        hit->da = da;
        hit->db = db;
      }
    } else if (top + 2 <= 128) {
      // Children whose boxes miss the segment's are not pushed (the same walk, in the same
      // order, as testing them when popped).
      const int meet = childrenMeet(id, segBox);
      if (meet == 3) {
        stack[top++] = node.left;
        id = node.right;
      } else {
        id = meet == 2 ? node.right : meet == 1 ? node.left : -1;
      }
    } else {
      id = -1;
    }
  }
  return found;
}

bool CutSurface::mayTouch(const Eigen::AlignedBox3d& box, double eps) const {
  if (is_plane_) {
    // Support of the box along the normal.
    const Eigen::Vector3d c = box.center(), h = 0.5 * box.sizes();
    const double r = std::abs(normal_.x()) * h.x() + std::abs(normal_.y()) * h.y() + std::abs(normal_.z()) * h.z();
    return std::abs(normal_.dot(c - point_)) <= r + eps;
  }
  Eigen::Vector3d grownLo = box.min(), grownHi = box.max();
  grownLo.array() -= eps;
  grownHi.array() += eps;
  // Down the tree: the box meets a leaf's box (a few triangles). (Only nodes whose boxes meet
  // it are visited, the right child before the left, as when both were pushed and tested when
  // popped. The depth guard: a tree is at most about log2(triangles) + 2 deep, far below it.)
  if (!boxesMeet(nodes_[0].box, grownLo, grownHi)) return false;
  alignas(16) const double grownBox[12] = {grownLo[0], grownLo[0], grownLo[1], grownLo[1], grownLo[2], grownLo[2],
                                           grownHi[0], grownHi[0], grownHi[1], grownHi[1], grownHi[2], grownHi[2]};
  int stack[128];
  int top = 0;
  int id = 0;
  for (;;) {
    if (id < 0) {
      if (top == 0) return false;
      id = stack[--top];
    }
    const Node& node = nodes_[id];
    if (node.left < 0 || top + 2 > 128) return true;
    const int meet = childrenMeet(id, grownBox);
    if (meet == 3) {
      stack[top++] = node.left;
      id = node.right;
    } else {
      id = meet == 2 ? node.right : meet == 1 ? node.left : -1;
    }
  }
}

bool CutSurface::within(const Eigen::Vector3d& x, double r) const {
  if (is_plane_) return std::abs(normal_.dot(x - point_)) <= r;
  // Boxes farther than r (with a margin for rounding) cannot hold a triangle within r.
  const double limit = r * r * (1.0 + 1e-6) + std::numeric_limits<double>::min();
  alignas(16) const double xx[6] = {x[0], x[0], x[1], x[1], x[2], x[2]};
  bool found = false;
  walkNear(x, xx, limit, [&](int begin, int end) {
    for (int i = begin; i < end && !found; ++i) found = std::sqrt((nearestOnLeaf(xx, x, i) - x).squaredNorm()) <= r;
    return found;
  });
  return found;
}

}  // namespace hysim::cutting
