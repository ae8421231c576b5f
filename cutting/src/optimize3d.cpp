// Local optimisation of a tet mesh around a cut (the paper's 2D regularisation carried to
// 3D, its "future work"). Only nodes of poor elements near the cut take part. Each node moves
// within what keeps the cut and the boundary where they are:
//  - interior nodes freely, but never onto or across the cut surface (sides are kept);
//  - nodes on the cut only within the cut plane (plane cuts; on a curved surface only where
//    all their boundary faces are coplanar), and only if every boundary face around them
//    lies in the cut (rim nodes, where the cut meets the outer boundary, stay);
//  - other boundary nodes only where their boundary is flat (every face normal within
//    boundary_flat_deg of the area-weighted normal), and only perpendicular to that normal:
//    the volume of a mesh is linear in one node's position with gradient (1/3) * the sum of
//    its boundary faces' area vectors, so such a move keeps the volume exactly.
// On a curved cut (shaving: the loop's swept strip skims the tissue at shallow angles and
// leaves thin wedges between the cut and the boundary, and rough boundaries from earlier
// passes), more is allowed, within the volume budget: cut nodes slide on the cut where their
// cut faces are within boundary_curved_deg; boundary nodes there move on their own boundary
// faces; rim nodes (cut meets boundary) and crease nodes slide along their ridge (these moves
// within a small volume budget of their own); 2-3 and 3-2 flips repair
// slivers whose nodes cannot move; snaps and collapses may change a tiny star's volume by a
// fraction of a regular tet of the local edge. Shaving passes also sweep over the rough
// surfaces earlier passes left (thin flaps, slivers of four boundary nodes, fixed corners),
// so on curved cuts: the repair region takes the poor tets within repair_rings of the cut;
// interior edges with 4 to 6 tets around are removed (the ring triangulated as a fan) where
// that helps; edges with neither end on the cut collapse too (one material, boundary into
// boundary); the volume budgets bound the net change (collapses add and remove volume
// locally), the sum of absolute changes volume_churn_factor x that. Plane cuts are as before.
// Candidate moves (ascent along the gradient of the worst incident element's q*, a damped
// spring step toward the local mean edge length, a push away from the face opposite the
// node in its worst element; each tried at decreasing lengths) are kept only if no incident
// tet inverts and the worst incident q* rises: the local minimum quality never drops.
#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <iterator>
#include <limits>
#include <vector>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/mesh_stats.hpp"
#include "flap_peel.hpp"
#include "optimize3d_internal.hpp"

