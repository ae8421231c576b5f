// Volume bookkeeping: the mesh's volume as the budgets take it, and the per-material limit
// of collapses and snaps.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "cut_optimizer.hpp"
#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::cutting::opt3d {

// Per material (collapse_material_limit): matVol gathers, per label, (before, after) of the
// star's tets (a tet keeps its label, a dying tet's volume goes); matFits checks each against
// collapse_volume_fraction of its own part or of the whole star (starBefore).
void CutOptimizer::matAdd(int t, double before, double after) {
  const std::int32_t m = mesh.material(t);
  for (MatVol& e : matVol)
    if (e.m == m) {
      e.before += before;
      e.after += after;
      return;
    }
  matVol.push_back({m, before, after});
}

bool CutOptimizer::matFits(double starBefore) const {
  using MaterialLimit = Optimize3DOptions::MaterialLimit;
  if (!curved || options.collapse_material_limit == MaterialLimit::Off || matVol.size() < 2) return true;
  for (const MatVol& e : matVol) {
    const double ref = options.collapse_material_limit == MaterialLimit::OwnPart ? e.before : starBefore;
    if (std::abs(e.after - e.before) > options.collapse_volume_fraction * std::max(ref, refVolume)) return false;
  }
  return true;
}

}  // namespace hysim::cutting::opt3d

namespace hysim::cutting {

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

}  // namespace hysim::cutting