namespace hysim::cutting {
namespace {

using Vec3 = Eigen::Vector3d;
constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

// v[0, mid) and v[mid, end), each sorted, into one sorted list without repeats (what sort +
// unique of the whole gives); scratch is working room.
void mergeSortedRuns(std::vector<std::int32_t>& v, size_t mid, std::vector<std::int32_t>& scratch) {
  scratch.clear();
  const auto m = v.begin() + static_cast<std::ptrdiff_t>(mid);
  std::merge(v.begin(), m, m, v.end(), std::back_inserter(scratch));
  scratch.erase(std::unique(scratch.begin(), scratch.end()), scratch.end());
  v.swap(scratch);
}

// Six times tetVolume (mesh.cpp), inlined, in scalars over the coordinate columns: Eigen's
// cross (y1 z2 - z1 y2, z1 x2 - x1 z2, x1 y2 - y1 x2) and 3-vector dot ((a0 b0 + a1 b1) +
// a2 b2), the same value as (x1 - x0).dot((x2 - x0).cross(x3 - x0)) (checked bit for bit).
inline double tetVolume6Here(const TetMesh& mesh, int t) {
  const double* cx = mesh.X.col(0).data();
  const double* cy = mesh.X.col(1).data();
  const double* cz = mesh.X.col(2).data();
  const int i0 = mesh.T(t, 0), i1 = mesh.T(t, 1), i2 = mesh.T(t, 2), i3 = mesh.T(t, 3);
  const double ax = cx[i1] - cx[i0], ay = cy[i1] - cy[i0], az = cz[i1] - cz[i0];
  const double bx = cx[i2] - cx[i0], by = cy[i2] - cy[i0], bz = cz[i2] - cz[i0];
  const double ex = cx[i3] - cx[i0], ey = cy[i3] - cy[i0], ez = cz[i3] - cz[i0];
  const double nx = by * ez - bz * ey, ny = bz * ex - bx * ez, nz = bx * ey - by * ex;
  const double v6 = (ax * nx + ay * ny) + az * nz;
#ifdef HYSIM_CHECK_EXACT
  const Eigen::Vector3d x0 = mesh.X.row(i0), x1 = mesh.X.row(i1), x2 = mesh.X.row(i2), x3 = mesh.X.row(i3);
  const double ref = (x1 - x0).dot((x2 - x0).cross(x3 - x0));
  if (std::memcmp(&ref, &v6, sizeof v6) != 0) std::abort();
#endif
  return v6;
}
// tetVolume (mesh.cpp) inlined: the same value.
inline double tetVolumeHere(const TetMesh& mesh, int t) {
  const double v = tetVolume6Here(mesh, t) / 6.0;
#ifdef HYSIM_CHECK_EXACT
  const double ref = tetVolume(mesh, t);
  if (std::memcmp(&ref, &v, sizeof v) != 0) std::abort();
#endif
  return v;
}

enum class Freedom { Free, Plane, Surface, Fan, Ridge, Fixed };

// A volume budget: the net change stays within `limit`, the sum of the absolute changes
// within churn_factor x limit.
struct VolumeBudget {
  double limit = 0, churn_factor = 1, net = 0, churn = 0;
  bool fits(double dv) const {
    return std::abs(net + dv) <= limit && churn + std::abs(dv) <= churn_factor * limit;
  }
  void spend(double dv) {
    net += dv;
    churn += std::abs(dv);
  }
};
struct Constraint {
  Freedom kind = Freedom::Fixed;
  Vec3 normal = Vec3::Zero();  // Plane: moves are perpendicular to it
  Vec3 ridge[2];               // Ridge: the two neighbours along the ridge
};

}  // namespace

// The mesh's volume as the optimisation's budgets take it: tetVolume's value per tet, in
// scalars without the out-of-line cross product (tetVolumeHere), added in index order. Two
// tets at a time in SSE2 lanes: each lane does tetVolume6Here's operations, / 6.0, so it
// holds tetVolumeHere's value.
double optimizeMeshVolume(const TetMesh& mesh) {
  double meshVolume = 0;
  const int M = mesh.numTets();
  {
    int t = 0;
#if defined(__SSE2__)
    const double* cx = mesh.X.col(0).data();
    const double* cy = mesh.X.col(1).data();
    const double* cz = mesh.X.col(2).data();
    const std::int32_t *c0 = mesh.T.col(0).data(), *c1 = mesh.T.col(1).data(), *c2 = mesh.T.col(2).data(),
                       *c3 = mesh.T.col(3).data();
    const __m128d six = _mm_set1_pd(6.0);
    auto pair = [](const double* c, int a, int b) { return _mm_loadh_pd(_mm_load_sd(c + a), c + b); };
    for (; t + 2 <= M; t += 2) {
      const int a0 = c0[t], a1 = c1[t], a2 = c2[t], a3 = c3[t];
      const int b0 = c0[t + 1], b1 = c1[t + 1], b2 = c2[t + 1], b3 = c3[t + 1];
      const __m128d x0 = pair(cx, a0, b0), y0 = pair(cy, a0, b0), z0 = pair(cz, a0, b0);
      const __m128d ax = _mm_sub_pd(pair(cx, a1, b1), x0), ay = _mm_sub_pd(pair(cy, a1, b1), y0),
                    az = _mm_sub_pd(pair(cz, a1, b1), z0);
      const __m128d bx = _mm_sub_pd(pair(cx, a2, b2), x0), by = _mm_sub_pd(pair(cy, a2, b2), y0),
                    bz = _mm_sub_pd(pair(cz, a2, b2), z0);
      const __m128d ex = _mm_sub_pd(pair(cx, a3, b3), x0), ey = _mm_sub_pd(pair(cy, a3, b3), y0),
                    ez = _mm_sub_pd(pair(cz, a3, b3), z0);
      const __m128d nx = _mm_sub_pd(_mm_mul_pd(by, ez), _mm_mul_pd(bz, ey));
      const __m128d ny = _mm_sub_pd(_mm_mul_pd(bz, ex), _mm_mul_pd(bx, ez));
      const __m128d nz = _mm_sub_pd(_mm_mul_pd(bx, ey), _mm_mul_pd(by, ex));
      const __m128d v6 = _mm_add_pd(_mm_add_pd(_mm_mul_pd(ax, nx), _mm_mul_pd(ay, ny)), _mm_mul_pd(az, nz));
      const __m128d v = _mm_div_pd(v6, six);
      const double v0 = _mm_cvtsd_f64(v), v1 = _mm_cvtsd_f64(_mm_unpackhi_pd(v, v));
#ifdef HYSIM_CHECK_EXACT
      const double r0 = tetVolumeHere(mesh, t), r1 = tetVolumeHere(mesh, t + 1);
      if (std::memcmp(&r0, &v0, sizeof v0) != 0 || std::memcmp(&r1, &v1, sizeof v1) != 0) std::abort();
#endif
      meshVolume += v0;
      meshVolume += v1;
    }
#endif
    for (; t < M; ++t) meshVolume += tetVolumeHere(mesh, t);
  }
  return meshVolume;
}

void optimizeAroundCut(TetMesh& mesh, const CutRegion& region, const Optimize3DOptions& options,
                       std::vector<std::int32_t>* moved, std::vector<std::uint8_t>* dead, OptimizeCounts* counts) {
  const int N = mesh.numNodes(), M = mesh.numTets();
  if (region.left_alone != nullptr && region.left_alone->size() == static_cast<size_t>(M)) {
    *dead = *region.left_alone;
  } else {
    dead->assign(M, 0);
  }
  if (region.seeds.empty() || N == 0) return;
  const bool plane = region.surface && region.surface->isPlane();
  // The repairs for curved cut surfaces (shaving): curved boundaries and ridges move, slivers
  // are flipped, snaps and collapses measure volume against the local edge; plane cuts keep
  // the plane-cut behaviour.
  const bool curved = region.surface != nullptr && !plane;
  // Runs step() and adds its wall time to *ms (counts' timings, when counts are asked for).
  auto timed = [counts](double OptimizeCounts::*ms, auto&& step) {
    const auto start = std::chrono::steady_clock::now();
    step();
    if (counts) counts->*ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  };
  std::vector<std::uint8_t> onCut = region.on_cut;  // grows: nodes snapped onto the cut here
  const double cosFlat = std::cos(options.boundary_flat_deg * M_PI / 180.0);
  const double cosCurved =
      curved ? std::cos(std::max(options.boundary_flat_deg, options.boundary_curved_deg) * M_PI / 180.0) : cosFlat;
  const double cosRidge = std::cos(options.ridge_deg * M_PI / 180.0);

  // Node -> tets of the whole mesh (one O(#T) pass, or taken over from region.stars;
  // everything else is local), live tets in index order. After edge collapses the lists of
  // the nodes whose tets died or changed are rebuilt (buildStars), into `ovrPool`; the others
  // keep their CSR rows.
  std::vector<std::int32_t> off, ovrStart, ovrLen, ovrPool;
  StarVector star;
  bool built = false;
  if (region.stars != nullptr) {
    off.swap(region.stars->off);
    star.swap(region.stars->star);
    ovrStart.swap(region.stars->pool_start);
    ovrLen.swap(region.stars->pool_len);
    ovrPool.swap(region.stars->pool);
    built = true;
  } else {
    off.assign(N + 1, 0);
    star.resize(4 * static_cast<size_t>(M));
    ovrStart.assign(N, -1);
    ovrLen.assign(N, 0);
  }
  std::vector<std::uint8_t> touched(N, 0);
  std::vector<std::int32_t> touchedList;
  std::vector<std::pair<std::int32_t, std::int32_t>> gained;  // (node, tet): tet took the node
  const NodeStars stars{off, star, ovrStart, ovrLen, ovrPool};
  auto starB = [&](int n) { return stars.begin(n); };
  auto starE = [&](int n) { return stars.end(n); };
  auto touch = [&](int n) {
    if (!touched[n]) {
      touched[n] = 1;
      touchedList.push_back(n);
    }
  };
  std::vector<std::int32_t> killed;  // tets removed here, in order (their slots may be reused)
  auto kill = [&](int t) {
    (*dead)[t] = 1;
    killed.push_back(t);
    for (int k = 0; k < 4; ++k) touch(mesh.T(t, k));
  };
  std::vector<std::int32_t> scratch, scratch2;
  auto buildStars = [&]() {
    if (!built) {
      built = true;
      for (int t = 0; t < M; ++t)
        if (!(*dead)[t])
          for (int k = 0; k < 4; ++k) ++off[mesh.T(t, k) + 1];
      for (int i = 0; i < N; ++i) off[i + 1] += off[i];
      std::vector<std::int32_t> fill(off.begin(), off.end() - 1);
      for (int t = 0; t < M; ++t)
        if (!(*dead)[t])
          for (int k = 0; k < 4; ++k) star[fill[mesh.T(t, k)]++] = t;
      return;
    }
    // The same lists as a full rebuild: live tets with the node, in index order.
    std::sort(gained.begin(), gained.end());
    for (int n : touchedList) {
      scratch.assign(starB(n), starE(n));
      auto g = std::lower_bound(gained.begin(), gained.end(), std::make_pair(static_cast<std::int32_t>(n), std::int32_t{-1}));
      // (A list is sorted and without repeats: a node that gained no tet needs no sort.)
      // (Both runs are sorted, the gained tets as `gained` is: merged, as a sort of the whole.)
      if (g != gained.end() && g->first == n) {
        const size_t mid = scratch.size();
        for (; g != gained.end() && g->first == n; ++g) scratch.push_back(g->second);
        mergeSortedRuns(scratch, mid, scratch2);
      }
#ifdef HYSIM_CHECK_EXACT
      if (std::adjacent_find(scratch.begin(), scratch.end(), std::greater_equal<std::int32_t>()) != scratch.end())
        std::abort();
#endif
      ovrStart[n] = static_cast<std::int32_t>(ovrPool.size());
      for (int t : scratch) {
        if ((*dead)[t]) continue;
        bool has = false;
        for (int k = 0; k < 4; ++k) has = has || mesh.T(t, k) == n;
        if (has) ovrPool.push_back(t);
      }
      ovrLen[n] = static_cast<std::int32_t>(ovrPool.size()) - ovrStart[n];
      touched[n] = 0;
    }
    touchedList.clear();
    gained.clear();
  };
  buildStars();
  // Peeling and collapses change the volume; together they may change it by at most
  // volume_budget of the mesh's volume.
  const double meshVolume = optimizeMeshVolume(mesh);
  // Curved cuts: the budgets bound the net change of the mesh volume (collapses and moves
  // add and remove volume; what they move about cancels) and, at volume_churn_factor x
  // that, the sum of the absolute changes. Plane cuts: the sum of the absolute changes.
  const double churnFactor = curved ? std::max(1.0, options.volume_churn_factor) : 1.0;
  VolumeBudget budget{meshVolume * options.volume_budget, churnFactor};
  // A collapse or snap may change its star's volume by collapse_volume_fraction of the star,
  // or of a regular tet with the local edge length where the star is smaller (a node very
  // near the cut among tiny tets).
  const double edgeTet = region.edge_length * region.edge_length * region.edge_length / (6.0 * std::sqrt(2.0));
  // Moves on curved surfaces: each within move_volume_fraction of a regular tet of the local
  // edge, all together within move_volume_budget of the mesh's volume.
  VolumeBudget moveBudget{meshVolume * options.move_volume_budget, churnFactor};
  const double refVolume = curved && options.collapse_volume_fraction_of_edge_tet ? edgeTet : 0.0;
  // Per material (collapse_material_limit): matVol gathers, per label, (before, after) of the
  // star's tets (a tet keeps its label, a dying tet's volume goes); matFits checks each against
  // collapse_volume_fraction of its own part or of the whole star (starBefore).
  struct MatVol {
    std::int32_t m;
    double before, after;
  };
  std::vector<MatVol> matVol;
  matVol.reserve(8);
  auto matAdd = [&](int t, double before, double after) {
    const std::int32_t m = mesh.material(t);
    for (MatVol& e : matVol)
      if (e.m == m) {
        e.before += before;
        e.after += after;
        return;
      }
    matVol.push_back({m, before, after});
  };
  using MaterialLimit = Optimize3DOptions::MaterialLimit;
  auto matFits = [&](double starBefore) {
    if (!curved || options.collapse_material_limit == MaterialLimit::Off || matVol.size() < 2) return true;
    for (const MatVol& e : matVol) {
      const double ref = options.collapse_material_limit == MaterialLimit::OwnPart ? e.before : starBefore;
      if (std::abs(e.after - e.before) > options.collapse_volume_fraction * std::max(ref, refVolume)) return false;
    }
    return true;
  };
  auto pos = [&](int i) -> Vec3 { return mesh.X.row(i).transpose(); };
  // q* of tet t, cached per tet with the node indices and the nodes' versions it was computed
  // from (nodeVer[n] counts the writes of n's position here; a hit needs the same nodes, none
  // moved since, so the value is exactly what radiusRatio returns).
  // (Each write takes a new number; restorePos puts back a position and the number it had.)
  std::vector<std::uint32_t> nodeVer(N, 0);
  std::uint32_t verClock = 0;
  auto setPos = [&](int n, const Vec3& x) {
    mesh.X.row(n) = x.transpose();
    nodeVer[n] = ++verClock;
  };
  auto restorePos = [&](int n, const Vec3& x, std::uint32_t ver) {
    mesh.X.row(n) = x.transpose();
    nodeVer[n] = ver;
  };
  struct QEntry {
    std::int32_t v[4];
    std::uint32_t ver[4];
    double q;
    std::int8_t up;  // tetVolume6Here > 0 at these positions (1, 0), -1: not asked yet
  };
  // (At most one entry per tet, in the order first asked.)
  std::vector<std::int32_t> qSlot(M, -1);
  std::vector<QEntry, NoInitAllocator<QEntry>> qPool(static_cast<size_t>(M));
  std::int32_t qNext = 0;
  auto tetQ = [&](int t) {
    QEntry cur;
    for (int k = 0; k < 4; ++k) {
      cur.v[k] = mesh.T(t, k);
      cur.ver[k] = nodeVer[cur.v[k]];
    }
    std::int32_t& slot = qSlot[t];
    if (slot >= 0) {
      const QEntry& e = qPool[slot];
      if (std::equal(cur.v, cur.v + 4, e.v) && std::equal(cur.ver, cur.ver + 4, e.ver)) return e.q;
    } else {
      slot = qNext++;
    }
    cur.q = radiusRatio(pos(cur.v[0]), pos(cur.v[1]), pos(cur.v[2]), pos(cur.v[3]));
    cur.up = -1;
    qPool[slot] = cur;
    return cur.q;
  };
  // vol6 > 0 ? tetQ(t) : -1 (vol6 = tetVolume6Here(mesh, t)), the sign cached with q*.
  // (An entry is only made where vol6 > 0, as tetQ is only asked there.)
  auto tetQUp = [&](int t) {
    QEntry cur;
    for (int k = 0; k < 4; ++k) {
      cur.v[k] = mesh.T(t, k);
      cur.ver[k] = nodeVer[cur.v[k]];
    }
    std::int32_t& slot = qSlot[t];
    if (slot >= 0) {
      QEntry& e = qPool[slot];
      if (std::equal(cur.v, cur.v + 4, e.v) && std::equal(cur.ver, cur.ver + 4, e.ver)) {
        if (e.up < 0) e.up = tetVolume6Here(mesh, t) > 0 ? 1 : 0;
        return e.up ? e.q : -1.0;
      }
    }
    if (!(tetVolume6Here(mesh, t) > 0)) return -1.0;
    if (slot < 0) slot = qNext++;
    cur.q = radiusRatio(pos(cur.v[0]), pos(cur.v[1]), pos(cur.v[2]), pos(cur.v[3]));
    cur.up = 1;
    qPool[slot] = cur;
    return cur.q;
  };
  // Quality of tet t with node n placed at y; negative when it would invert or go flat.
  // (The corners passed directly, n's replaced by y: the same values as a copy.)
  auto tetQAt = [&](int t, int n, const Vec3& y) {  // -1 where not (p1-p0).((p2-p0)x(p3-p0)) > 0
    const int a = mesh.T(t, 0), b = mesh.T(t, 1), c = mesh.T(t, 2), d = mesh.T(t, 3);
    if (a == n) return radiusRatioOriented(y, pos(b), pos(c), pos(d));
    if (b == n) return radiusRatioOriented(pos(a), y, pos(c), pos(d));
    if (c == n) return radiusRatioOriented(pos(a), pos(b), y, pos(d));
    if (d == n) return radiusRatioOriented(pos(a), pos(b), pos(c), y);
    return radiusRatioOriented(pos(a), pos(b), pos(c), pos(d));
  };
  // Worst q* around n where it is (tetQAt at its own position, through the cache).
  auto starWorst = [&](int n, int* worstTet) {
    double q = 1.0;
    for (const std::int32_t *s = starB(n), *sEnd = starE(n); s < sEnd; ++s) {
      const int t = (*s);
      if ((*dead)[t]) continue;
      const double qt = tetQUp(t);  // -1 where not (p1 - p0).dot((p2 - p0).cross(p3 - p0)) > 0
      if (qt < q) {
        q = qt;
        if (worstTet) *worstTet = (*s);
        if (qt < 0) return qt;
      }
    }
    return q;
  };
  // Is the worst q* around n with n at y above `floor`? Tet `first` (the likely worst) is
  // tried first and the scan stops at the first tet at or below the floor; when it passes,
  // *q receives the worst q* (as starWorst).
  // (firstQ: tetQAt(first, n, y), which the caller has already computed.)
  // The answer does not depend on the order of the tets (any at or below the floor: false;
  // else the minimum): the tet that failed n's last such test (lastBelow[n], where it is
  // still a live tet of n) is tried second, as it is likely to fail again.
  std::vector<std::int32_t> lastBelow(N, -1);
  auto starAbove = [&](int n, const Vec3& y, int first, double firstQ, double floor, double* q) {
    double worst = firstQ;
    if (!(worst > floor)) return false;
    int second = lastBelow[n];
    if (second == first || second < 0 || (*dead)[second]) {
      second = -1;
    } else {
      bool has = false;
      for (int k = 0; k < 4; ++k) has = has || mesh.T(second, k) == n;
      if (!has) second = -1;
    }
    if (second >= 0) {
      const double qt = tetQAt(second, n, y);
      if (!(qt > floor)) return false;
      worst = std::min(worst, qt);
    }
    for (const std::int32_t *s = starB(n), *sEnd = starE(n); s < sEnd; ++s) {
      if ((*s) == first || (*s) == second || (*dead)[(*s)]) continue;
      const double qt = tetQAt((*s), n, y);
      if (!(qt > floor)) {
        lastBelow[n] = *s;
        return false;
      }
      worst = std::min(worst, qt);
    }
    *q = std::min(1.0, worst);
    return true;
  };
  // Where node n may move (see the file comment).
  // The faces around n by the pair of their nodes other than n: where first seen (tet, face),
  // how many tets use them, the table entry; pairCount is -1 everywhere between calls.
  struct FaceUse {
    std::int32_t t, f, count, key;
  };
  // The boundary faces around n (used by one tet), in the order first seen.
  struct BFace {
    std::int32_t u, v;
    Vec3 area;  // outward area vector (x2 the area)
    Vec3 unit;  // area.normalized()
  };
  // constraintOf's scratch:
  //  - a node's neighbours, their local numbers (-1 elsewhere; also discAround's), a table
  //    over pairs of them;
  //  - the faces by pair (consFaces), per live star tet its tet, then its nodes' local numbers
  //    (n: -1) (consLocal);
  //  - the boundary faces (faces) and, for Fan, their corners (fan);
  //  - the kept boundary faces of the nodes looked at (bfPool, see bfStart).
  struct ConsScratch {
    std::vector<std::int32_t> nbrs, localId, pairCount, consLocal;
    std::vector<FaceUse> consFaces;
    std::vector<BFace> faces;
    std::vector<std::array<Vec3, 3>> fan;
    std::vector<std::array<std::int32_t, 2>> bfPool;
  };
  ConsScratch cons;
  cons.localId.assign(N, -1);
  std::vector<std::int32_t>& localId = cons.localId;
  // The move loop changes positions only, never which tets are live or their nodes, so the
  // boundary faces around a node, as (tet, face) in the order first seen, are the same at
  // every call there: kept per node (bfStart[n] >= 0: bfLen[n] entries of bfPool from
  // there). Empty bfStart: no keeping (the mesh may change between calls).
  std::vector<std::int32_t> bfStart, bfLen;
  auto constraintOf = [&](int n) {
    ConsScratch& S = cons;
    Constraint c;
    S.faces.clear();
    const bool keep = !bfStart.empty();
    if (!keep || bfStart[n] < 0) {
      if (!keep) S.bfPool.clear();
      S.consFaces.clear();
      // Faces by the pair of their nodes other than n (local numbers over n's neighbours).
      S.nbrs.clear();
      const std::int32_t *sBegin = starB(n), *sEnd = starE(n);
      const size_t recs = 5 * static_cast<size_t>(sEnd - sBegin);
      if (S.consLocal.size() < recs) S.consLocal.resize(recs);
      std::int32_t* cl = S.consLocal.data();
      for (const std::int32_t* s = sBegin; s < sEnd; ++s)
        if (!(*dead)[*s]) {
          *cl++ = *s;
          for (int k = 0; k < 4; ++k) {
            const int w = mesh.T(*s, k);
            if (w == n) {
              *cl++ = -1;
              continue;
            }
            if (S.localId[w] < 0) {
              S.localId[w] = static_cast<std::int32_t>(S.nbrs.size());
              S.nbrs.push_back(w);
            }
            *cl++ = S.localId[w];
          }
        }
      const std::int32_t* clEnd = cl;
      const size_t L = S.nbrs.size();
      if (S.pairCount.size() < L * L) S.pairCount.assign(L * L, -1);  // index into S.consFaces
      for (const std::int32_t* rec = S.consLocal.data(); rec < clEnd; rec += 5) {
        const std::int32_t* lt = rec + 1;
        int ln = 0;
        while (lt[ln] >= 0) ++ln;
        // The positions other than n's, p[0] < p[1] < p[2]; face f = p[r] (in f order) is the
        // pair of the other two.
        int p[3], np = 0;
        for (int k = 0; k < 4; ++k)
          if (k != ln) p[np++] = k;
        for (int r = 0; r < 3; ++r) {
          const std::int32_t x = lt[p[r == 0 ? 1 : 0]], y = lt[p[r == 2 ? 1 : 2]];
          const std::int32_t key = std::min(x, y) * static_cast<std::int32_t>(L) + std::max(x, y);
          std::int32_t& at = S.pairCount[key];
          if (at >= 0) {
            ++S.consFaces[at].count;
          } else {
            at = static_cast<std::int32_t>(S.consFaces.size());
            S.consFaces.push_back({rec[0], p[r], 1, key});
          }
        }
      }
      for (int w : S.nbrs) S.localId[w] = -1;
      if (keep) bfStart[n] = static_cast<std::int32_t>(S.bfPool.size());
      for (const FaceUse& fu : S.consFaces) {
        S.pairCount[fu.key] = -1;
        if (fu.count != 1) continue;
        S.bfPool.push_back({fu.t, fu.f});
      }
      if (keep) bfLen[n] = static_cast<std::int32_t>(S.bfPool.size()) - bfStart[n];
    }
    Vec3 sum = Vec3::Zero();
    bool boundary = false, allCut = true;
    const std::int32_t bfFrom = keep ? bfStart[n] : 0;
    const auto& bfPool = S.bfPool;
    const std::int32_t bfTo = keep ? bfStart[n] + bfLen[n] : static_cast<std::int32_t>(bfPool.size());
    for (std::int32_t bi = bfFrom; bi < bfTo; ++bi) {
      const int t = bfPool[bi][0], f = bfPool[bi][1];
      const int i0 = mesh.T(t, kFace[f][0]), i1 = mesh.T(t, kFace[f][1]), i2 = mesh.T(t, kFace[f][2]);
      std::int32_t o[2], m = 0;
      for (int v : {i0, i1, i2})
        if (v != n) o[m++] = v;
      if (o[0] > o[1]) std::swap(o[0], o[1]);
      const Vec3 area = (pos(i1) - pos(i0)).cross(pos(i2) - pos(i0));
      S.faces.push_back({o[0], o[1], area, area.normalized()});
      boundary = true;
      sum += area;
      allCut = allCut && onCut[o[0]] && onCut[o[1]];
    }
    const bool nodeOnCut = onCut[n] != 0;
    // A node on a ridge (the rim, where the cut meets the boundary, or a crease of the
    // boundary) slides along it: exactly two of its boundary edges are ridge edges (between a
    // cut and a non-cut face, or faces more than ridge_deg apart).
    auto ridgeOf = [&]() {
      if (!curved || !(options.ridge_deg > 0)) return false;
      int found = 0;
      for (size_t i = 0; i < S.faces.size(); ++i) {
        for (int w : {S.faces[i].u, S.faces[i].v})
          for (size_t j = i + 1; j < S.faces.size(); ++j) {
            if (S.faces[j].u != w && S.faces[j].v != w) continue;
            const bool cutI = onCut[S.faces[i].u] && onCut[S.faces[i].v] && nodeOnCut;
            const bool cutJ = onCut[S.faces[j].u] && onCut[S.faces[j].v] && nodeOnCut;
            // (On the cut only the rim counts: the node is put back onto the cut surface.)
            const bool edge = nodeOnCut ? cutI != cutJ
                                        : S.faces[i].unit.dot(S.faces[j].unit) < cosRidge;
            if (!edge) continue;
            if (found == 2) return false;
            c.ridge[found++] = pos(w);
          }
      }
      if (found != 2) return false;
      c.kind = Freedom::Ridge;
      c.normal = Vec3::Zero();
      return true;
    };
    if (nodeOnCut) {
      if (!options.move_cut_nodes) return c;
      if (boundary && !allCut) {  // rim node
        ridgeOf();
        return c;
      }
      if (plane) {
        c.kind = Freedom::Plane;
        c.normal = region.surface->planeNormal();
        return c;
      }
      if (!boundary || sum.norm() == 0) return c;
      c.normal = sum.normalized();
      // A curved cut surface: slide in the tangent plane, then back onto the surface (the
      // volume changes by second-order amounts), where the cut faces around are smooth.
      c.kind = Freedom::Surface;
      for (const auto& bf : S.faces)
        if (bf.unit.dot(c.normal) < cosCurved) c.kind = Freedom::Fixed;
      return c;
    }
    if (!boundary) {
      c.kind = Freedom::Free;
      return c;
    }
    if (!options.move_boundary_nodes || sum.norm() == 0) return c;
    c.normal = sum.normalized();
    c.kind = Freedom::Plane;
    for (const auto& bf : S.faces) {
      const double cosine = bf.unit.dot(c.normal);
      if (cosine < cosCurved) {
        c.kind = Freedom::Fixed;
        ridgeOf();
        return c;
      }
      if (cosine < cosFlat) c.kind = Freedom::Fan;
    }
    if (c.kind == Freedom::Fan) {  // the node stays on its boundary faces as they are now
      S.fan.clear();
      for (const auto& bf : S.faces) S.fan.push_back({pos(n), pos(bf.u), pos(bf.v)});
    }
    return c;
  };
  // A node off the cut stays strictly on its side of the surface.
  auto sideKept = [&](int n, const Vec3& x, const Vec3& y) {
    if (onCut[n] || region.surface == nullptr) return true;
    if (plane) {
      const Vec3 pn = region.surface->planeNormal(), pp = region.surface->planePoint();
      const double a = pn.dot(x - pp), b = pn.dot(y - pp);
      return a * b > 0 && std::abs(b) > region.eps;
    }
    CutSurface::Hit hit;
    return !region.surface->intersectSegment(x, y, region.eps, &hit) &&
           !region.surface->within(y, region.eps);
  };

  // Peeling: a sliver (q* below peel_quality) with a face on the boundary is removed when
  // the mesh stays manifold: the boundary faces around each of its nodes still form one
  // closed loop (a disc), or the node had no other tet (it goes with the sliver). Its volume (tiny: it is flat) is lost.
  std::vector<std::int32_t> link;  // scratch: link edges of a node, as pairs (discAround's local numbers)
  // The faces of t no other live tet has. Face f is shared when a live tet u != t around its
  // first node holds its other two (a live tet's nodes are distinct, so the two positions of u
  // equal to one of them are one each). Faces 1 to 3 start with t's node 0 and face 0 with its
  // node 1: one pass over each of those two stars, with per tet the mask of t's nodes it holds.
  auto boundaryFaceCount = [&](int t) {
    const int t0 = mesh.T(t, 0), t1 = mesh.T(t, 1), t2 = mesh.T(t, 2), t3 = mesh.T(t, 3);
    auto holds = [&](int u) {
      const int w0 = mesh.T(u, 0), w1 = mesh.T(u, 1), w2 = mesh.T(u, 2), w3 = mesh.T(u, 3);
      return unsigned(w0 == t1 || w1 == t1 || w2 == t1 || w3 == t1) << 1 |
             unsigned(w0 == t2 || w1 == t2 || w2 == t2 || w3 == t2) << 2 |
             unsigned(w0 == t3 || w1 == t3 || w2 == t3 || w3 == t3) << 3;
    };
    unsigned shared = 0;  // bit f: face f is shared
    for (const std::int32_t *s = starB(t0), *sEnd = starE(t0); s < sEnd && shared != 0xEu; ++s) {
      const int u = (*s);
      if (u == t || (*dead)[u]) continue;
      const unsigned h = holds(u);  // (bit 0 unused: u holds t's node 0)
      for (int f = 1; f < 4; ++f) {
        const unsigned S = 0xEu & ~(1u << f);
        if ((h & S) == S) shared |= 1u << f;
      }
    }
    for (const std::int32_t *s = starB(t1), *sEnd = starE(t1); s < sEnd; ++s) {
      const int u = (*s);
      if (u == t || (*dead)[u]) continue;
      if ((holds(u) & 0xCu) == 0xCu) {
        shared |= 1u;
        break;
      }
    }
    constexpr int kUnshared[16] = {4, 3, 3, 2, 3, 2, 2, 1, 3, 2, 2, 1, 2, 1, 1, 0};  // 4 - popcount
    const int count = kUnshared[shared];
#ifdef HYSIM_CHECK_EXACT
    int ref = 0;
    for (int f = 0; f < 4; ++f) {
      const int a = mesh.T(t, kFace[f][0]), b = mesh.T(t, kFace[f][1]), c = mesh.T(t, kFace[f][2]);
      bool sh = false;
      for (const std::int32_t *s = starB(a), *sEnd = starE(a); s < sEnd && !sh; ++s) {
        const int u = (*s);
        if (u == t || (*dead)[u]) continue;
        int hits = 0;
        for (int k = 0; k < 4; ++k) hits += mesh.T(u, k) == b || mesh.T(u, k) == c;
        sh = hits == 2;
      }
      ref += sh ? 0 : 1;
    }
    if (ref != count) std::abort();
#endif
    return count;
  };
  // The tets around v (live ones from the node->tet lists, plus `extra`).
  auto liveStar = [&](int v, std::vector<std::int32_t>& out, const std::vector<std::int32_t>* extra) {
    out.clear();
    for (const std::int32_t *s = starB(v), *sEnd = starE(v); s < sEnd; ++s)
      if (!(*dead)[(*s)]) out.push_back((*s));
    if (extra)
      for (int t : *extra)
        if (!(*dead)[t]) out.push_back(t);
  };
  // Is the neighbourhood of v (tets `around`) manifold: every face used by at most two tets,
  // and the boundary faces around v one closed loop (or none: interior)? No tets: the node
  // goes away (compacted), which is fine.
  // linkOnly: only fill `link` (the boundary edges around v, up to the first face used by
  // more than two tets) and return whether the faces are; the loop check is skipped.
  // (Scratch that only grows, so that it is written without zeroing: tetLocal, faceKey,
  // linkInc and discNbrs, v's neighbours in local number order.)
  std::vector<std::int32_t> linkDeg, linkInc, tetLocal, faceKey, discNbrs;
  std::vector<std::uint16_t> faceUses;
  auto discAround = [&](int v, const std::vector<std::int32_t>& around, bool linkOnly = false) {
    link.clear();
    if (around.empty()) return true;
    // Every tet of `around` has v; a face (v, a, b) is used by the tets with both a and b:
    // count the pairs of each tet's other three nodes in a table over v's neighbours.
    // Each tet's three other nodes as local numbers (in the tet's order), read from the mesh
    // once.
    const size_t n = around.size();
    if (tetLocal.size() < 3 * n + 1) tetLocal.resize(3 * n + 1);  // (+1: a tet without v writes a fourth number)
    if (discNbrs.size() < 4 * n) discNbrs.resize(4 * n);
    std::int32_t* nb = discNbrs.data();
    std::int32_t L = 0;     // neighbours numbered so far
    bool threeEach = true;  // (every tet has v once: its three other nodes)
    for (size_t i = 0; i < n; ++i) {
      const int t = around[i];
      std::int32_t* o = &tetLocal[3 * i];
      int m = 0;
      for (int k = 0; k < 4; ++k) {
        const int w = mesh.T(t, k);
        if (w == v) continue;
        std::int32_t& id = localId[w];
        if (id < 0) {
          id = L;
          nb[L++] = w;
        }
        o[m++] = id;
      }
      threeEach = threeEach && m == 3;
    }
    if (!threeEach) {  // not a star of v (never so here)
      for (std::int32_t i = 0; i < L; ++i) localId[nb[i]] = -1;
      return false;
    }
    // The faces at v of each tet, in the order of the face opposite each other node (faces
    // f != v's in order f = 0..3: without o[0], without o[1], without o[2]): the pairs
    // (o1, o2), (o0, o2), (o0, o1), each as its table index min * L + max.
    faceUses.assign(static_cast<size_t>(L) * L, 0);
    if (faceKey.size() < 3 * n) faceKey.resize(3 * n);
    for (size_t i = 0; i < n; ++i) {
      const std::int32_t* o = &tetLocal[3 * i];
      std::int32_t* key = &faceKey[3 * i];
      const std::int32_t a = o[0], b = o[1], c = o[2];
      key[0] = std::min(b, c) * L + std::max(b, c);
      key[1] = std::min(a, c) * L + std::max(a, c);
      key[2] = std::min(a, b) * L + std::max(a, b);
      ++faceUses[key[0]];
      ++faceUses[key[1]];
      ++faceUses[key[2]];
    }
    // The boundary faces' edges, up to the first face used by more than two tets.
    bool manifold = true;
    for (size_t i = 0; i < n && manifold; ++i) {
      const std::int32_t* o = &tetLocal[3 * i];
      const std::int32_t* key = &faceKey[3 * i];
      for (int f = 0; f < 3; ++f) {
        const std::uint16_t uses = faceUses[key[f]];
        if (uses > 2) {
          manifold = false;
          break;
        }
        if (uses == 1) {
          const std::int32_t p = f == 0 ? o[1] : o[0], q = f == 2 ? o[1] : o[2];
          link.push_back(p);
          link.push_back(q);
        }
      }
    }
    for (std::int32_t i = 0; i < L; ++i) localId[nb[i]] = -1;
    if (!manifold || link.empty() || linkOnly) return manifold;  // (link.empty(): an interior node)
    // One closed loop: every link vertex has degree 2, and walking from one edge visits all.
    // Each link vertex's (first two) edges in a table over v's neighbours: with all degrees 2
    // the walk from edge 0 leaves each vertex by its other edge, and it visits all edges iff
    // they form one loop.
    const size_t edges = link.size() / 2;
    linkDeg.assign(L, 0);
    if (linkInc.size() < 2 * static_cast<size_t>(L)) linkInc.resize(2 * static_cast<size_t>(L));
    for (size_t i = 0; i < link.size(); ++i) {
      const std::int32_t id = link[i];
      if (linkDeg[id] < 2) linkInc[2 * id + linkDeg[id]] = static_cast<std::int32_t>(i / 2);
      ++linkDeg[id];
    }
    bool loop = true;
    for (size_t i = 0; i < link.size() && loop; ++i) loop = linkDeg[link[i]] == 2;
    size_t visited = 1;
    std::int32_t start = link[0], at = link[1];
    std::int32_t prevEdge = 0;
    while (loop && at != start && visited <= edges) {
      const std::int32_t next = linkInc[2 * at] != prevEdge ? linkInc[2 * at] : linkInc[2 * at + 1];
      at = link[2 * next] == at ? link[2 * next + 1] : link[2 * next];
      prevEdge = next;
      ++visited;
    }
    return loop && at == start && visited == edges;
  };
  std::vector<std::int32_t> around;
  std::vector<std::int32_t> lateSnapped;  // nodes snapNear moved onto the cut
  // Curved cuts: the repair region also takes the poor tets (q* below flip_quality) within
  // repair_rings edge steps of what the cut touched, left there by earlier cuts (a shaving
  // pass sweeps over the surfaces of earlier ones): their nodes join the seeds.
  std::vector<std::int32_t> seeds(region.seeds.begin(), region.seeds.end());
  if (curved && options.repair_rings > 0 && options.flip_quality > 0) {
    std::vector<std::uint8_t> reached(N, 0);
    std::vector<std::int32_t> frontier, next;
    for (int n : region.seeds)
      if (n >= 0 && n < N && !reached[n]) {
        reached[n] = 1;
        frontier.push_back(n);
      }
    for (int r = 0; r < options.repair_rings && !frontier.empty(); ++r) {
      next.clear();
      for (int n : frontier)
        for (const std::int32_t *s = starB(n), *sEnd = starE(n); s < sEnd; ++s) {
          if ((*dead)[*s]) continue;
          const bool poor = tetQ(*s) < options.flip_quality;
          for (int k = 0; k < 4; ++k) {
            const int v = mesh.T(*s, k);
            if (reached[v]) continue;
            reached[v] = 1;
            next.push_back(v);
            if (poor) seeds.push_back(v);
          }
          if (poor)
            for (int k = 0; k < 4; ++k) seeds.push_back(mesh.T(*s, k));
        }
      frontier.swap(next);
    }
    // The added seeds sorted, without repeats (as sort + unique).
    const size_t base = region.seeds.size();
    if (seeds.size() > base) {
      IndexBits added(N);
      for (size_t i = base; i < seeds.size(); ++i) added.mark(seeds[i]);
      seeds.resize(base);
      added.drainInto(seeds);
    }
  }
  // The live tets around the seeds, each once, in index order (the live tets with a seed
  // node). Kept (regionKept) with topoClock's value when found: while no tet has taken other
  // nodes since (topoClock counts the writes of tets' nodes) and none came alive (only a
  // written slot or an undone removal does, and no one asks between a removal and its undo),
  // the list is the kept one without the tets that died since.
  IndexBits tetBits(M);
  std::vector<std::int32_t> regionKept;
  std::uint64_t topoClock = 0, regionClock = ~std::uint64_t{0};
  auto regionTets = [&](std::vector<std::int32_t>& out) {
    out.clear();
    if (regionClock == topoClock) {
      size_t kept = 0;
      for (const std::int32_t t : regionKept)
        if (!(*dead)[t]) regionKept[kept++] = t;
      regionKept.resize(kept);
      out.assign(regionKept.begin(), regionKept.end());
#ifdef HYSIM_CHECK_EXACT
      std::vector<std::int32_t> ref;
      for (int n : seeds)
        for (const std::int32_t *s = starB(n), *sEnd = starE(n); s < sEnd; ++s)
          if (!(*dead)[*s]) tetBits.mark(*s);
      tetBits.drainInto(ref);
      if (ref != out) std::abort();
#endif
      return;
    }
    for (int n : seeds)
      for (const std::int32_t *s = starB(n), *sEnd = starE(n); s < sEnd; ++s)
        if (!(*dead)[*s]) tetBits.mark(*s);
    tetBits.drainInto(out);
    regionKept.assign(out.begin(), out.end());
    regionClock = topoClock;
  };
  std::vector<std::int32_t> peelStamp, failedAt;
  int peelCount = 0;
  auto peel = [&]() {
    if (!(options.peel_quality > 0)) return;
    std::vector<std::int32_t> candidates;
    regionTets(candidates);
    candidates.erase(std::remove_if(candidates.begin(), candidates.end(),
                                    [&](int t) { return !(tetQ(t) < options.peel_quality); }),
                     candidates.end());
    // A candidate's tests (a boundary face, the discs around its nodes) look only at the
    // live tets around its nodes: one that failed them is not tested again until a tet with
    // one of its nodes was peeled (peelStamp, per node: the count of peels when it last lost
    // a tet; failedAt, per candidate: that count when it failed). The budget is asked anew.
    if (peelStamp.empty()) peelStamp.assign(N, -1);
    failedAt.assign(candidates.size(), -1);
    for (bool again = true; again;) {
      again = false;
      for (size_t i = 0; i < candidates.size(); ++i) {
        const int t = candidates[i];
        if ((*dead)[t]) continue;
        if (failedAt[i] >= 0) {
          int last = -1;
          for (int k = 0; k < 4; ++k) last = std::max(last, peelStamp[mesh.T(t, k)]);
          if (last <= failedAt[i]) continue;
          failedAt[i] = -1;
        }
        if (boundaryFaceCount(t) == 0) {
          failedAt[i] = peelCount;
          continue;
        }
        if (!budget.fits(-tetVolumeHere(mesh, t))) continue;
        kill(t);
        bool ok = true;
        for (int k = 0; k < 4 && ok; ++k) {
          liveStar(mesh.T(t, k), around, nullptr);
          ok = discAround(mesh.T(t, k), around);
        }
        if (!ok) {
          (*dead)[t] = 0;
          failedAt[i] = peelCount;
          continue;
        }
        ++peelCount;
        for (int k = 0; k < 4; ++k) peelStamp[mesh.T(t, k)] = peelCount;
        again = true;
        budget.spend(-tetVolumeHere(mesh, t));
        if (counts) {
          ++counts->peeled;
          counts->peeled_volume += tetVolumeHere(mesh, t);
        }
      }
    }
  };
  peel();

  // Flips: a poor tet (q* below flip_quality) with all its nodes held in place is repaired by
  // retriangulating it with its neighbours: 2-3 (the tet and its neighbour across a face
  // become three tets around the edge between their far nodes) and 3-2 (the three tets
  // around an interior edge become two across the triangle of their other nodes). Only
  // interior faces and edges change, within one material: the boundary, the cut and the
  // volume stay exactly. Kept when the worst q* of the tets involved rises; the best flip
  // of a tet is taken. A 2-3 flip reuses the slot of a removed tet (none free: no 2-3).
  std::vector<std::int32_t> freeSlots;
  // A candidate that found no flip in a round is not tried again in the next round of the same
  // call while nothing it reads changed: it reads the stars of its nodes, the tets in them (and
  // the stars of their nodes, for the existence checks) and how many free slots there are (as
  // min(count, 2): one for a 2-3, up to two for an edge removal). Each flip's rebuilt stars
  // mark (flipMark, with the flip's number) their nodes and the nodes of the tets around them;
  // a tet or star changed anywhere the candidate reads marks one of its nodes.
  struct FlipFailed {
    std::int32_t t, clock, avail;
  };
  std::vector<FlipFailed> failedPrev, failedNow;
  std::vector<std::int32_t> flipMark, flipRebuilt, flipChanged, flipSeeds;
  std::vector<std::uint8_t> flipNodeBit;  // per node: bit k when it is node k of the tet tried (else 0)
  std::int32_t flipClock = 0;
  auto flips = [&]() {
    if (!curved || !(options.flip_quality > 0)) return;
    freeSlots.assign(killed.begin(), killed.end());
    std::sort(freeSlots.begin(), freeSlots.end());
    freeSlots.erase(std::unique(freeSlots.begin(), freeSlots.end()), freeSlots.end());
    // The dead tets in freeSlots (the slots free for reuse), counted when first needed after
    // each change.
    // Only min(count, 2) is read (the checks of failed candidates; an edge removal takes at most
    // two): the count stops at 2.
    int availNow = -1;
    auto availSlots = [&]() {
      if (availNow < 0) {
        availNow = 0;
        for (size_t k = 0; k < freeSlots.size() && availNow < 2; ++k) availNow += (*dead)[freeSlots[k]] ? 1 : 0;
      }
      return availNow;
    };
    failedPrev.clear();
    failedNow.clear();
    std::vector<std::int32_t> cands, candsMerged;
    // The live tets around t's nodes 0, 1 and 2 (star order; t among them), each with the mask
    // c of t's nodes it contains (bit k: t's node k is one of its nodes): the face and edge
    // searches below read them instead of scanning the stars again. The scans counted the
    // positions l of the tet whose node is one of t's nodes in S (hitsOf below, with m holding
    // per position l, 4 bits each, the mask of t's nodes equal to node l). A live tet's four
    // nodes are distinct and so are t's: each nibble of m has at most one bit and different
    // nibbles have different bits, so that count is popcount(c & S) with c the OR of the
    // nibbles; "count == |S|" is then (c & S) == S (checked under HYSIM_CHECK_EXACT).
    struct NearTet {
      std::int32_t s;
      std::uint32_t c;
#ifdef HYSIM_CHECK_EXACT
      std::uint32_t m;
#endif
    };
    std::vector<NearTet> nearTets;
#ifdef HYSIM_CHECK_EXACT
    auto hitsOf = [](unsigned m, unsigned S) {
      return int((m & S) != 0) + int(((m >> 4) & S) != 0) + int(((m >> 8) & S) != 0) + int(((m >> 12) & S) != 0);
    };
    auto checkHits = [&](const NearTet& nt, unsigned S, int need) {
      if ((hitsOf(nt.m, S) == need) != ((nt.c & S) == S)) std::abort();
    };
#endif
    auto vol6 = [&](int a, int b, int c, int d) {
      const Vec3 p0 = pos(a);
      return (pos(b) - p0).dot((pos(c) - p0).cross(pos(d) - p0));
    };
    auto q4 = [&](int a, int b, int c, int d) {
      return radiusRatioOriented(pos(a), pos(b), pos(c), pos(d));  // -1 unless vol6(a, b, c, d) > 0
    };
    auto setTet = [&](int t, int a, int b, int c, int d) {
      ++topoClock;
      flipChanged.push_back(t);
      const int v[4] = {a, b, c, d};
      for (int k = 0; k < 4; ++k) {
        touch(mesh.T(t, k));
        mesh.T(t, k) = v[k];
        touch(v[k]);
        gained.emplace_back(v[k], t);
      }
    };
    flipChanged.clear();
    for (int round = 0; round < 3; ++round) {
      if (round == 0) {
        regionTets(cands);
      } else {
        // The region's tets now (every star rebuilt after the last flip): a tet no flip
        // changed kept its nodes, its place in the region (a seed among its nodes) and its q*;
        // the others were changed by setTet. So: the last round's candidates and the changed
        // tets, live, with a seed among their nodes.
        if (flipSeeds.empty()) {
          flipSeeds.assign(seeds.begin(), seeds.end());
          std::sort(flipSeeds.begin(), flipSeeds.end());
        }
        // (cands is sorted and without repeats: the changed tets sorted and merged in, as a
        // sort + unique of the whole.)
#ifdef HYSIM_CHECK_EXACT
        std::vector<std::int32_t> ref(cands);
        ref.insert(ref.end(), flipChanged.begin(), flipChanged.end());
        std::sort(ref.begin(), ref.end());
        ref.erase(std::unique(ref.begin(), ref.end()), ref.end());
        if (std::adjacent_find(cands.begin(), cands.end(), std::greater_equal<std::int32_t>()) != cands.end())
          std::abort();
#endif
        const size_t mid = cands.size();
        cands.insert(cands.end(), flipChanged.begin(), flipChanged.end());
        std::sort(cands.begin() + static_cast<std::ptrdiff_t>(mid), cands.end());
        mergeSortedRuns(cands, mid, candsMerged);
#ifdef HYSIM_CHECK_EXACT
        if (ref != cands) std::abort();
#endif
        cands.erase(std::remove_if(cands.begin(), cands.end(),
                                   [&](int t) {
                                     if ((*dead)[t]) return true;
                                     bool in = false;
                                     for (int k = 0; k < 4 && !in; ++k)
                                       in = std::binary_search(flipSeeds.begin(), flipSeeds.end(), mesh.T(t, k));
                                     return !in;
                                   }),
                    cands.end());
        flipChanged.clear();
      }
      cands.erase(std::remove_if(cands.begin(), cands.end(), [&](int t) { return !(tetQ(t) < options.flip_quality); }),
                  cands.end());
      int done = 0;
      size_t fp = 0;
      for (int t : cands) {
        if ((*dead)[t]) continue;
        const double qt = tetQ(t);
        if (!(qt < options.flip_quality)) continue;
        while (fp < failedPrev.size() && failedPrev[fp].t < t) ++fp;
        if (fp < failedPrev.size() && failedPrev[fp].t == t) {
          const FlipFailed& prev = failedPrev[fp];
          bool same = std::min(availSlots(), 2) == prev.avail;
          for (int k = 0; k < 4 && same && !flipMark.empty(); ++k) same = flipMark[mesh.T(t, k)] <= prev.clock;
          if (same) {
            failedNow.push_back(prev);
            continue;
          }
        }
        // Best flip: kind 0 = 2-3 across face f (neighbour u), kind 1 = 3-2 about edge (i, j).
        double best = qt;
        int bestKind = -1, bestF = -1, bestU = -1, bestI = -1, bestJ = -1;
        std::int32_t ring[3] = {-1, -1, -1}, ringTets[3] = {-1, -1, -1};
        // Nothing changes below until the best flip is applied.
        int nearOff[4];
        nearTets.clear();
        {
          const int t0 = mesh.T(t, 0), t1 = mesh.T(t, 1), t2 = mesh.T(t, 2), t3 = mesh.T(t, 3);
          // A tet's mask: the OR of its nodes' bits (t's nodes carry bits 0 to 3 while it is
          // tried; every other node 0).
          if (flipNodeBit.empty()) flipNodeBit.assign(N, 0);
          std::uint8_t* const nodeBit = flipNodeBit.data();
          nodeBit[t0] = 1;
          nodeBit[t1] = 2;
          nodeBit[t2] = 4;
          nodeBit[t3] = 8;
          for (int i = 0; i < 3; ++i) {
            nearOff[i] = static_cast<int>(nearTets.size());
            for (const std::int32_t *s = starB(mesh.T(t, i)), *sEnd = starE(mesh.T(t, i)); s < sEnd; ++s) {
              if ((*dead)[*s]) continue;
              const int w0 = mesh.T(*s, 0), w1 = mesh.T(*s, 1), w2 = mesh.T(*s, 2), w3 = mesh.T(*s, 3);
              const unsigned c = unsigned(nodeBit[w0] | nodeBit[w1] | nodeBit[w2] | nodeBit[w3]);
#ifdef HYSIM_CHECK_EXACT
              unsigned m = 0;
              const int wl[4] = {w0, w1, w2, w3};
              for (int l = 0; l < 4; ++l)
                m |= (unsigned(wl[l] == t0) | unsigned(wl[l] == t1) << 1 | unsigned(wl[l] == t2) << 2 |
                      unsigned(wl[l] == t3) << 3)
                     << (4 * l);
              if (c != ((m | m >> 4 | m >> 8 | m >> 12) & 0xFu)) std::abort();
              nearTets.push_back({*s, c, m});
#else
              nearTets.push_back({*s, c});
#endif
            }
          }
          nodeBit[t0] = nodeBit[t1] = nodeBit[t2] = nodeBit[t3] = 0;
          nearOff[3] = static_cast<int>(nearTets.size());
        }
        // The tets around each edge (i, j) of t, i < j (from the list of node i, in its order;
        // bit j of a tet's mask around node i): their count and the first six, all that the
        // 3-2 flip (three) and the edge removal (four to six) read. And the neighbour across
        // each face f: the first other tet around the face's first node (node 1 for face 0,
        // node 0 for the others) holding the face's three nodes.
        constexpr int kEdgeOf[4][4] = {{-1, 0, 1, 2}, {0, -1, 3, 4}, {1, 3, -1, 5}, {2, 4, 5, -1}};
        std::int32_t edgeTetsOf[6][6];
        int edgeN[6] = {0, 0, 0, 0, 0, 0}, edgeSameMat[6] = {1, 1, 1, 1, 1, 1};
        int faceU[4] = {-1, -1, -1, -1};
        {
          const int matT = mesh.material(t);
          for (int i = 0; i < 3; ++i)
            for (int k = nearOff[i]; k < nearOff[i + 1]; ++k) {
              const unsigned c = nearTets[k].c;
              const std::int32_t s = nearTets[k].s;
#ifdef HYSIM_CHECK_EXACT
              for (int j = i + 1; j < 4; ++j) checkHits(nearTets[k], (1u << i) | (1u << j), 2);
              for (int f = 0; f < 4; ++f)
                if (kFace[f][0] == i) checkHits(nearTets[k], 0xFu & ~(1u << f), 3);
#endif
              if ((c >> (i + 1)) == 0) continue;  // (no other node of t after node i)
              for (int j = i + 1; j < 4; ++j)
                if (c & (1u << j)) {
                  const int e = kEdgeOf[i][j];
                  if (edgeN[e] < 6) edgeTetsOf[e][edgeN[e]] = s;
                  ++edgeN[e];
                  edgeSameMat[e] = edgeSameMat[e] && mesh.material(s) == matT;
                }
              if (s == t || i > 1) continue;
              if (i == 1) {
                if (faceU[0] < 0 && (c & 0xEu) == 0xEu) faceU[0] = s;
              } else {
                for (int f = 1; f < 4; ++f) {
                  const unsigned S = 0xFu & ~(1u << f);
                  if (faceU[f] < 0 && (c & S) == S) faceU[f] = s;
                }
              }
            }
        }
        // 2-3.
        const bool slot = [&]() {
          while (!freeSlots.empty() && !(*dead)[freeSlots.back()]) freeSlots.pop_back();
          return !freeSlots.empty();
        }();
        for (int f = 0; f < 4 && slot; ++f) {
          const int a = mesh.T(t, kFace[f][0]), b = mesh.T(t, kFace[f][1]), c = mesh.T(t, kFace[f][2]),
                    d = mesh.T(t, f);
          const int u = faceU[f];
          if (u < 0 || mesh.material(u) != mesh.material(t)) continue;
          int e = -1;
          for (int k = 0; k < 4; ++k)
            if (mesh.T(u, k) != a && mesh.T(u, k) != b && mesh.T(u, k) != c) e = mesh.T(u, k);
          const double old = std::min(qt, tetQ(u));
          // The new edge (d, e) is no shorter than the shortest edge of the two tets.
          double shortest = std::numeric_limits<double>::infinity();
          for (int tt : {t, u})
            for (int i = 0; i < 4; ++i)
              for (int j = i + 1; j < 4; ++j)
                shortest = std::min(shortest, (pos(mesh.T(tt, i)) - pos(mesh.T(tt, j))).squaredNorm());
          if ((pos(d) - pos(e)).squaredNorm() < shortest) continue;
          // (d, e) must not be an edge already (where the mesh folds, it could be).
          bool exists = false;
          for (const std::int32_t *s = starB(d), *sEnd = starE(d); s < sEnd && !exists; ++s)
            if (!(*dead)[*s])
              for (int k = 0; k < 4; ++k) exists = exists || mesh.T(*s, k) == e;
          if (exists) continue;
          // (d, a, b, c) with kFace's order is positive when the face is (a, b, c) seen from
          // outside, i.e. vol(a, b, c, d) < 0 in this convention: use the tet's own order.
          // New tets: t with one face node replaced by e.
          int v[4];
          for (int k = 0; k < 4; ++k) v[k] = mesh.T(t, k);
          double qn = 1.0;
          for (int r = 0; r < 3 && qn > best; ++r) {
            const int fk = kFace[f][r];
            int w[4] = {v[0], v[1], v[2], v[3]};
            w[fk] = e;
            qn = std::min(qn, q4(w[0], w[1], w[2], w[3]));
          }
          if (qn > best && qn > old) {
            best = qn;
            bestKind = 0;
            bestF = f;
            bestU = u;
            bestI = e;
          }
        }
        // 3-2.
        for (int i = 0, ei = 0; i < 4; ++i)
          for (int j = i + 1; j < 4; ++j, ++ei) {
            const int a = mesh.T(t, i), b = mesh.T(t, j);
            const std::int32_t* edgeTets = edgeTetsOf[ei];
            if (edgeN[ei] != 3) continue;
            if (!edgeSameMat[ei]) continue;
            // The other two nodes of each tet; a closed ring uses each of three nodes twice.
            std::int32_t others[6], m = 0;
            for (int r = 0; r < 3; ++r)
              for (int k = 0, u = edgeTets[r]; k < 4; ++k)
                if (mesh.T(u, k) != a && mesh.T(u, k) != b) others[m++] = mesh.T(u, k);
            if (m != 6) continue;
            std::int32_t p[3], np = 0;
            bool closed = true;
            for (int k = 0; k < 6 && closed; ++k) {
              int uses = 0;
              for (int l = 0; l < 6; ++l) uses += others[l] == others[k];
              closed = uses == 2;
              bool seen = false;
              for (int l = 0; l < np; ++l) seen = seen || p[l] == others[k];
              if (!seen && np < 3) p[np++] = others[k];
            }
            if (!closed || np != 3) continue;
            // The triangle (p0, p1, p2) must not be a face already (where the mesh folds).
            bool exists = false;
            for (const std::int32_t *s = starB(p[0]), *sEnd = starE(p[0]); s < sEnd && !exists; ++s) {
              if ((*dead)[*s]) continue;
              int hits = 0;
              for (int k = 0; k < 4; ++k) hits += mesh.T(*s, k) == p[1] || mesh.T(*s, k) == p[2];
              exists = hits == 2;
            }
            if (exists) continue;
            double old = 1.0;
            for (int r = 0; r < 3; ++r) old = std::min(old, tetQ(edgeTets[r]));
            const double va = vol6(p[0], p[1], p[2], a);
            const int top = va > 0 ? a : b, bottom = va > 0 ? b : a;
            const double qn = std::min(q4(p[0], p[1], p[2], top), q4(p[0], p[2], p[1], bottom));
            if (qn > best && qn > old) {
              best = qn;
              bestKind = 1;
              bestI = top;
              bestJ = bottom;
              for (int k = 0; k < 3; ++k) {
                ring[k] = p[k];
                ringTets[k] = edgeTets[k];
              }
            }
          }
        // Edge removal: the n (4 to 6) tets around an interior edge (a, b), all of t's
        // material, become 2(n - 2): the ring of their other nodes is triangulated as a fan
        // from one ring node and each triangle joined to a and to b. Valid when a and b lie on
        // opposite sides of every triangle (all new tets positive); n > 4 takes free slots.
        std::int32_t erRing[6], erTets[6];
        int erN = 0, erApex = -1;
        if (options.edge_removal) {
          int avail = -1;  // the free slots, counted when first needed
          for (int i = 0, ei = 0; i < 4; ++i)
            for (int j = i + 1; j < 4; ++j, ++ei) {
              const int a = mesh.T(t, i), b = mesh.T(t, j);
              const std::int32_t* edgeTets = edgeTetsOf[ei];
              const bool sameMat = edgeSameMat[ei] != 0;
              const int n = edgeN[ei];
              if (n > 4 && n <= 6 && avail < 0) avail = availSlots();
              if (n < 4 || n > 6 || (n > 4 && n - 4 > avail) || !sameMat) continue;
              // The ring: each tet's other two nodes, chained into one cycle.
              std::int32_t pr[6][2], cyc[6], cycT[6];
              bool used[6] = {false, false, false, false, false, false};
              for (int e = 0; e < n; ++e) {
                int m = 0;
                for (int k = 0; k < 4; ++k)
                  if (mesh.T(edgeTets[e], k) != a && mesh.T(edgeTets[e], k) != b && m < 2) pr[e][m++] = mesh.T(edgeTets[e], k);
              }
              cyc[0] = pr[0][0];
              cyc[1] = pr[0][1];
              cycT[0] = edgeTets[0];
              used[0] = true;
              bool closed = true;
              for (int m = 2; m <= n && closed; ++m) {
                const int from = cyc[m - 1];
                int found = -1;
                for (int e = 0; e < n && found < 0; ++e)
                  if (!used[e] && (pr[e][0] == from || pr[e][1] == from)) found = e;
                if (found < 0) {
                  closed = false;
                  break;
                }
                used[found] = true;
                cycT[m - 1] = edgeTets[found];
                const int to = pr[found][0] == from ? pr[found][1] : pr[found][0];
                if (m < n) {
                  for (int l = 0; l < m; ++l) closed = closed && cyc[l] != to;
                  cyc[m] = to;
                } else {
                  closed = to == cyc[0];
                }
              }
              if (!closed) continue;
              double old = 1.0;
              for (int r = 0; r < n; ++r) old = std::min(old, tetQ(edgeTets[r]));
              for (int apex = 0; apex < n; ++apex) {
                double qn = 1.0;
                int sign = 0;
                for (int m = 1; m + 1 < n && qn > best; ++m) {
                  const int p0 = cyc[apex], p1 = cyc[(apex + m) % n], p2 = cyc[(apex + m + 1) % n];
                  const double va = vol6(p0, p1, p2, a), vb = vol6(p0, p1, p2, b);
                  const int sg = va > 0 ? 1 : -1;
                  if (!(va * vb < 0) || (sign != 0 && sg != sign)) {
                    qn = -1;
                    break;
                  }
                  sign = sg;
                  qn = std::min(qn, sg > 0 ? std::min(q4(p0, p1, p2, a), q4(p0, p2, p1, b))
                                           : std::min(q4(p0, p2, p1, a), q4(p0, p1, p2, b)));
                }
                if (!(qn > best && qn > old)) continue;
                // The fan's diagonals must not be edges already (where the mesh folds).
                bool exists = false;
                for (int m = 2; m + 1 < n && !exists; ++m) {
                  const int d0 = cyc[apex], d1 = cyc[(apex + m) % n];
                  for (const std::int32_t *s = starB(d0), *sEnd = starE(d0); s < sEnd && !exists; ++s)
                    if (!(*dead)[*s])
                      for (int k = 0; k < 4; ++k) exists = exists || mesh.T(*s, k) == d1;
                }
                if (exists) continue;
                best = qn;
                bestKind = 2;
                bestI = a;
                bestJ = b;
                erN = n;
                erApex = apex;
                for (int e = 0; e < n; ++e) {
                  erRing[e] = cyc[e];
                  erTets[e] = cycT[e];
                }
              }
            }
        }
        if (bestKind == 0) {
          int v[4];
          for (int k = 0; k < 4; ++k) v[k] = mesh.T(t, k);
          const int e = bestI, u = bestU;
          const int extra = freeSlots.back();
          freeSlots.pop_back();
          const int slots[3] = {t, u, extra};
          (*dead)[extra] = 0;
          mesh.material(extra) = mesh.material(t);
          for (int r = 0; r < 3; ++r) {
            int w[4] = {v[0], v[1], v[2], v[3]};
            w[kFace[bestF][r]] = e;
            setTet(slots[r], w[0], w[1], w[2], w[3]);
          }
          if (!(*dead)[u]) touch(mesh.T(u, 0));
          ++done;
          if (counts) ++counts->flips;
        } else if (bestKind == 1) {
          setTet(ringTets[0], ring[0], ring[1], ring[2], bestI);
          setTet(ringTets[1], ring[0], ring[2], ring[1], bestJ);
          kill(ringTets[2]);
          freeSlots.push_back(ringTets[2]);
          ++done;
          if (counts) ++counts->flips;
        } else if (bestKind == 2) {
          const int a = bestI, b = bestJ, n = erN;
          std::int32_t slots[8];
          for (int e = 0; e < n; ++e) slots[e] = erTets[e];
          for (int e = n; e < 2 * (n - 2); ++e) {
            while (!freeSlots.empty() && !(*dead)[freeSlots.back()]) freeSlots.pop_back();
            slots[e] = freeSlots.back();  // (there are: counted when the removal was chosen)
            freeSlots.pop_back();
            (*dead)[slots[e]] = 0;
            mesh.material(slots[e]) = mesh.material(t);
          }
          int next = 0;
          for (int m = 1; m + 1 < n; ++m) {
            const int p0 = erRing[erApex], p1 = erRing[(erApex + m) % n], p2 = erRing[(erApex + m + 1) % n];
            if (vol6(p0, p1, p2, a) > 0) {
              setTet(slots[next++], p0, p1, p2, a);
              setTet(slots[next++], p0, p2, p1, b);
            } else {
              setTet(slots[next++], p0, p2, p1, a);
              setTet(slots[next++], p0, p1, p2, b);
            }
          }
          touch(a);
          touch(b);
          ++done;
          if (counts) ++counts->flips;
        }
        if (bestKind < 0) {
          failedNow.push_back({t, flipClock, std::min(availSlots(), 2)});
          continue;
        }
        ++flipClock;
        availNow = -1;
        flipRebuilt.assign(touchedList.begin(), touchedList.end());
        buildStars();
        if (flipMark.empty()) flipMark.assign(N, -1);
        for (int y : flipRebuilt) {
          flipMark[y] = flipClock;
          for (const std::int32_t *s = starB(y), *sEnd = starE(y); s < sEnd; ++s)
            if (!(*dead)[*s])
              for (int k = 0; k < 4; ++k) flipMark[mesh.T(*s, k)] = flipClock;
        }
      }
      failedPrev.swap(failedNow);
      failedNow.clear();
      if (done == 0) break;
    }
  };

  // Edge collapse on the cut: an edge with an end on the cut that is short (below
  // collapse_fraction of its tet's mean edge) or belongs to a poor tet (q* below
  // quality_target) is collapsed into its end on the cut, which keeps its place (so the cut
  // stays where it is): the tets around the edge go, the other tets of the collapsed node
  // take the kept one. Kept only if no tet inverts, the worst q* there rises (short edges:
  // does not fall), the volume changes by at most collapse_volume_fraction of the star and
  // within the budget, no two tets coincide and the mesh stays manifold. The node->tet lists are stale for the two ends until the next batch, so
  // within a batch they take part in no other collapse.
  // Curved cuts, last (after flap peeling): only edges of tets below flap_quality, and a node
  // already non-manifold may stay so (see below).
  bool lastResort = false;
  std::vector<std::uint8_t> isSeed, tetChanged;  // collapseEdges: per node, per tet
  struct Refused {
    std::int32_t v, next;
    std::uint32_t stampU, stampV;
    bool shortEdge, offCut;
  };
  std::vector<std::uint32_t> starStamp;  // collapseEdges: see there
  std::uint32_t stampClock = 0;
  std::vector<std::int32_t> refusedHead, refusedUs;
  std::vector<Refused> refusedPool;
  auto collapseEdges = [&]() {
    if (!(options.collapse_fraction > 0)) return;
    std::vector<std::uint8_t> locked(N, 0);
    // Candidates refused by a check that looks only at the stars of u and v (positions do not
    // change here): refused again while neither star changes (starStamp[n] takes a new number
    // whenever a tet with n dies or changes), whatever else happened. A later batch skips them
    // (the budget check, which depends on the other collapses, never records a refusal).
    // Per u, a list of (v, shortEdge, offCut, the two stamps) in `refusedPool`.
    // (The arrays live across calls, allocated by the first: the stamps keep counting, the
    // lists are emptied at the end of each call.)
    if (starStamp.empty()) {
      starStamp.assign(N, 0);
      refusedHead.assign(N, -1);
    }
    std::vector<std::int32_t> dying, changing, vstar, checked;
    std::vector<double> detAfter;  // per changing tet: 6 x its volume after the collapse
    std::vector<std::array<std::int32_t, 4>> keysB;
    struct Cand {
      double len;
      std::int32_t u, v;
      bool shortEdge;
      bool offCut;  // v is not on the cut (curved cuts, collapse_off_cut)
      std::int32_t tet;  // the tet it came from
    };
    const bool offCutToo = curved && options.collapse_off_cut;
    // Does node n have a boundary face?
    auto onBoundary = [&](int n) {
      liveStar(n, vstar, nullptr);
      discAround(n, vstar, true);
      return !link.empty();
    };
    // The candidates of tet t (edges of a poor tet, short edges), appended to `out`.
    auto candidatesOf = [&](int t, std::vector<Cand>& out) {
      if ((*dead)[t]) return;
      {
        const double q = tetQ(t);
        if (lastResort && !(q < options.flap_quality)) return;
        // Edge lengths as Eigen's norm() of p[a] - p[b]: the square root of ((x x + y y) + z z),
        // in scalars over the coordinate columns.
        double sq[6], lens[6];
        {
          const double* cx = mesh.X.col(0).data();
          const double* cy = mesh.X.col(1).data();
          const double* cz = mesh.X.col(2).data();
          const int i[4] = {mesh.T(t, 0), mesh.T(t, 1), mesh.T(t, 2), mesh.T(t, 3)};
          for (int a = 0, e = 0; a < 4; ++a)
            for (int b = a + 1; b < 4; ++b, ++e) {
              const double dx = cx[i[a]] - cx[i[b]], dy = cy[i[a]] - cy[i[b]], dz = cz[i[a]] - cz[i[b]];
              sq[e] = (dx * dx + dy * dy) + dz * dz;
            }
        }
        // A tet at or above quality_target has only its short edges: none where the shortest
        // is not below collapse_fraction x the longest (a bound on the mean: the six rounded
        // sixths add up to at most hi (1 + 6 eps) < hi (1 + 1e-9)) or the local edge.
        // (sqrt is correctly rounded, so monotone: the shortest and longest lengths are the
        // roots of the smallest and largest squares; the other four are taken only past here.)
        if (q >= options.quality_target) {
          double lo2 = sq[0], hi2 = sq[0];
          for (int e = 1; e < 6; ++e) {
            lo2 = std::min(lo2, sq[e]);
            hi2 = std::max(hi2, sq[e]);
          }
          const double lo = std::sqrt(lo2), hi = std::sqrt(hi2);
          if (lo >= options.collapse_fraction * std::max(hi * (1 + 1e-9), region.edge_length)) return;
        }
        double mean = 0;
        for (int e = 0; e < 6; ++e) {
          lens[e] = std::sqrt(sq[e]);
          mean += lens[e] / 6.0;
        }
#ifdef HYSIM_CHECK_EXACT
        const Vec3 p[4] = {pos(mesh.T(t, 0)), pos(mesh.T(t, 1)), pos(mesh.T(t, 2)), pos(mesh.T(t, 3))};
        for (int a = 0, e = 0; a < 4; ++a)
          for (int b = a + 1; b < 4; ++b, ++e) {
            const double ref = (p[a] - p[b]).norm();
            if (std::memcmp(&ref, &lens[e], sizeof ref) != 0) std::abort();
          }
#endif
        for (int a = 0, e = 0; a < 4; ++a)
          for (int b = a + 1; b < 4; ++b, ++e) {
            const int x = mesh.T(t, a), y = mesh.T(t, b);
            const double len = lens[e];
            const bool shortEdge = len < options.collapse_fraction * std::max(mean, region.edge_length);
            if (!shortEdge && q >= options.quality_target) continue;
            if (onCut[y]) out.push_back({len, x, y, shortEdge, false, t});
            if (onCut[x]) out.push_back({len, y, x, shortEdge, false, t});
            if (offCutToo && !onCut[x] && !onCut[y]) {
              out.push_back({len, x, y, shortEdge, true, t});
              out.push_back({len, y, x, shortEdge, true, t});
            }
          }
      }
    };
    // The candidates of all region tets (`raw`, with copies). A batch changes only the tets
    // of its collapses (removed, or a node replaced: `changedTets`) and nothing else a
    // candidate depends on (positions, the cut flags): the next batch keeps the candidates of
    // the other tets and takes those of the changed ones anew (where they are still region
    // tets: with a seed node). The sorted and merged list below is the same as from scratch.
    if (isSeed.empty()) {
      isSeed.assign(N, 0);
      for (int n : seeds) isSeed[n] = 1;
    }
    if (tetChanged.empty()) tetChanged.assign(M, 0);
    std::vector<Cand> raw, cands;
    std::vector<std::int32_t> changedTets;
    // Sorted by length (then ends); an edge comes once per poor tet around it: one candidate
    // per (u, v), short if any of its copies is (a short edge's test accepts what the other
    // accepts, and copies would be tried one after the other on the same mesh).
    auto byKey = [](const Cand& p, const Cand& q) {  // (the lengths are finite)
      if (p.len < q.len) return true;
      if (q.len < p.len) return false;
      return p.u != q.u ? p.u < q.u : p.v < q.v;
    };
    // (c sorted by byKey: copies of a candidate are neighbours, in any order; the first
    // copy's fields are kept, the same for every copy but the tet, which the loop below does
    // not read.)
    // (Into `out`, which is resized to c's size first and then cut to the merged count.)
    auto mergeCopies = [](const std::vector<Cand>& c, std::vector<Cand>& out) {
      out.resize(c.size());
      size_t kept = 0;
      for (size_t i = 0; i < c.size(); ++i) {
        if (kept > 0 && out[kept - 1].len == c[i].len && out[kept - 1].u == c[i].u && out[kept - 1].v == c[i].v) {
          out[kept - 1].shortEdge = out[kept - 1].shortEdge || c[i].shortEdge;
          continue;
        }
        out[kept++] = c[i];
      }
      out.resize(kept);
    };
#ifdef HYSIM_CHECK_EXACT
    auto sortMerge = [&](std::vector<Cand>& c) {
      std::sort(c.begin(), c.end(), byKey);
      const std::vector<Cand> all = c;
      mergeCopies(all, c);
    };
#endif
    // `raw` is kept sorted by byKey: the first batch sorts it; a later batch drops the
    // candidates of the changed tets (the rest stays sorted), sorts the new ones and merges
    // the two runs. The list is then the same as a sort of the whole (the same elements; copies
    // only differ in their tet).
    for (int batch = 0; batch < 3; ++batch) {
      if (batch == 0) {
        std::vector<std::int32_t> seen;
        regionTets(seen);
        raw.clear();
        for (int t : seen) candidatesOf(t, raw);
        std::sort(raw.begin(), raw.end(), byKey);
      } else {
        for (int t : changedTets) tetChanged[t] = 1;
        raw.erase(std::remove_if(raw.begin(), raw.end(),
                                 [&](const Cand& c) { return (*dead)[c.tet] || tetChanged[c.tet]; }),
                  raw.end());
        const size_t kept = raw.size();
        for (int t : changedTets) {
          if (!tetChanged[t]) continue;  // (a tet changed twice: once)
          tetChanged[t] = 0;
          bool inRegion = false;
          for (int k = 0; k < 4; ++k) inRegion = inRegion || isSeed[mesh.T(t, k)];
          if (inRegion) candidatesOf(t, raw);
        }
        changedTets.clear();
        const auto mid = raw.begin() + static_cast<std::ptrdiff_t>(kept);
        std::sort(mid, raw.end(), byKey);
        cands.clear();
        std::merge(raw.begin(), mid, mid, raw.end(), std::back_inserter(cands), byKey);
        raw.swap(cands);
      }
      mergeCopies(raw, cands);
#ifdef HYSIM_CHECK_EXACT
      {  // the same list as from scratch
        std::vector<std::int32_t> seen;
        std::vector<Cand> ref;
        regionTets(seen);
        for (int t : seen) candidatesOf(t, ref);
        sortMerge(ref);
        bool same = ref.size() == cands.size();
        for (size_t i = 0; i < ref.size() && same; ++i)
          same = std::memcmp(&ref[i].len, &cands[i].len, sizeof(double)) == 0 && ref[i].u == cands[i].u &&
                 ref[i].v == cands[i].v && ref[i].shortEdge == cands[i].shortEdge && ref[i].offCut == cands[i].offCut;
        if (!same) std::abort();
      }
#endif
      int done = 0;
      for (const Cand& c : cands) {
        const int u = c.u, v = c.v;
        if (locked[u] || locked[v]) continue;
        {
          bool again = false;
          for (std::int32_t r = refusedHead[u]; r >= 0 && !again; r = refusedPool[r].next) {
            const Refused& e = refusedPool[r];
            again = e.v == v && e.shortEdge == c.shortEdge && e.offCut == c.offCut && e.stampU == starStamp[u] &&
                    e.stampV == starStamp[v];
          }
          if (again) continue;
        }
        auto refuse = [&]() {
          if (refusedHead[u] < 0) refusedUs.push_back(u);
          refusedPool.push_back({v, refusedHead[u], starStamp[u], starStamp[v], c.shortEdge, c.offCut});
          refusedHead[u] = static_cast<std::int32_t>(refusedPool.size()) - 1;
        };
        // One pass over u's live tets: those with v die, the others change (u becomes v).
        // Checks in order of cost, all must pass and have no side effects (so the first
        // failure rejects, whichever it is): off the cut, one material (every live tet of u,
        // that is the dying and changing ones, has the label of the first); no changed tet
        // inverts or goes flat (its determinant with v for u, in tetVolumeHere's scalar
        // arithmetic: Eigen's (p1 - p0).dot((p2 - p0).cross(p3 - p0)), the same value; kept
        // for the volume check below); the edge is still an edge (a tet dies).
        dying.clear();
        changing.clear();
        detAfter.clear();
        bool ok = true;
        {
          const double* cx = mesh.X.col(0).data();
          const double* cy = mesh.X.col(1).data();
          const double* cz = mesh.X.col(2).data();
          const double vx = cx[v], vy = cy[v], vz = cz[v];
          std::int32_t mat0 = 0;
          bool first = true;
          for (const std::int32_t *s = starB(u), *sEnd = starE(u); s < sEnd; ++s) {
            const int t = (*s);
            if ((*dead)[t]) continue;
            if (c.offCut) {
              const std::int32_t m = mesh.material(t);
              if (first) {
                mat0 = m;
                first = false;
              } else if (m != mat0) {
                ok = false;
                break;
              }
            }
            const int i0 = mesh.T(t, 0), i1 = mesh.T(t, 1), i2 = mesh.T(t, 2), i3 = mesh.T(t, 3);
            if ((i0 == v) | (i1 == v) | (i2 == v) | (i3 == v)) {
              dying.push_back(t);
              continue;
            }
            const double x0 = i0 == u ? vx : cx[i0], y0 = i0 == u ? vy : cy[i0], z0 = i0 == u ? vz : cz[i0];
            const double x1 = i1 == u ? vx : cx[i1], y1 = i1 == u ? vy : cy[i1], z1 = i1 == u ? vz : cz[i1];
            const double x2 = i2 == u ? vx : cx[i2], y2 = i2 == u ? vy : cy[i2], z2 = i2 == u ? vz : cz[i2];
            const double x3 = i3 == u ? vx : cx[i3], y3 = i3 == u ? vy : cy[i3], z3 = i3 == u ? vz : cz[i3];
            const double ax = x1 - x0, ay = y1 - y0, az = z1 - z0;
            const double bx = x2 - x0, by = y2 - y0, bz = z2 - z0;
            const double ex = x3 - x0, ey = y3 - y0, ez = z3 - z0;
            const double nx = by * ez - bz * ey, ny = bz * ex - bx * ez, nz = bx * ey - by * ex;
            const double det = (ax * nx + ay * ny) + az * nz;
#ifdef HYSIM_CHECK_EXACT
            {
              Vec3 p[4];
              for (int k = 0; k < 4; ++k) p[k] = mesh.T(t, k) == u ? pos(v) : pos(mesh.T(t, k));
              const double ref = (p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0]));
              if (std::memcmp(&ref, &det, sizeof det) != 0) std::abort();
            }
#endif
            if (!(det > 0)) {
              ok = false;
              break;
            }
            changing.push_back(t);
            detAfter.push_back(det);
          }
        }
        if (!ok || dying.empty()) {
          refuse();
          continue;
        }
        const Vec3 xv = pos(v);
        // Volume: the removed tets and the change of the others, against u's star.
        double before = 0, after = 0;
        matVol.clear();
        for (int t : dying) {
          const double vt = tetVolumeHere(mesh, t);
          before += vt;
          matAdd(t, vt, 0.0);
        }
        for (size_t i = 0; i < changing.size(); ++i) {
          const int t = changing[i];
          const double vt = tetVolumeHere(mesh, t);
          before += vt;
          const double vol = detAfter[i] / 6.0;
          after += vol;
          matAdd(t, vt, vol);
        }
        const double change = std::abs(after - before);
        // (The same decision as change > ... || !budget.fits(...) || !matFits(...): no side effects.)
        if (change > options.collapse_volume_fraction * std::max(before, refVolume) || !matFits(before)) {
          refuse();
          continue;
        }
        if (!budget.fits(after - before)) continue;
        double oldMin = 1.0;
        for (int t : dying) oldMin = std::min(oldMin, tetQ(t));
        for (int t : changing) oldMin = std::min(oldMin, tetQ(t));
        // newMin = the worst q* after; stop as soon as it fails against oldMin.
        double newMin = 1.0;
        for (int t : changing) {
          newMin = std::min(newMin, tetQAt(t, u, xv));
          if (c.shortEdge ? newMin < oldMin : !(newMin > oldMin)) {
            ok = false;
            break;
          }
        }
        if (!ok || (c.shortEdge ? newMin < oldMin : !(newMin > oldMin))) {
          refuse();
          continue;
        }
        // No changed tet may coincide with a tet already around v.
        liveStar(v, vstar, nullptr);
        keysB.clear();
        for (int w : vstar) {
          if (std::find(dying.begin(), dying.end(), w) != dying.end()) continue;
          std::array<std::int32_t, 4> k{mesh.T(w, 0), mesh.T(w, 1), mesh.T(w, 2), mesh.T(w, 3)};
          std::sort(k.begin(), k.end());
          keysB.push_back(k);
        }
        for (size_t i = 0; i < changing.size() && ok; ++i) {
          const int t = changing[i];
          std::array<std::int32_t, 4> k{mesh.T(t, 0), mesh.T(t, 1), mesh.T(t, 2), mesh.T(t, 3)};
          std::replace(k.begin(), k.end(), u, v);
          std::sort(k.begin(), k.end());
          for (const auto& kb : keysB)
            if (k == kb) ok = false;
        }
        if (!ok) {
          refuse();
          continue;
        }
        // Off the cut: a boundary node only into a boundary node (an interior node's star
        // keeps its volume).
        if (c.offCut && onBoundary(u) && !onBoundary(v)) {
          refuse();
          continue;
        }
        // Apply, check manifoldness around v and the other nodes of the removed tets, or undo.
        ++topoClock;
        for (int t : dying) kill(t);
        touch(u);
        touch(v);
        for (int t : changing) {
          gained.emplace_back(v, t);
          for (int k = 0; k < 4; ++k)
            if (mesh.T(t, k) == u) mesh.T(t, k) = v;
        }
        liveStar(v, around, &changing);
        ok = discAround(v, around);
        // (Each node once: the nodes around the edge are in two of the removed tets.)
        checked.clear();
        for (size_t i = 0; i < dying.size() && ok; ++i)
          for (int k = 0; k < 4 && ok; ++k) {
            const int w = mesh.T(dying[i], k);
            if (w == u || w == v || std::find(checked.begin(), checked.end(), w) != checked.end()) continue;
            checked.push_back(w);
            liveStar(w, around, nullptr);
            ok = discAround(w, around);
            if (!ok && lastResort) {
              // Last resort: a node whose star earlier cuts had already left non-manifold
              // (two sheets of the boundary touching at it) may stay so, if its star has no
              // more pieces and boundary loops than before.
              const StarShape after = starShape(mesh, w, around);
              for (int t : dying) (*dead)[t] = 0;
              for (int t : changing)
                for (int k = 0; k < 4; ++k)
                  if (mesh.T(t, k) == v) mesh.T(t, k) = u;
              liveStar(w, around, nullptr);
              const StarShape before = starShape(mesh, w, around);
              for (int t : dying) (*dead)[t] = 1;
              for (int t : changing)
                for (int k = 0; k < 4; ++k)
                  if (mesh.T(t, k) == u) mesh.T(t, k) = v;
              ok = !before.manifold() && after.noWorseThan(before);
            }
          }
        if (!ok) {
          for (int t : dying) (*dead)[t] = 0;
          for (int t : changing)
            for (int k = 0; k < 4; ++k)
              if (mesh.T(t, k) == v) mesh.T(t, k) = u;
          continue;
        }
        locked[u] = locked[v] = 1;
        // The stars that changed: of every node of the removed and changed tets (v among them), and u.
        starStamp[u] = ++stampClock;
        for (int t : dying)
          for (int k = 0; k < 4; ++k) starStamp[mesh.T(t, k)] = ++stampClock;
        for (int t : changing)
          for (int k = 0; k < 4; ++k) starStamp[mesh.T(t, k)] = ++stampClock;
        changedTets.insert(changedTets.end(), changing.begin(), changing.end());
        budget.spend(after - before);
        ++done;
        if (counts) {
          ++counts->collapsed;
        }
      }
      if (done == 0) break;
      buildStars();
      std::fill(locked.begin(), locked.end(), 0);
    }
    for (int u : refusedUs) refusedHead[u] = -1;
    refusedUs.clear();
    refusedPool.clear();
  };
  // Late snapping: a node off the cut but within collapse_fraction of the local edge length
  // of it, with tets whose other three nodes lie on the cut (slivers and short edges no single
  // edge collapse can remove: collapsing into one cut node flattens the others), moves onto
  // the cut (its nearest point), and the tets that become flat (all four nodes on the cut) are
  // removed. Same acceptance as a collapse: nothing inverts, the worst q* around does not
  // fall, volume within the limits, no non-manifold node.
  // Distances of nodes to the cut surface, kept with the position they were measured at
  // (both snapNear calls ask about the same nodes; most have not moved in between). An entry
  // is exact (|distance| and nearest point) or a lower bound (within() said no). within(x, r)
  // is |signedDistance(x)| <= r with the same per-triangle distances, so the answers are the
  // ones the surface queries give.
  struct DistEntry {
    Vec3 x;
    double d;  // exact: |signed distance|; bound: the distance is above it
    Vec3 closest;
    std::int8_t kind;  // 0 none, 1 exact, 2 lower bound (set when the entry is made)
  };
  // (At most one entry per node, in the order first asked.)
  std::vector<std::int32_t> distSlot;
  std::vector<DistEntry, NoInitAllocator<DistEntry>> distPool;
  std::int32_t distNext = 0;
  auto distInit = [&] {
    if (!distSlot.empty()) return;
    distSlot.assign(N, -1);
    distPool.resize(N);
  };
  auto distEntry = [&](int n) -> DistEntry& {
    distInit();
    std::int32_t& slot = distSlot[n];
    if (slot < 0) {
      slot = distNext++;
      distPool[slot].kind = 0;
    }
    DistEntry& e = distPool[slot];
    if (e.kind != 0 && e.x != pos(n)) e.kind = 0;
    return e;
  };
  // |signed distance| of node n to the cut, and its nearest point. `within`: a distance n is
  // known to be within (within() said so, or n is on the cut and `within` the on-surface
  // tolerance), for the bounded search, which gives signedDistance's value and point (and
  // searches everything after all where nothing is that near).
  auto nodeDistance = [&](int n, Vec3* closest, double within = std::numeric_limits<double>::infinity()) {
    DistEntry& e = distEntry(n);
    if (e.kind != 1) {
      e.x = pos(n);
      e.d = std::abs(region.surface->signedDistanceNear(e.x, within, &e.closest));
      e.kind = 1;
    }
    if (closest) *closest = e.closest;
    return e.d;
  };
  // region.surface->within(pos(n), r).
  auto nodeWithin = [&](int n, double r) {
    DistEntry& e = distEntry(n);
    if (e.kind == 1) return e.d <= r;
    if (e.kind == 2 && r <= e.d) return false;
    const bool in = region.surface->within(pos(n), r);
    if (!in) {
      e.x = pos(n);
      e.d = r;
      e.kind = 2;
    }
    return in;
  };
  auto snapNear = [&]() {
    if (!(options.collapse_fraction > 0) || region.surface == nullptr) return;
    std::vector<std::pair<double, std::int32_t>> cands;
    std::vector<std::int32_t> around0;
    regionTets(around0);
    std::vector<std::uint8_t> tried(N, 0);
    for (int t : around0)
      for (int k = 0; k < 4; ++k) {
        const int u = mesh.T(t, k);
        if (onCut[u] || tried[u]) continue;
        tried[u] = 1;
        const double limit = options.collapse_fraction * region.edge_length;
        if (!nodeWithin(u, limit)) continue;  // far: no nearest-point search
        const double d = nodeDistance(u, nullptr, limit);
        if (d < limit) cands.emplace_back(d, u);
      }
    std::sort(cands.begin(), cands.end());
    std::vector<std::int32_t> dying, changing, group, tets, tetsMerged;
    std::vector<Vec3> targets, groupTo, groupFrom;
    std::vector<std::uint64_t> targetEdges;
    std::vector<std::uint32_t> groupVer;
    const double near = options.collapse_fraction * region.edge_length;
    // groupAt[v]: 1 + v's place in the group while trySnap runs (0: not in it; the group's
    // nodes are distinct), for inGroup and the group's targets without a search.
    std::vector<std::int8_t> groupAt(N, 0);
    auto inGroup = [&](int v) { return groupAt[v] != 0; };
    // A retry (the group grown by a partner, nothing else changed: a failed trySnap leaves
    // everything as it was) takes the volume and q* of each changing tet without the new
    // member from the attempt before (prevGroup: its group size, 0 after a new group).
    std::vector<std::int32_t> prevTets;
    std::vector<double> prevVol, prevQ, curVol, curQ;
    size_t prevGroup = 0;
    // Moves the group onto the cut and removes the tets that go flat, if that passes the
    // checks; otherwise leaves everything as it was and names a near node (not on the cut, not
    // in the group) of the tet that failed, if there is one.
    auto trySnapMarked = [&](int* partner) {
      // The live tets of the group's stars, sorted, each once: each star is sorted, so a
      // merge of the runs (one node: its star as it is) gives what sort + unique gave.
      tets.clear();
      for (size_t gi = 0; gi < group.size(); ++gi) {
        const size_t mid = tets.size();
        for (const std::int32_t *s = starB(group[gi]), *sEnd = starE(group[gi]); s < sEnd; ++s)
          if (!(*dead)[(*s)]) tets.push_back((*s));
        if (gi > 0) mergeSortedRuns(tets, mid, tetsMerged);
      }
#ifdef HYSIM_CHECK_EXACT
      {
        std::vector<std::int32_t> ref;
        for (int g : group)
          for (const std::int32_t *s = starB(g), *sEnd = starE(g); s < sEnd; ++s)
            if (!(*dead)[(*s)]) ref.push_back((*s));
        std::sort(ref.begin(), ref.end());
        ref.erase(std::unique(ref.begin(), ref.end()), ref.end());
        if (ref != tets) std::abort();
      }
#endif
      dying.clear();
      changing.clear();
      double oldMin = 1.0, newMin = 1.0, before = 0, after = 0;
      int worstTet = -1;
      // The partner: a near node of the worst tet off the cut and not in the group (the last).
      auto namePartner = [&](int* partner) {
        for (int k = 0; k < 4; ++k) {
          const int v = mesh.T(worstTet, k);
          if (!onCut[v] && !inGroup(v) && nodeWithin(v, near) && nodeDistance(v, nullptr, near) < near)
            *partner = v;
        }
      };
      matVol.clear();
      const bool reuse = prevGroup > 0 && prevGroup + 1 == group.size();
      const int added = reuse ? group.back() : -1;
      size_t pi = 0;
      // The last try of a chain (three nodes): the caller takes no partner from it, so it may
      // stop at the first changing tet below the old minimum (then newMin < oldMin).
      const bool last = group.size() >= 3;
      if (last)
        for (int t : tets) oldMin = std::min(oldMin, tetQ(t));
      curVol.assign(tets.size(), 0.0);
      curQ.assign(tets.size(), 0.0);
      for (size_t ti = 0; ti < tets.size(); ++ti) {
        const int t = tets[ti];
        int onAfter = 0;
        bool hasAdded = false;
        for (int k = 0; k < 4; ++k) {
          const int v = mesh.T(t, k);
          onAfter += onCut[v] || inGroup(v);
          hasAdded = hasAdded || v == added;
        }
        oldMin = std::min(oldMin, tetQ(t));
        const double vt = tetVolumeHere(mesh, t);
        before += vt;
        if (onAfter == 4) {
          dying.push_back(t);
          matAdd(t, vt, 0.0);
          continue;
        }
        changing.push_back(t);
        double vol, q;
        while (reuse && pi < prevTets.size() && prevTets[pi] < t) ++pi;
        if (reuse && !hasAdded && pi < prevTets.size() && prevTets[pi] == t) {
          vol = prevVol[pi];
          q = prevQ[pi];
        } else {
          Vec3 p[4];
          for (int k = 0; k < 4; ++k) {
            const int v = mesh.T(t, k);
            p[k] = pos(v);
            if (groupAt[v] != 0) p[k] = groupTo[groupAt[v] - 1];
          }
          vol = (p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0])) / 6.0;
          q = vol > 0 ? radiusRatio(p[0], p[1], p[2], p[3]) : -1.0;
        }
        curVol[ti] = vol;
        curQ[ti] = q;
        matAdd(t, vt, vol);
        if (q < newMin) {
          newMin = q;
          worstTet = t;
          // An inverted tet (q* -1, below every q* >= 0): the try fails and this is the worst
          // tet whatever follows (a later one must be strictly worse). Without a partner from
          // it, the caller ends the chain (nothing below is used: stop here).
          if (q < 0 && !last) {
            int p = -1;
            namePartner(&p);
            if (p < 0) return false;
          }
        }
        after += vol;
        if (last && newMin < oldMin) return false;
      }
      prevGroup = group.size();
      prevTets.assign(tets.begin(), tets.end());
      prevVol.swap(curVol);
      prevQ.swap(curQ);
      const double change = std::abs(after - before);
      if (newMin < oldMin && worstTet >= 0) namePartner(partner);
      if (dying.empty() || changing.empty() || newMin < oldMin ||
          change > options.collapse_volume_fraction * std::max(before, refVolume) || !budget.fits(after - before) ||
          !matFits(before)) {
        return false;
      }
      groupFrom.clear();
      groupVer.clear();
      for (size_t g = 0; g < group.size(); ++g) {
        groupFrom.push_back(pos(group[g]));
        groupVer.push_back(nodeVer[group[g]]);
        setPos(group[g], groupTo[g]);
      }
      for (int t : dying) kill(t);
      bool ok = true;
      for (size_t g = 0; g < group.size() && ok; ++g) {
        liveStar(group[g], around, nullptr);
        ok = discAround(group[g], around);
      }
      for (size_t i = 0; i < dying.size() && ok; ++i)
        for (int k = 0; k < 4 && ok; ++k) {
          const int w = mesh.T(dying[i], k);
          if (inGroup(w)) continue;
          liveStar(w, around, nullptr);
          ok = discAround(w, around);
        }
      if (!ok) {
        for (int t : dying) (*dead)[t] = 0;
        for (size_t g = 0; g < group.size(); ++g) restorePos(group[g], groupFrom[g], groupVer[g]);
        return false;
      }
      for (int g : group) {
        onCut[g] = 1;
        lateSnapped.push_back(g);
        if (counts) ++counts->late_snaps;
      }
      budget.spend(after - before);
      return true;
    };
    auto trySnap = [&](int* partner) {
      for (size_t g = 0; g < group.size(); ++g) groupAt[group[g]] = static_cast<std::int8_t>(g + 1);
      const bool ok = trySnapMarked(partner);
      for (int g : group) groupAt[g] = 0;
      return ok;
    };
    for (const auto& [dist, u] : cands) {
      if (onCut[u]) continue;
      // Targets: the nearest point of the cut, then the nearest points of the edges between
      // two cut nodes around u (for a node on the outer boundary, the rim: it stays on the
      // boundary's polygonal surface).
      targets.clear();
      targetEdges.clear();
      targets.emplace_back();
      nodeDistance(u, &targets.back());
      for (const std::int32_t *s = starB(u), *sEnd = starE(u); s < sEnd; ++s) {
        const int t = (*s);
        if ((*dead)[t]) continue;
        for (int i = 0; i < 4; ++i)
          for (int j = i + 1; j < 4; ++j) {
            const int a = mesh.T(t, i), b = mesh.T(t, j);
            if (a == u || b == u || !onCut[a] || !onCut[b]) continue;
            // The same link edge seen from its other tet, possibly as (b, a): its point differs
            // from the first one's in rounding only, and is not tried again.
            const std::uint64_t edge = std::uint64_t(std::uint32_t(std::min(a, b))) << 32 | std::uint32_t(std::max(a, b));
            if (std::find(targetEdges.begin(), targetEdges.end(), edge) != targetEdges.end()) continue;
            targetEdges.push_back(edge);
            const Vec3 pa = pos(a), ab = pos(b) - pa;
            const double l2 = ab.squaredNorm();
            if (!(l2 > 0)) continue;
            // A target equal (bit for bit) to an earlier one fails the same way: trySnap leaves
            // everything as it was when it fails (the link edge (a, b) of u is in two tets).
            const Vec3 y = pa + std::clamp((pos(u) - pa).dot(ab) / l2, 0.1, 0.9) * ab;
            bool seen = false;
            for (size_t k = 0; k < targets.size() && !seen; ++k)
              seen = std::memcmp(targets[k].data(), y.data(), sizeof(double) * 3) == 0;
            if (!seen) targets.push_back(y);
          }
      }
      for (const Vec3& y : targets) {
        if ((y - pos(u)).norm() > options.collapse_fraction * region.edge_length) continue;
        // The moving set: u, plus (up to two) near nodes next to it that must come along (a
        // tet that would go flat or get worse because another of its nodes is also near the
        // cut): they move to their nearest points of the cut.
        group.assign({u});
        groupTo.assign({y});
        prevGroup = 0;
        bool done = false;
        while (!done) {
          int partner = -1;
          const bool ok = trySnap(&partner);
          if (ok) {
            done = true;
            break;
          }
          if (partner < 0 || group.size() >= 3) break;
          Vec3 z;
          nodeDistance(partner, &z);
          group.push_back(partner);
          groupTo.push_back(z);
        }
        if (done) break;
      }
    }
  };
  timed(&OptimizeCounts::late_snap_ms, snapNear);
  timed(&OptimizeCounts::collapse_ms, collapseEdges);
  flips();

  // Nodes up to `rings` edge steps from the seeds may move.
  std::vector<std::int8_t> ring(N, -1);
  {
    std::vector<std::int32_t> frontier, next;
    for (int n : seeds)
      if (n >= 0 && n < N && ring[n] < 0) {
        ring[n] = 0;
        frontier.push_back(n);
      }
    for (int r = 1; r <= options.rings && !frontier.empty(); ++r) {
      next.clear();
      for (int n : frontier)
        for (const std::int32_t *s = starB(n), *sEnd = starE(n); s < sEnd; ++s)
          for (int k = 0; k < 4; ++k) {
            const int v = mesh.T((*s), k);
            if (ring[v] < 0) {
              ring[v] = static_cast<std::int8_t>(r);
              next.push_back(v);
            }
          }
      frontier.swap(next);
    }
  }
  // Work list: the nodes of poor elements around the seeds.
  std::vector<std::int32_t> stamp(N, -1), work;
  auto addNodesOf = [&](int t, int round) {  // t's nodes within the rings, each once a round
    for (int k = 0; k < 4; ++k) {
      const int v = mesh.T(t, k);
      if (ring[v] >= 0 && stamp[v] != round) {
        stamp[v] = round;
        work.push_back(v);
      }
    }
  };
  auto addBadAround = [&](int n, int round) {
    for (const std::int32_t *s = starB(n), *sEnd = starE(n); s < sEnd; ++s) {
      const int t = (*s);
      if ((*dead)[t] || tetQ(t) >= options.quality_target) continue;
      addNodesOf(t, round);
    }
  };
  {
    // (As addBadAround(n, 0) for each seed n: the poor tets met, in order, then their nodes.)
    std::vector<std::int32_t> poor;
    for (int n : seeds)
      if (n >= 0 && n < N)
        for (const std::int32_t *s = starB(n), *sEnd = starE(n); s < sEnd; ++s)
          if (!(*dead)[*s] && tetQ(*s) < options.quality_target) poor.push_back(*s);
    for (const int t : poor) addNodesOf(t, 0);
  }
  std::vector<std::uint8_t> didMove(N, 0);
  std::vector<std::int32_t> movedNow;
  struct StarVolTet {  // per live star tet in the move loop's volume check (see there)
    double p[3][4];    // the corners' x, y, z
    double a[3], b[3], e[3], nrm[3];  // p1 - p0, p2 - p0, p3 - p0, b x e (where kn != 0)
    double old;        // its volume where n is
    int kn;            // n's corner
  };
  // The move loop's scratch, what an iteration gathers, and what the part being moved spent.
  struct MoveScratch {
    std::vector<double> starVolume;  // per node, filled when first needed
    std::vector<StarVolTet> starVol;
    double largest = 0, scale = 0;
    bool split = false;         // moving a part (see moveRun): half the budget left at its start
    double net = 0, churn = 0;  // (split) the volume change the part spent
  };
  MoveScratch mv;
  // Does a move's volume change dv fit the move budget? A part of a split has half the room
  // left at the split's start: |net + 2 (its net + dv)| <= limit and the same for the churn,
  // so whatever both parts spend, the sum fits (the halves' mean does).
  auto moveFits = [&](double dv) {
    if (!mv.split) return moveBudget.fits(dv);
    return std::abs(moveBudget.net + 2.0 * (mv.net + dv)) <= moveBudget.limit &&
           moveBudget.churn + 2.0 * (mv.churn + std::abs(dv)) <= moveBudget.churn_factor * moveBudget.limit;
  };
  // One node's move (the file comment): it reads the positions of n and its neighbours and
  // writes n's; appends n to movedNow where it moved.
  auto moveNode = [&](int n) {
    // (The cached quality test before the constraint, which looks at the whole star.)
    int wt = -1;
    const double before = starWorst(n, &wt);
    if (before < 0 || before >= options.quality_target || wt < 0) return;
    const Constraint c = constraintOf(n);
    if (c.kind == Freedom::Fixed) return;
    const Vec3 x = pos(n);
    auto project = [&](Vec3 d) {
      if (c.kind != Freedom::Free && c.kind != Freedom::Ridge) d -= d.dot(c.normal) * c.normal;
      return d;
    };
    // Unit direction of the allowed part of d (zero when d is (nearly) all normal: the
    // remainder would be rounding noise).
    auto unitIn = [&](const Vec3& d) {
      const Vec3 p = project(d);
      const double len = p.norm();
      return len > 1e-6 * d.norm() && len > 0 ? Vec3(project(p / len)) : Vec3::Zero();
    };
    double sum = 0;
    int deg = 0;
    Vec3 force = Vec3::Zero();
    for (const std::int32_t *s = starB(n), *sEnd = starE(n); s < sEnd; ++s) {
      if ((*dead)[(*s)]) continue;
      for (int k = 0; k < 4; ++k) {
        const int m = mesh.T((*s), k);
        if (m == n) continue;
        sum += (pos(m) - x).norm();
        ++deg;
      }
    }
    if (deg == 0) return;
    const double h = sum / deg;
    mv.scale = std::max(mv.scale, h);
    for (const std::int32_t *s = starB(n), *sEnd = starE(n); s < sEnd; ++s) {
      if ((*dead)[(*s)]) continue;
      for (int k = 0; k < 4; ++k) {
        const int m = mesh.T((*s), k);
        if (m == n) continue;
        const Vec3 d = pos(m) - x;
        const double len = d.norm();
        if (len > 0) force += (len - h) * d / len;
      }
    }
    // The worst tet's corners, n's at wtK (for tetQAt(wt, n, y) below: the same values).
    Vec3 wtP[4];
    int wtK = -1;
    for (int k = 0; k < 4; ++k) {
      const int v = mesh.T(wt, k);
      wtP[k] = pos(v);
      if (v == n) wtK = k;
    }
    auto wtQAt = [&](const Vec3& y) {
      switch (wtK) {
        case 0: return radiusRatioOriented(y, wtP[1], wtP[2], wtP[3]);
        case 1: return radiusRatioOriented(wtP[0], y, wtP[2], wtP[3]);
        case 2: return radiusRatioOriented(wtP[0], wtP[1], y, wtP[3]);
        case 3: return radiusRatioOriented(wtP[0], wtP[1], wtP[2], y);
        default: return radiusRatioOriented(wtP[0], wtP[1], wtP[2], wtP[3]);  // (n not a corner: not expected)
      }
    };
    // Gradient of the worst element's q* (central differences).
    Vec3 grad = Vec3::Zero();
    const double fd = 1e-4 * h;
    for (int a = 0; a < 3; ++a) {
      Vec3 e = Vec3::Zero();
      e[a] = fd;
      grad[a] = (wtQAt(x + e) - wtQAt(x - e)) / (2 * fd);
    }
    grad = unitIn(grad);
    // Push: away from the face opposite n in its worst tet.
    Vec3 face[3];
    int f = 0;
    for (int k = 0; k < 4; ++k)
      if (mesh.T(wt, k) != n) face[f++] = pos(mesh.T(wt, k));
    Vec3 push = (face[1] - face[0]).cross(face[2] - face[0]);
    if (push.norm() > 0) push.normalize();
    if (push.dot(x - face[0]) < 0) push = -push;
    push = unitIn(push);
    const Vec3 spring = options.step_gain * 2.0 * force / deg;
    const Vec3 dirs[3] = {0.25 * h * grad, spring.norm() * unitIn(spring), 0.3 * h * push};
    double best = before, bestDv = 0;
    Vec3 bestX = x;
    // Every candidate lies within 2 x the longest direction of x (a fan's nearest point is
    // no farther from y than x is). When the cut surface is farther than that from x (with a
    // margin of a few eps), no candidate can cross it or come within eps of it: sideKept
    // holds for all of them, and its surface queries are skipped (one query, asked when the
    // first candidate gets that far, instead).
    // y := its nearest point of the cut, which lies within |y - x| + dist(x) of y: the
    // search looks no farther (the same point as a full search).
    auto onCutAgain = [&](Vec3& y) {
      const double r = (y - x).norm() + nodeDistance(n, nullptr, onCut[n] ? region.eps : std::numeric_limits<double>::infinity());
      region.surface->signedDistanceNear(Vec3(y), r, &y);
    };
    int farFromCut = curved && !onCut[n] ? -1 : 0;  // -1: not asked yet
    mv.starVolume.clear();
    auto sideOk = [&](const Vec3& y) {
      if (farFromCut < 0) {
        double reach = 0;
        for (const Vec3& d : dirs) reach = std::max(reach, d.norm());
        farFromCut = nodeWithin(n, 2.0 * reach + 4.0 * region.eps) ? 0 : 1;
      }
      return farFromCut == 1 || sideKept(n, x, y);
    };
    for (const Vec3& d : dirs) {
      if (d.squaredNorm() == 0) continue;
      double step = 1.0;
      for (int tries = 0; tries < 5; ++tries, step *= 0.5) {
        Vec3 y = x + step * d;
        if (c.kind == Freedom::Surface) onCutAgain(y);
        if (c.kind == Freedom::Ridge) {  // along the ridge edge nearest the move, at most 0.45 of it
          const Vec3 d = y - x;
          double bestAlong = 0;
          Vec3 to = x;
          for (const Vec3& r : c.ridge) {
            const Vec3 e = r - x;
            const double len = e.norm();
            if (!(len > 0)) continue;
            const double along = std::min(d.dot(e) / len, 0.45 * len);
            if (along > bestAlong) {
              bestAlong = along;
              to = x + (along / len) * e;
            }
          }
          if (!(bestAlong > 0)) continue;
          y = to;
          if (onCut[n]) onCutAgain(y);
        }
        if (c.kind == Freedom::Fan) {
          Vec3 best = y;
          double bestD = std::numeric_limits<double>::infinity();
          for (const auto& tri : cons.fan) {
            const Vec3 z = closestPointOnTriangle(y, tri[0], tri[1], tri[2]);
            const double dz = (z - y).squaredNorm();
            if (dz < bestD) {
              bestD = dz;
              best = z;
            }
          }
          y = best;
        }
        // The checks below must all pass and have no side effects on the outcome (their
        // caches and starAbove's lastBelow only skip or order work), so any order gives the
        // same moves: the cheapest first (the worst tet, which starAbove tries first anyway),
        // then the volume check (it fails often), the surface queries after it.
        const double qFirst = wtQAt(y);
        if (!(qFirst > best)) continue;
        // Moves on a curved surface change the volume a little (the faces are chords): within the budget.
        double dv = 0;
        if (curved && (c.kind == Freedom::Surface || c.kind == Freedom::Fan || c.kind == Freedom::Ridge)) {
          if (mv.starVolume.empty()) {  // the star's volumes where n is (the same for every candidate)
            // With them, per live star tet the parts of its volume expression that do not
            // depend on n's position (the corners, the differences and the cross product of
            // the fixed corners: the same operations on the same values as below).
            const double* cx = mesh.X.col(0).data();
            const double* cy = mesh.X.col(1).data();
            const double* cz = mesh.X.col(2).data();
            mv.starVol.clear();
            for (const std::int32_t *s = starB(n), *sEnd = starE(n); s < sEnd; ++s) {
              mv.starVolume.push_back((*dead)[*s] ? 0.0 : tetVolumeHere(mesh, *s));
              if ((*dead)[*s]) continue;
              StarVolTet sv;
              double px[4], py[4], pz[4];
              sv.kn = -1;
              for (int k = 0; k < 4; ++k) {
                const int v = mesh.T(*s, k);
                if (v == n && sv.kn < 0) sv.kn = k;
                px[k] = cx[v];
                py[k] = cy[v];
                pz[k] = cz[v];
              }
              sv.old = mv.starVolume.back();
              for (int k = 0; k < 4; ++k) {
                sv.p[0][k] = px[k];
                sv.p[1][k] = py[k];
                sv.p[2][k] = pz[k];
              }
              if (sv.kn != 0) {
                sv.a[0] = px[1] - px[0], sv.a[1] = py[1] - py[0], sv.a[2] = pz[1] - pz[0];
                sv.b[0] = px[2] - px[0], sv.b[1] = py[2] - py[0], sv.b[2] = pz[2] - pz[0];
                sv.e[0] = px[3] - px[0], sv.e[1] = py[3] - py[0], sv.e[2] = pz[3] - pz[0];
                const double bx = sv.b[0], by = sv.b[1], bz = sv.b[2];
                const double ex = sv.e[0], ey = sv.e[1], ez = sv.e[2];
                sv.nrm[0] = by * ez - bz * ey, sv.nrm[1] = bz * ex - bx * ez, sv.nrm[2] = bx * ey - by * ex;
              }
              mv.starVol.push_back(sv);
            }
          }
          // (The volume of each tet with n at y in scalars, as tetVolumeHere: the same value
          // as the vector expression (p1 - p0).dot((p2 - p0).cross(p3 - p0)).)
          for (const StarVolTet& sv : mv.starVol) {
            double ax, ay, az, bx, by, bz, ex, ey, ez, vol6;
            if (sv.kn == 0) {
              ax = sv.p[0][1] - y[0], ay = sv.p[1][1] - y[1], az = sv.p[2][1] - y[2];
              bx = sv.p[0][2] - y[0], by = sv.p[1][2] - y[1], bz = sv.p[2][2] - y[2];
              ex = sv.p[0][3] - y[0], ey = sv.p[1][3] - y[1], ez = sv.p[2][3] - y[2];
            } else {
              ax = sv.a[0], ay = sv.a[1], az = sv.a[2];
              bx = sv.b[0], by = sv.b[1], bz = sv.b[2];
              ex = sv.e[0], ey = sv.e[1], ez = sv.e[2];
              const double dx = y[0] - sv.p[0][0], dy = y[1] - sv.p[1][0], dz = y[2] - sv.p[2][0];
              if (sv.kn == 1) ax = dx, ay = dy, az = dz;
              else if (sv.kn == 2) bx = dx, by = dy, bz = dz;
              else if (sv.kn == 3) ex = dx, ey = dy, ez = dz;
            }
            if (sv.kn == 1 || sv.kn < 0) {  // (kn < 0: n not a corner, not expected)
              vol6 = (ax * sv.nrm[0] + ay * sv.nrm[1]) + az * sv.nrm[2];
            } else {
              const double nx = by * ez - bz * ey, ny = bz * ex - bx * ez, nz = bx * ey - by * ex;
              vol6 = (ax * nx + ay * ny) + az * nz;
            }
#ifdef HYSIM_CHECK_EXACT
            {
              Vec3 p[4];
              for (int k = 0; k < 4; ++k)
                p[k] = k == sv.kn ? y : Vec3(sv.p[0][k], sv.p[1][k], sv.p[2][k]);
              const double ref = (p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0]));
              if (std::memcmp(&ref, &vol6, sizeof vol6) != 0) std::abort();
            }
#endif
            dv += vol6 / 6.0 - sv.old;
          }
          if (!moveFits(dv) || std::abs(dv) > options.move_volume_fraction * edgeTet) continue;
        }
        if (!sideOk(y)) continue;
        double q = 0;
        if (starAbove(n, y, wt, qFirst, best, &q)) {
          best = q;
          bestX = y;
          bestDv = dv;
          break;
        }
      }
    }
    if (best > before) {
      mv.largest = std::max(mv.largest, (bestX - x).norm());
      if (mv.split) {
        mv.net += bestDv;
        mv.churn += std::abs(bestDv);
      } else {
        moveBudget.spend(bestDv);
      }
      setPos(n, bestX);
      didMove[n] = 1;
      movedNow.push_back(n);
    }
  };
  // The move loop's nodes in parts: after splitWork(list), partA and partB (each in list
  // order) have no two nodes that are neighbours (share a tet), so neither part's moves read
  // a position the other's write, and partS holds the rest. A sort along an axis by position
  // puts the nodes ranked below k on the left; partA is those whose neighbours in the list
  // are all on the left too, partB the right, partS the left ones with a neighbour on the
  // right. k makes max(|A|, |B|) + |S| smallest.
  // False where the list is too short to be worth it or no split leaves both parts nodes.
  std::vector<std::int32_t> workAt(N, -1);  // place in the list being split, -1 elsewhere
  // Per node looked at: its neighbours, ringLen[n] entries of ringPool from ringStart[n] (-1: not yet).
  std::vector<std::int32_t> ringStart(N, -1), ringLen(N, 0), ringMark(N, -1), ringPool;
  std::vector<std::int32_t> adjOff, adj, rankOf, reach, below, partA, partB, partS;
  std::vector<std::pair<double, std::int32_t>> keyed;  // (coordinate, place in the list)
  auto splitWork = [&](const std::vector<std::int32_t>& list) {
    const int W = static_cast<int>(list.size());
    if (W < std::max(2, options.parallel_min_nodes)) return false;
    for (int i = 0; i < W; ++i) workAt[list[i]] = i;
    adjOff.assign(W + 1, 0);
    adj.clear();
    for (int i = 0; i < W; ++i) {
      const int n = list[i];
      if (ringStart[n] < 0) {  // n's neighbours (live tets), kept: the loop changes no tet
        ringStart[n] = static_cast<std::int32_t>(ringPool.size());
        for (const std::int32_t *s = starB(n), *sEnd = starE(n); s < sEnd; ++s) {
          if ((*dead)[*s]) continue;
          for (int k = 0; k < 4; ++k) {
            const int m = mesh.T(*s, k);
            if (m == n || ringMark[m] == n) continue;
            ringMark[m] = n;
            ringPool.push_back(m);
          }
        }
        ringLen[n] = static_cast<std::int32_t>(ringPool.size()) - ringStart[n];
      }
      for (const std::int32_t *m = &ringPool[ringStart[n]], *mEnd = m + ringLen[n]; m < mEnd; ++m)
        if (workAt[*m] >= 0) adj.push_back(workAt[*m]);
      adjOff[i + 1] = static_cast<std::int32_t>(adj.size());
    }
    for (int n : list) workAt[n] = -1;
    // The axis: the longest side of the nodes' bounding box.
    Vec3 lo = pos(list[0]), hi = lo;
    for (int n : list) {
      lo = lo.cwiseMin(pos(n));
      hi = hi.cwiseMax(pos(n));
    }
    int axis = 0;
    (hi - lo).maxCoeff(&axis);
    keyed.resize(W);
    for (int i = 0; i < W; ++i) keyed[i] = {mesh.X(list[i], axis), i};
    std::sort(keyed.begin(), keyed.end());
    rankOf.resize(W);
    reach.resize(W);
    for (int r = 0; r < W; ++r) rankOf[keyed[r].second] = r;
    for (int i = 0; i < W; ++i) {  // the highest rank of a node and its neighbours
      reach[i] = rankOf[i];
      for (int j = adjOff[i]; j < adjOff[i + 1]; ++j) reach[i] = std::max(reach[i], rankOf[adj[j]]);
    }
    below.assign(W + 1, 0);  // below[k]: nodes with reach < k (partA's size at k)
    for (int i = 0; i < W; ++i) ++below[reach[i] + 1];
    for (int k = 0; k < W; ++k) below[k + 1] += below[k];
    int bestK = -1, bestCost = W;
    for (int k = 1; k < W; ++k) {
      const int sizeA = below[k], sizeB = W - k, sizeS = k - sizeA;
      const int cost = std::max(sizeA, sizeB) + sizeS;
      if (sizeA > 0 && cost < bestCost) {
        bestCost = cost;
        bestK = k;
      }
    }
    if (bestK < 0) return false;
    partA.clear();
    partB.clear();
    partS.clear();
    for (int i = 0; i < W; ++i) {
      if (rankOf[i] >= bestK) {
        partB.push_back(list[i]);
      } else if (reach[i] < bestK) {
        partA.push_back(list[i]);
      } else {
        partS.push_back(list[i]);
      }
    }
    return true;
  };
  // Moves the nodes of `list` (no repeats), appending the moved ones to movedNow: part A,
  // then part B, each with half of the move budget left at the split's start (moveFits; both
  // spend it only after B), then the rest the same way, and the last part (too short to
  // split) one node after another.
  std::vector<std::int32_t> moveRest;
  auto moveRun = [&](const std::vector<std::int32_t>& list) {
    moveRest = list;
    while (splitWork(moveRest)) {
      double net[2], churn[2];
      mv.split = true;
      for (int k = 0; k < 2; ++k) {
        mv.net = mv.churn = 0;
        for (int n : k == 0 ? partA : partB) moveNode(n);
        net[k] = mv.net;
        churn[k] = mv.churn;
      }
      mv.split = false;
      for (int k = 0; k < 2; ++k) {
        moveBudget.net += net[k];
        moveBudget.churn += churn[k];
      }
      moveRest.swap(partS);
    }
    for (int n : moveRest) moveNode(n);
  };
  int it = 0;
  bfStart.assign(N, -1);  // constraintOf keeps the boundary faces per node (see there)
  bfLen.assign(N, 0);
  cons.bfPool.clear();
  for (; it < options.max_iterations && !work.empty(); ++it) {
    mv.largest = mv.scale = 0;
    movedNow.clear();
    timed(&OptimizeCounts::move_ms, [&] { moveRun(work); });
    const double largest = mv.largest, scale = mv.scale;
    work.clear();
    for (int n : movedNow) addBadAround(n, it + 1);
    if (largest <= options.stop_fraction * scale) {
      ++it;
      break;
    }
  }
  bfStart.clear();
  if (counts) counts->iterations = it;
  timed(&OptimizeCounts::late_snap_ms, snapNear);  // moves may have made new short edges on the cut
  timed(&OptimizeCounts::collapse_ms, collapseEdges);
  flips();
  peel();
  if (moved)
    for (int n = 0; n < N; ++n)
      if (didMove[n]) moved->push_back(n);
  if (moved) moved->insert(moved->end(), lateSnapped.begin(), lateSnapped.end());
  if (counts) counts->onto_cut = lateSnapped;
  if (curved) {
    buildStars();  // the lists of the nodes around tets peeled above, as peelFlaps needs them
    const std::function<double(int)> quality = [&](int t) { return tetQ(t); };
    peelFlaps(mesh, region, seeds, stars, options, dead, counts, &quality);  // flap_peel.cpp
    // Tets below flap_quality that no repair removed, around a node earlier cuts left
    // non-manifold (every collapse there was refused): collapse their edges, the node
    // staying as it was.
    lastResort = true;
    timed(&OptimizeCounts::collapse_ms, collapseEdges);
  }
}

}  // namespace hysim::cutting
