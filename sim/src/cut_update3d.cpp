// Incremental model update after a 3D cut (updateModelAfterCut3D, see tissue_update3d.hpp).
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <functional>
#include <immintrin.h>
#include <limits>
#include <memory>
#include <string>

#include "hysim/sim/tissue_update3d.hpp"
#include "implicit_solver.hpp"
#include "model_internal.hpp"

namespace hysim::sim {

// See model_internal.hpp. Newton's method on the characteristic polynomial from above (from
// the Gershgorin bound: every root is real, so the iterates decrease monotonically to the
// largest), with the pivots of T - x I as the Sturm sequence.
double topTridiagonalEigenvalue(const Eigen::VectorXd& diag, const Eigen::VectorXd& sub) {
  const Eigen::Index n = diag.size();
  double x = -std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < n; ++i)
    x = std::max(x, diag[i] + (i > 0 ? std::abs(sub[i - 1]) : 0.0) + (i + 1 < n ? std::abs(sub[i]) : 0.0));
  double norm = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) norm = std::max(norm, std::abs(diag[i]));
  for (Eigen::Index i = 0; i + 1 < n; ++i) norm = std::max(norm, std::abs(sub[i]));
  x += 1e-12 * norm + std::numeric_limits<double>::min();  // strictly above every root
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // The largest root lies in (lo, hi]: hi the last iterate found above it, lo the last below.
  double hi = x, lo = -std::numeric_limits<double>::infinity();
  for (int iter = 0; iter < 200; ++iter) {
    // Pivots p_i of T - x I and their derivatives: p_i = d_i - x - e_{i-1}^2 / p_{i-1};
    // f'/f = sum p_i' / p_i with p_i' = -1 + e_{i-1}^2 p_{i-1}' / p_{i-1}^2. All p_i < 0
    // exactly when x is above every root (Sturm).
    double p = diag[0] - x, dp = -1.0;
    bool below = !(p < 0.0);
    double ratio = dp / p;
    for (Eigen::Index i = 1; i < n && !below; ++i) {
      const double e2 = sub[i - 1] * sub[i - 1];
      const double q = e2 / p;
      const double next_dp = -1.0 + q * dp / p;
      p = diag[i] - x - q;
      dp = next_dp;
      below = !(p < 0.0);
      ratio += dp / p;
    }
    if (below) {
      lo = x;  // round-off stepped past the root (or landed on it): bisect back up
    } else {
      hi = x;
      // f = prod p_i, f'/f = ratio > 0 above the roots; Newton steps down by 1 / ratio.
      const double step = 1.0 / ratio;
      if (!(step > 0.0)) return nan;
      if (step <= 4.0 * std::numeric_limits<double>::epsilon() * norm) return x - step;
      x -= step;
      if (x > lo) continue;
    }
    if (hi - lo <= 1e-13 * norm) return hi;
    x = 0.5 * (lo + hi);
  }
  return nan;
}

namespace {

// The Lanczos operator (see topEigenvalue), A u = r (K (r u)) with r = M^-1/2 per node: y = r u,
// z' = H y + the springs' terms, z = r z'. A spring between free nodes is kept at its end of
// lower local index k (its group) as w = sqrt(k_s) d, d the unit direction from k to its other
// end b, and b's 4-lane offset; its term is t = w.(y_b - y_k), z'_k -= t w, z'_b += t w. Per
// node (4 lanes: x, y, z, pad 0) y and z' live in y4 and z4.
// Groups in increasing k: z'_k is final once its group is done (every other spring with k at
// an end came in an earlier group), so it is kept in registers through its group and scaled
// into z at the end. 32 bytes a spring: the loop streams them once a step.
struct alignas(32) SpringY {
  double w[3];
  std::int32_t b;  // 4 * local index
  std::int32_t unused;
};
static_assert(sizeof(SpringY) == 32);

// The operator in scalars: `cols` 12 per node (the three columns of the symmetric held block,
// the sum of w w^T over the node's springs to held nodes, pad 0), `r` per node, group k's
// springs springs[group[k], group[k + 1]).
void applySpringsScalar(int count, const double* u, double* z, const double* cols, const double* r,
                        const SpringY* springs, const int* group, double* y4, double* z4) {
  for (int k = 0; k < count; ++k) {
    const double rk = r[k];
    const double x = rk * u[3 * k], y = rk * u[3 * k + 1], w = rk * u[3 * k + 2];
    double* yk = y4 + 4 * k;
    yk[0] = x;
    yk[1] = y;
    yk[2] = w;
    yk[3] = 0.0;
    const double* c = cols + 12 * k;
    double* zk = z4 + 4 * k;
    zk[0] = (c[0] * x + c[4] * y) + c[8] * w;
    zk[1] = (c[1] * x + c[5] * y) + c[9] * w;
    zk[2] = (c[2] * x + c[6] * y) + c[10] * w;
    zk[3] = 0.0;
  }
  for (int k = 0; k < count; ++k) {
    const double* yk = y4 + 4 * k;
    double acc[3] = {z4[4 * k], z4[4 * k + 1], z4[4 * k + 2]};
    for (int i = group[k]; i < group[k + 1]; ++i) {
      const SpringY& s = springs[i];
      const double* yb = y4 + s.b;
      const double t = (s.w[0] * (yb[0] - yk[0]) + s.w[1] * (yb[1] - yk[1])) + s.w[2] * (yb[2] - yk[2]);
      double* zb = z4 + s.b;
      for (int c = 0; c < 3; ++c) {
        acc[c] = acc[c] - t * s.w[c];
        zb[c] = zb[c] + t * s.w[c];
      }
    }
    for (int c = 0; c < 3; ++c) z[3 * k + c] = r[k] * acc[c];
  }
}

bool lanczosAvx2() {
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
}

// The same operator in AVX2: the same IEEE operations in the same order per lane as the scalar
// loop, so the results are the same to the last bit (no FMA: the AVX2 build does not enable
// it, and ISO C++ mode keeps contraction off). Pad lanes hold zeros.
[[gnu::target("avx2")]] void applySpringsAvx2(int count, const double* u, double* z, const double* cols,
                                              const double* r, const SpringY* springs, const int* group, double* y4,
                                              double* z4) {
  const __m256i three = _mm256_set_epi64x(0, -1, -1, -1);
  const __m256d zero = _mm256_setzero_pd();
  for (int k = 0; k < count; ++k) {
    const __m256d rk = _mm256_broadcast_sd(r + k);
    const __m256d y = _mm256_mul_pd(rk, _mm256_maskload_pd(u + 3 * k, three));
    _mm256_storeu_pd(y4 + 4 * k, y);
    const double* c = cols + 12 * k;
    // (c0 x + c4 y) + c8 w per lane
    const __m256d xy = _mm256_add_pd(_mm256_mul_pd(_mm256_loadu_pd(c), _mm256_permute4x64_pd(y, 0x00)),
                                     _mm256_mul_pd(_mm256_loadu_pd(c + 4), _mm256_permute4x64_pd(y, 0x55)));
    _mm256_storeu_pd(z4 + 4 * k, _mm256_add_pd(xy, _mm256_mul_pd(_mm256_loadu_pd(c + 8), _mm256_permute4x64_pd(y, 0xAA))));
  }
  for (int k = 0; k < count; ++k) {
    const __m256d yk = _mm256_loadu_pd(y4 + 4 * k);
    __m256d acc = _mm256_loadu_pd(z4 + 4 * k);
    int i = group[k];
    const int end = group[k + 1];
    // Two springs at a time: their t in one set of shuffles (y is read only), then their
    // updates in spring order (the same sums in the same order as one at a time).
    for (; i + 2 <= end; i += 2) {
      const SpringY& s1 = springs[i];
      const SpringY& s2 = springs[i + 1];
      const __m256d w1 = _mm256_blend_pd(_mm256_load_pd(s1.w), zero, 0x8);  // (lane 3 holds b)
      const __m256d w2 = _mm256_blend_pd(_mm256_load_pd(s2.w), zero, 0x8);
      const __m256d p1 = _mm256_mul_pd(w1, _mm256_sub_pd(_mm256_loadu_pd(y4 + s1.b), yk));
      const __m256d p2 = _mm256_mul_pd(w2, _mm256_sub_pd(_mm256_loadu_pd(y4 + s2.b), yk));
      // lo + hi = (p1_0 + p1_1, p2_0 + p2_1, p1_2, p2_2); then the halves' sum
      const __m256d sum = _mm256_add_pd(_mm256_unpacklo_pd(p1, p2), _mm256_unpackhi_pd(p1, p2));
      const __m128d t = _mm_add_pd(_mm256_castpd256_pd128(sum), _mm256_extractf128_pd(sum, 1));
      const __m256d tw1 = _mm256_mul_pd(_mm256_broadcastsd_pd(t), w1);
      const __m256d tw2 = _mm256_mul_pd(_mm256_broadcastsd_pd(_mm_unpackhi_pd(t, t)), w2);
      acc = _mm256_sub_pd(acc, tw1);
      double* zb = z4 + s1.b;
      _mm256_storeu_pd(zb, _mm256_add_pd(_mm256_loadu_pd(zb), tw1));
      acc = _mm256_sub_pd(acc, tw2);
      zb = z4 + s2.b;
      _mm256_storeu_pd(zb, _mm256_add_pd(_mm256_loadu_pd(zb), tw2));
    }
    if (i < end) {
      const SpringY& s1 = springs[i];
      const __m256d w1 = _mm256_blend_pd(_mm256_load_pd(s1.w), zero, 0x8);
      const __m256d p1 = _mm256_mul_pd(w1, _mm256_sub_pd(_mm256_loadu_pd(y4 + s1.b), yk));
      const __m128d lo = _mm256_castpd256_pd128(p1);
      const __m128d sum01 = _mm_add_sd(lo, _mm_unpackhi_pd(lo, lo));
      const __m256d tw1 = _mm256_mul_pd(_mm256_broadcastsd_pd(_mm_add_sd(sum01, _mm256_extractf128_pd(p1, 1))), w1);
      acc = _mm256_sub_pd(acc, tw1);
      double* zb = z4 + s1.b;
      _mm256_storeu_pd(zb, _mm256_add_pd(_mm256_loadu_pd(zb), tw1));
    }
    _mm256_maskstore_pd(z + 3 * k, three, _mm256_mul_pd(_mm256_broadcast_sd(r + k), acc));
  }
}

// The elements t of `after` that are not the old element old_of[t] with the same nodes in the
// same order (o2n[before.T(old_of[t], k)] == after.T(t, k), k = 0..3), 4 at a time (and the
// last T1 % 4 whatever they are), into `out` in increasing order; returns their number.
[[gnu::target("avx2")]] int sameOrderCandidatesAvx2(int T1, const int* old_of, const std::int32_t* const after_col[4],
                                                    const std::int32_t* const before_col[4], const std::int32_t* o2n,
                                                    int* out) {
  int n = 0, t = 0;
  const __m128i minus1 = _mm_set1_epi32(-1);
  for (; t + 4 <= T1; t += 4) {
    const __m128i o = _mm_loadu_si128(reinterpret_cast<const __m128i*>(old_of + t));
    const __m128i valid = _mm_cmpgt_epi32(o, minus1);
    __m128i same = valid;
    for (int c = 0; c < 4; ++c) {
      const __m128i node = _mm_mask_i32gather_epi32(_mm_setzero_si128(), before_col[c], o, valid, 4);
      const __m128i renumbered = _mm_mask_i32gather_epi32(minus1, o2n, node, valid, 4);
      same = _mm_and_si128(same, _mm_cmpeq_epi32(renumbered, _mm_loadu_si128(reinterpret_cast<const __m128i*>(after_col[c] + t))));
    }
    const int bits = _mm_movemask_ps(_mm_castsi128_ps(same));
    if (bits != 0xF)
      for (int i = 0; i < 4; ++i)
        if (!((bits >> i) & 1)) out[n++] = t + i;
  }
  for (; t < T1; ++t) out[n++] = t;
  return n;
}

// The Lanczos step's element-wise parts (per entry the operations Eigen's expressions
// z -= a * q; z -= beta * prev; and q = z / b; do), each in one pass, compiled for baseline
// x86-64 and for AVX2: the same IEEE operations either way (no FMA).
[[gnu::always_inline]] inline void residualBody(Eigen::Index n, double* __restrict z, const double* __restrict q, double a,
                                                const double* __restrict prev, double beta) {
  if (prev == nullptr) {
    for (Eigen::Index i = 0; i < n; ++i) z[i] = z[i] - a * q[i];
  } else {
    for (Eigen::Index i = 0; i < n; ++i) z[i] = (z[i] - a * q[i]) - beta * prev[i];
  }
}
[[gnu::always_inline]] inline void nextBody(Eigen::Index n, const double* __restrict z, double b, double* __restrict q,
                                            double* __restrict column) {
  for (Eigen::Index i = 0; i < n; ++i) {
    const double v = z[i] / b;
    q[i] = v;
    column[i] = v;
  }
}
void residualBaseline(Eigen::Index n, double* z, const double* q, double a, const double* prev, double beta) {
  residualBody(n, z, q, a, prev, beta);
}
[[gnu::target("avx2")]] void residualAvx2(Eigen::Index n, double* z, const double* q, double a, const double* prev,
                                          double beta) {
  residualBody(n, z, q, a, prev, beta);
}
void nextBaseline(Eigen::Index n, const double* z, double b, double* q, double* column) { nextBody(n, z, b, q, column); }
[[gnu::target("avx2")]] void nextAvx2(Eigen::Index n, const double* z, double b, double* q, double* column) {
  nextBody(n, z, b, q, column);
}
void lanczosResidual(Eigen::Index n, double* z, const double* q, double a, const double* prev, double beta, bool avx2) {
  (avx2 ? residualAvx2 : residualBaseline)(n, z, q, a, prev, beta);
}
void lanczosNext(Eigen::Index n, const double* z, double b, double* q, double* column, bool avx2) {
  (avx2 ? nextAvx2 : nextBaseline)(n, z, b, q, column);
}

// Resets a table of local numbers (-1 between uses) at `nodes` when it goes out of scope.
struct ResetLocal {
  std::vector<int>& local;
  const std::vector<int>& nodes;
  ~ResetLocal() {
    for (int node : nodes) local[node] = -1;
  }
};

// The springs at each node, in increasing spring order (StepSprings' lists, so that the sums
// over them are the same to the last bit): those of node i are spring[e] for
// first[i] <= e < first[i + 1], with ends a, b and stiffness k.
struct NodeSprings {
  const std::int32_t* first = nullptr;
  const std::int32_t* spring = nullptr;
  const std::int32_t* a = nullptr;
  const std::int32_t* b = nullptr;
  const double* k = nullptr;
  int begin(int node) const { return first[node]; }
  int end(int node) const { return first[node + 1]; }
  static NodeSprings of(const StepSprings& st) {
    return {st.node_offset.data(), st.incident.data(), st.a.data(), st.b.data(), st.stiffness.data()};
  }
};

// topEigenvalue's work arrays, kept by the caller across the estimates of one update: `local`
// is all -1 between calls (reset on the way out).
struct LanczosScratch {
  std::vector<int> local;
  std::vector<SpringY> springs;
  std::vector<int> group;
  std::vector<double> cols, y4, z4, inv_root;
};

// Top eigenvalue of M^-1/2 K M^-1/2 (springs linearised along their rest directions) over
// the free nodes `nodes` (none anchored), every other node held fixed (a principal
// submatrix), by Lanczos.
// `start` (#N x 3, may be null or zero) is mixed into the deterministic start vector; `mode`
// (#N x 3) receives the Ritz vector (zero outside `nodes`).
// `decided` (may be null; monotone: once true, true for every larger lambda) may end the
// iteration early: the top Ritz value never decreases from one step to the next (T's leading
// block is the previous T; Cauchy interlacing) and stays below the top eigenvalue, so once
// it is above a value where `decided` holds, so is the value the full iteration would
// return. Then that Ritz value is returned; the caller uses it only through `decided`.
double topEigenvalue(const Model& m, const NodeSprings& st, const cutting::Positions& X, const std::vector<int>& nodes,
                     const Eigen::MatrixX3d* start, const CutUpdate3DOptions& options, Eigen::MatrixX3d* mode,
                     int* steps_taken, const std::function<bool(double)>* decided, LanczosScratch& scratch) {
  const int count = static_cast<int>(nodes.size());
  if (steps_taken) *steps_taken = 0;
  if (count == 0) return 0.0;
  std::vector<int>& local = scratch.local;
  if (local.size() < static_cast<size_t>(m.num_nodes)) local.resize(static_cast<size_t>(m.num_nodes), -1);
  for (int k = 0; k < count; ++k) local[nodes[k]] = k;
  ResetLocal reset_local{local, nodes};
  // The operator (see SpringY): with y = M^-1/2 u, a spring between free nodes contributes
  // t = k d.(y_b - y_a) to z_b along d and its negative to z_a; with w = sqrt(k) d that is
  // t = w.(y_b - y_a), z_a -= t w, z_b += t w. A spring to a held node (y = 0 there) only adds
  // (w.y_i) w at its free end: summed per node into a symmetric 3x3 block, kept as its three
  // columns (`cols`, 12 per node, pad 0). z = M^-1/2 of the sums.
  std::vector<SpringY>& springs = scratch.springs;
  springs.clear();
  const bool avx2 = m.options.simd && lanczosAvx2();
  std::vector<double>& cols = scratch.cols;
  std::vector<double>& inv_root = scratch.inv_root;
  if (cols.size() < 12 * static_cast<size_t>(count)) cols.resize(12 * static_cast<size_t>(count));
  if (inv_root.size() < static_cast<size_t>(count)) inv_root.resize(static_cast<size_t>(count));
  for (int k = 0; k < count; ++k) inv_root[k] = 1.0 / std::sqrt(m.mass[nodes[k]]);
  std::vector<int>& group = scratch.group;
  group.resize(static_cast<size_t>(count) + 1);
  for (int k = 0; k < count; ++k) {
    const int node = nodes[k];
    group[k] = static_cast<int>(springs.size());
    double h[6] = {0, 0, 0, 0, 0, 0};  // xx yy zz xy yz zx
    for (int e = st.begin(node), e_end = st.end(node); e < e_end; ++e) {
      const int s = st.spring[e];
      const int a = st.a[s], b = st.b[s];
      // (local is -1 at anchored nodes: `nodes` are free ones, the caller's estimate nodes.)
      const int la = local[a], lb = local[b];
      const int other = a == node ? b : a, l_other = a == node ? lb : la;
      if (la >= 0 && lb >= 0 && l_other < k) continue;  // taken at the other end
      Eigen::RowVector3d d = X.row(other) - X.row(node);  // (d, w: from this node)
      d /= d.norm();
      const Eigen::RowVector3d w = d * std::sqrt(st.k[s]);
      if (la >= 0 && lb >= 0) {
        SpringY sy;
        for (int c = 0; c < 3; ++c) sy.w[c] = w[c];
        sy.b = 4 * l_other;
        sy.unused = 0;
        springs.push_back(sy);
      } else if (la == k || lb == k) {  // this node free, the other end held
        h[0] += w[0] * w[0];
        h[1] += w[1] * w[1];
        h[2] += w[2] * w[2];
        h[3] += w[0] * w[1];
        h[4] += w[1] * w[2];
        h[5] += w[2] * w[0];
      }
    }
    const double col[12] = {h[0], h[3], h[5], 0.0, h[3], h[1], h[4], 0.0, h[5], h[4], h[2], 0.0};
    std::copy(col, col + 12, &cols[12 * static_cast<size_t>(k)]);
  }
  group[count] = static_cast<int>(springs.size());
  const Eigen::Index n3 = 3 * static_cast<Eigen::Index>(count);
  std::vector<double>& y4 = scratch.y4;
  std::vector<double>& z4 = scratch.z4;
  if (y4.size() < 4 * static_cast<size_t>(count)) y4.resize(4 * static_cast<size_t>(count));
  if (z4.size() < 4 * static_cast<size_t>(count)) z4.resize(4 * static_cast<size_t>(count));
  auto apply = [&](const Eigen::VectorXd& u, Eigen::VectorXd& z) {
    (avx2 ? applySpringsAvx2 : applySpringsScalar)(count, u.data(), z.data(), cols.data(), inv_root.data(),
                                                   springs.data(), group.data(), y4.data(), z4.data());
  };
  // Start: the alternating pattern of buildModel's power iteration (excites the highest
  // modes), plus the given vector.
  Eigen::VectorXd q(n3);
  for (int k = 0; k < count; ++k) {
    const double s = (nodes[k] % 2 == 0) ? 1.0 : -1.0;
    q[3 * k] = s;
    q[3 * k + 1] = -0.5 * s;
    q[3 * k + 2] = 0.25 * s;
  }
  q.normalize();
  if (start != nullptr && start->rows() == m.num_nodes) {
    Eigen::VectorXd w(n3);
    for (int k = 0; k < count; ++k)
      for (int c = 0; c < 3; ++c) w[3 * k + c] = (*start)(nodes[k], c);
    const double norm = w.norm();
    if (norm > 0.0) q = w / norm + 0.1 * q;
    q.normalize();
  }
  const int max_steps = std::max(1, std::min(options.lanczos_steps, static_cast<int>(n3)));
  const bool reorthogonalise = n3 <= options.lanczos_reorthogonalise_max;
  Eigen::MatrixXd Q(n3, max_steps);
  std::vector<double> alpha, beta, history;
  std::vector<std::uint8_t> exact;  // history[h] is the dense solver's value
  bool theta_exact = true;
  Eigen::VectorXd z(n3);
  // Reorthogonalisation: Q^T z and Q (Q^T z), evaluated as the expression
  // z -= Q (Q^T z) evaluates them (into zeroed temporaries, then subtracted), in buffers
  // allocated once.
  Eigen::VectorXd q_dot_z(max_steps), q_proj(reorthogonalise ? n3 : 0);
  // The Ritz values of steps before this one are never read (the settled test looks 5
  // steps back from beyond lanczos_min_steps): their eigenvalue solves are skipped unless
  // the breakdown test needs theta (see below).
  const int first_needed = std::max(1, options.lanczos_min_steps - 4);
  double theta = 0.0;
  Eigen::VectorXd ritz;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(max_steps);
  Eigen::VectorXd tri_diag(max_steps), tri_sub(max_steps);
  // The dense solver's top eigenvalue of the first `size` rows of T, scaled as the loop
  // below scales it: the value the loop's step `size` would have had from it.
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig_exact(max_steps);
  Eigen::VectorXd exact_diag(max_steps), exact_sub(max_steps);
  // The first `size` rows of T into (diag, sub), divided by their largest entry, which is
  // returned (as Eigen's dense compute() scales, so the values are the same to the last bit).
  auto loadScaled = [&](int size, Eigen::VectorXd& diag, Eigen::VectorXd& sub) {
    double scale = 0.0;
    for (int i = 0; i < size; ++i) scale = std::max(scale, std::abs(alpha[i]));
    for (int i = 0; i + 1 < size; ++i) scale = std::max(scale, std::abs(beta[i]));
    if (scale == 0.0) scale = 1.0;
    diag.resize(size);
    sub.resize(size - 1);
    for (int i = 0; i < size; ++i) diag[i] = alpha[i] / scale;
    for (int i = 0; i + 1 < size; ++i) sub[i] = beta[i] / scale;
    return scale;
  };
  auto exactTheta = [&](int size) {
    if (size == 1) return alpha[0];
    const double scale = loadScaled(size, exact_diag, exact_sub);
    eig_exact.computeFromTridiagonal(exact_diag, exact_sub, Eigen::EigenvaluesOnly);
    return eig_exact.eigenvalues()[size - 1] * scale;
  };
  for (int j = 0; j < max_steps; ++j) {
    if (j == 0) Q.col(j) = q;  // later columns are written with q (below)
    apply(q, z);
    const double a = q.dot(z);
    alpha.push_back(a);
    // z -= a q, then z -= beta Q_{j-1}: the same operations per entry, in one pass.
    lanczosResidual(n3, z.data(), q.data(), a, j > 0 ? Q.col(j - 1).data() : nullptr, j > 0 ? beta.back() : 0.0,
                    avx2);
    if (reorthogonalise) {
      q_dot_z.head(j + 1).noalias() = Q.leftCols(j + 1).transpose() * z;
      q_proj.noalias() = Q.leftCols(j + 1) * q_dot_z.head(j + 1);
      z -= q_proj;
    }
    const double b = z.norm();
    const int size = j + 1;
    // T is tridiagonal already: solved as such (Eigen's dense compute() would reduce it by
    // Householder reflections that are all the identity here, O(size^3) per step). Scaled as
    // compute() scales (by its largest entry), so the values are the same to the last bit.
    const double scale = loadScaled(size, tri_diag, tri_sub);
    // Eigenvalues only until theta has settled: the Ritz vector (for the residual and the
    // mode) is needed only from then on.
    // Before first_needed, theta matters only to the breakdown test b <= 1e-14 |theta|; the
    // top eigenvalue of T is at most scale * max row sum of |T / scale| (Gershgorin), so when
    // b is above 1e-14 times that bound the test fails whatever theta is, and theta need not
    // be computed (it is never read: NaN in the history).
    bool need_theta = size == 1 || size >= first_needed || j + 1 == max_steps || decided != nullptr;
    if (!need_theta) {
      double row_max = 0.0;
      for (int i = 0; i < size; ++i) {
        const double row = std::abs(tri_diag[i]) + (i > 0 ? std::abs(tri_sub[i - 1]) : 0.0) +
                           (i + 1 < size ? std::abs(tri_sub[i]) : 0.0);
        row_max = std::max(row_max, row);
      }
      need_theta = !(b > 1e-14 * (2.0 * row_max * scale));  // 2x: room for round-off in the bound
    }
    theta_exact = true;
    if (size == 1) {
      theta = alpha[0];
      ritz = Eigen::VectorXd::Ones(1);
    } else if (need_theta) {
      // Newton's value: it only decides the tests below, which ask the dense solver's value
      // (as computed before) whenever it lies within 1e-9 of a threshold, so the decisions
      // are the dense solver's (the values differ by round-off, ~1e-15).
      theta = topTridiagonalEigenvalue(tri_diag, tri_sub) * scale;
      theta_exact = false;
      if (std::isnan(theta)) theta = exactTheta(size);
    } else {
      theta = std::numeric_limits<double>::quiet_NaN();
    }
    if (steps_taken) *steps_taken = size;
    // Converged: the top Ritz pair's residual is small (theta is near *an* eigenvalue) and
    // theta has stopped growing over the last steps (it rises towards the top one; near the
    // top the spectrum is dense, so a small residual alone can stop below it).
    history.push_back(theta);
    exact.push_back(theta_exact ? 1 : 0);
    auto makeExact = [&](size_t h) {
      if (!exact[h]) {
        history[h] = exactTheta(static_cast<int>(h) + 1);
        exact[h] = 1;
      }
    };
    bool settled = false;
    if (size > std::max(options.lanczos_min_steps, 5)) {
      const size_t back = history.size() - 6, now = history.size() - 1;
      const double margin = 1e-9 * std::abs(history[now]);
      const double gap = options.lanczos_tolerance * std::abs(history[now]) - (history[now] - history[back]);
      if (!(std::abs(gap) > margin)) {  // close (or NaN): as the dense solver's values decide
        makeExact(back);
        makeExact(now);
      }
      settled = history[now] - history[back] <= options.lanczos_tolerance * std::abs(history[now]);
    }
    if (!(b > 2e-14 * std::abs(history.back()))) makeExact(history.size() - 1);
    theta = history.back();
    // Decided: theta (exact or Newton's, within ~1e-15 of the dense solver's) less a 1e-9
    // margin is a lower bound of the value the full iteration would return.
    const bool last = b <= 1e-14 * std::abs(theta) || j + 1 == max_steps ||
                      (decided != nullptr && theta > 0.0 && (*decided)(theta * (1.0 - 1e-9)));
    if (settled || last) {
      if (size > 1) {
        eig.computeFromTridiagonal(tri_diag, tri_sub, Eigen::ComputeEigenvectors);
        theta = eig.eigenvalues()[size - 1] * scale;
        ritz = eig.eigenvectors().col(size - 1);
      }
      const double residual = b * std::abs(ritz[size - 1]);
      if ((residual <= options.lanczos_tolerance * std::abs(theta) && settled) || last) break;
    }
    beta.push_back(b);
    lanczosNext(n3, z.data(), b, q.data(), Q.col(j + 1).data(), avx2);  // q = z / b, and Q's next column
  }
  if (mode != nullptr) {
    const Eigen::VectorXd y = Q.leftCols(ritz.size()) * ritz;
    const double norm = y.norm();
    mode->setZero(m.num_nodes, 3);
    for (int k = 0; k < count; ++k)
      for (int c = 0; c < 3; ++c) (*mode)(nodes[k], c) = norm > 0 ? y[3 * k + c] / norm : 0.0;
  }
  return std::max(theta, 0.0);
}

// An upper bound of the top eigenvalue of M^-1/2 K M^-1/2 over the free nodes `nodes`, every
// other node held fixed (the matrix topEigenvalue estimates from below). With y = M^-1/2 u
// (zero at held nodes) and S_i = sum of k_s d_s d_s^T over the springs at node i,
//   u^T A u = sum_s k_s (d_s . (y_b - y_a))^2 <= sum_s 2 k_s ((d_s . y_a)^2 + (d_s . y_b)^2)
//           <= sum_i 2 y_i^T S_i y_i <= max_i (2 lambda_max(S_i) / m_i) |u|^2
// (a held end's term is dropped, which only lowers the middle sums). One pass over the
// springs of `nodes` (it stops once above `stop_above`); lambda_max(S_i) is taken from the
// closed form plus 1e-6 of the trace (its round-off stays far below that).
double topEigenvalueBound(const Model& m, const NodeSprings& st, const cutting::Positions& X,
                          const std::vector<int>& nodes, double stop_above) {
  double bound = 0.0;
  for (int i = 0; i < static_cast<int>(nodes.size()); ++i) {
    const int node = nodes[i];
    double s00 = 0, s11 = 0, s22 = 0, s01 = 0, s12 = 0, s20 = 0;
    for (int e = st.begin(node), e_end = st.end(node); e < e_end; ++e) {
      const int s = st.spring[e];
      const int a = st.a[s], b = st.b[s];
      const double dx = X(b, 0) - X(a, 0), dy = X(b, 1) - X(a, 1), dz = X(b, 2) - X(a, 2);
      const double len2 = dx * dx + dy * dy + dz * dz;
      if (!(len2 > 0.0)) return std::numeric_limits<double>::infinity();
      const double c = st.k[s] / len2;
      s00 += c * dx * dx;
      s11 += c * dy * dy;
      s22 += c * dz * dz;
      s01 += c * dx * dy;
      s12 += c * dy * dz;
      s20 += c * dz * dx;
    }
    const double trace = s00 + s11 + s22;
    if (!(trace > 0.0)) continue;
    if (2.0 * trace / m.mass[node] <= bound) continue;  // lambda_max(S) <= trace
    Eigen::Matrix3d S;
    S << s00, s01, s20, s01, s11, s12, s20, s12, s22;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(S, Eigen::EigenvaluesOnly);
    const double top = std::min(trace, eig.eigenvalues()[2] + 1e-6 * trace);
    bound = std::max(bound, 2.0 * top / m.mass[node]);
    if (bound > stop_above) return bound;  // decided: above
  }
  return bound;
}

// What the first part of the update (prepareUpdate) hands to the second (finishUpdate).
struct Prepared {
  struct Spring {
    int a, b;  // nodes of `after`
    double rest, k, c;
  };
  CutUpdate3DReport report;            // filled so far: masses, touched_nodes, springs_recomputed, omega_previous
  Eigen::VectorXd mass;                // #N of after
  std::vector<std::uint8_t> touched;   // #N of after: masses and springs between them recomputed
  std::vector<std::uint8_t> region;    // #N of after: touched and their rings (mass region)
  std::vector<Spring> springs;         // recomputed, in buildModel's order
};

// The first part: the cut mesh's masses and the springs between touched nodes, which do not
// depend on the nodes kept; the model is left as it is, so an error here changes nothing.
Status prepareUpdate(const Model& model, const cutting::TetMesh& before, const cutting::TetMesh& after,
                     const cutting::TopologyChange& change, const CutUpdate3DOptions& options, Prepared* prepared) {
  const auto start = std::chrono::steady_clock::now();
  const int N0 = before.numNodes(), N1 = after.numNodes(), T1 = after.numTets();
  if (model.num_nodes != N0 || model.mass.size() != N0) return Error{"updateModelAfterCut3D: the model is not the mesh's"};
  if (static_cast<int>(change.node_old_to_new.size()) != N0 || change.new_num_nodes != N1)
    return Error{"updateModelAfterCut3D: the change does not match the meshes"};
  const std::vector<std::int32_t>& o2n = change.node_old_to_new;
  CutUpdate3DReport& rep = prepared->report;
  rep.omega_previous = model.omega_max;
  const int T0 = before.numTets();
  if (static_cast<int>(change.element_old_to_new.size()) != T0)
    return Error{"updateModelAfterCut3D: the change's element map does not match the mesh"};

  // Touched nodes: their masses and the springs between them change.
  std::vector<std::uint8_t> touched(static_cast<size_t>(N1), 0);
  for (const cutting::NewNode& nn : change.new_nodes)
    if (nn.id >= 0 && nn.id < N1) touched[nn.id] = 1;
  for (int i : change.cut_nodes)
    if (i >= 0 && i < N1) touched[i] = 1;
  // Elements that are not an old element with the same nodes (added, or renumbered onto a
  // duplicate by the cut) touch their nodes, and so do the old elements they replace.
  const std::int32_t* after_col[4] = {after.T.col(0).data(), after.T.col(1).data(), after.T.col(2).data(),
                                       after.T.col(3).data()};
  const std::int32_t* before_col[4] = {before.T.col(0).data(), before.T.col(1).data(), before.T.col(2).data(),
                                        before.T.col(3).data()};
  {
    std::vector<int> old_of(static_cast<size_t>(T1), -1);
    for (int t = 0; t < T0; ++t) {
      const int u = change.element_old_to_new[t];
      if (u >= 0 && u < T1) old_of[u] = t;
    }
    auto touchTetHere = [&](int t) {
      for (int k = 0; k < 4; ++k) touched[after_col[k][t]] = 1;
    };
    auto touchOld = [&](int t) {
      for (int k = 0; k < 4; ++k) {
        const int j = o2n[before_col[k][t]];
        if (j >= 0) touched[j] = 1;
      }
    };
    for (int t = 0; t < T0; ++t)
      if (change.element_old_to_new[t] < 0) touchOld(t);
    auto compareElement = [&](int t) {
      const int o = old_of[t];
      if (o >= 0 && after_col[0][t] == o2n[before_col[0][o]] && after_col[1][t] == o2n[before_col[1][o]] &&
          after_col[2][t] == o2n[before_col[2][o]] && after_col[3][t] == o2n[before_col[3][o]])
        return;  // the same nodes in the same order: most elements
      bool same = o >= 0;
      if (same) {
        std::array<int, 4> a{}, b{};
        for (int k = 0; k < 4; ++k) {
          a[k] = after_col[k][t];
          b[k] = o2n[before_col[k][o]];
        }
        if (a != b) {  // the same nodes in another order are the same element
          std::sort(a.begin(), a.end());
          std::sort(b.begin(), b.end());
          same = a == b;
        }
      }
      if (!same) {
        touchTetHere(t);
        if (o >= 0) touchOld(o);
      }
    };
    if (model.options.simd && lanczosAvx2() && T1 > 0) {
      // The first test (same nodes in the same order) 4 elements at a time; the others as above.
      const std::unique_ptr<int[]> candidates(new int[static_cast<size_t>(T1)]);
      const int num_candidates =
          sameOrderCandidatesAvx2(T1, old_of.data(), after_col, before_col, o2n.data(), candidates.get());
      for (int i = 0; i < num_candidates; ++i) compareElement(candidates[i]);
    } else {
      for (int t = 0; t < T1; ++t) compareElement(t);
    }
  }

  // Material of each tet (written in full below: allocated without a fill).
  const std::unique_ptr<int[]> material_storage(new int[static_cast<size_t>(T1)]);
  int* const material = material_storage.get();
  for (int t = 0, last_label = 0, last = -1; t < T1; ++t) {
    if (last < 0 || after.material[t] != last_label) {  // runs of one label: look up at changes
      last_label = after.material[t];
      last = -1;
      for (int i = 0; i < static_cast<int>(model.materials.size()); ++i)
        if (model.materials[i].label == last_label) last = i;  // the last with the label, as before
    }
    material[t] = last;
    if (material[t] < 0)
      return Error{"tet " + std::to_string(t) + " has material label " + std::to_string(after.material[t]) +
                   " but the scene defines no material with that label"};
  }
  // Tets around each node (CSR).
  // (tv: the tets' nodes row by row, tv[4 t + k] = after.T(t, k), one cache line a tet for
  // the look-ups by tet below; `around` is written in full below: allocated without
  // zero-filling it first.)
  std::vector<int> off(static_cast<size_t>(N1) + 1, 0);
  const std::unique_ptr<int[]> around_storage(new int[4 * static_cast<size_t>(T1)]);
  const std::unique_ptr<std::int32_t[]> tv_storage(new std::int32_t[4 * static_cast<size_t>(T1)]);
  int* const around = around_storage.get();
  std::int32_t* const tv = tv_storage.get();
  {
    const std::int32_t* const c0 = after.T.col(0).data();
    const std::int32_t* const c1 = after.T.col(1).data();
    const std::int32_t* const c2 = after.T.col(2).data();
    const std::int32_t* const c3 = after.T.col(3).data();
    for (int t = 0; t < T1; ++t) {
      std::int32_t* const row = tv + 4 * static_cast<size_t>(t);
      row[0] = c0[t];
      row[1] = c1[t];
      row[2] = c2[t];
      row[3] = c3[t];
      for (int k = 0; k < 4; ++k) ++off[row[k]];
    }
  }
  auto node = [tv](int t, int k) { return tv[4 * static_cast<size_t>(t) + k]; };
  // Each node's number of tets at off[i], summed into the end of its entries; the tets then
  // taken backwards, each placed just below its node's last one: a node's tets in increasing
  // order, off[i] ending at their start (no cursor array copied).
  for (int i = 1; i < N1; ++i) off[i] += off[i - 1];
  if (N1 > 0) off[N1] = off[N1 - 1];
  for (int t = T1 - 1; t >= 0; --t)
    for (int k = 3; k >= 0; --k) around[--off[node(t, k)]] = t;
  std::vector<double> volume(static_cast<size_t>(T1), std::nan(""));
  auto computeVolume = [&](int t) {  // cutting::tetVolume's arithmetic, inlined
    const Eigen::Vector3d x0 = after.X.row(node(t, 0));
    const Eigen::Vector3d x1 = after.X.row(node(t, 1));
    const Eigen::Vector3d x2 = after.X.row(node(t, 2));
    const Eigen::Vector3d x3 = after.X.row(node(t, 3));
    return (x1 - x0).dot((x2 - x0).cross(x3 - x0)) / 6.0;
  };
  auto tetVolume = [&](int t) {
    if (std::isnan(volume[t])) volume[t] = computeVolume(t);
    return volume[t];
  };

  auto touchTet = [&](int t) {
    for (int k = 0; k < 4; ++k) touched[node(t, k)] = 1;
  };
  for (int t : change.added_elements)
    if (t >= 0 && t < T1) touchTet(t);
  for (int i : change.moved_nodes)
    if (i >= 0 && i < N1)
      for (int e = off[i]; e < off[i + 1]; ++e) touchTet(around[e]);  // their volumes changed
  std::vector<int> region_nodes;
  for (int i = 0; i < N1; ++i)
    if (touched[i]) region_nodes.push_back(i);
  rep.touched_nodes = static_cast<int>(region_nodes.size());
  for (int t : change.added_elements) {
    if (t >= 0 && t < T1 && !(tetVolume(t) > 0.0))
      return Error{"tet " + std::to_string(t) + " has non-positive volume " + std::to_string(tetVolume(t))};
  }
  // Mass region: the touched nodes and rings of neighbours (a cut's nodes lie near one
  // surface, where the second moments across it are badly conditioned).
  std::vector<std::uint8_t> region = touched;
  for (int ring = 0, begin = 0; ring < options.mass_rings; ++ring) {
    const int end = static_cast<int>(region_nodes.size());
    for (int r = begin; r < end; ++r)
      for (int e = off[region_nodes[r]]; e < off[region_nodes[r] + 1]; ++e)
        for (int k = 0; k < 4; ++k) {
          const int j = node(around[e], k);
          if (!region[j]) {
            region[j] = 1;
            region_nodes.push_back(j);
          }
        }
    begin = end;
  }

  // Masses: carried over outside the region; inside, lumped prior + smallest correction
  // keeping the moments of the old masses they replace.
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(N1);
  for (int i = 0; i < N0; ++i) {
    const int j = o2n[i];
    if (j >= 0 && !region[j]) mass[j] = model.mass[i];
  }
  std::vector<int> unknown;
  // Lumped priors: a quarter of each incident tet's mass, summed over a node's tets in
  // increasing order (one pass over the tets, each volume computed once).
  // A small region sums over its nodes' tet lists (increasing too: the same sums).
  auto lumpedShare = [&](int t) { return 0.25 * model.materials[material[t]].density_g_mm3 * std::abs(tetVolume(t)); };
  std::size_t region_incidences = 0;
  for (int j : region_nodes) region_incidences += static_cast<std::size_t>(off[j + 1] - off[j]);
  if (region_incidences < static_cast<std::size_t>(T1)) {
    for (int j : region_nodes)
      for (int e = off[j]; e < off[j + 1]; ++e) mass[j] += lumpedShare(around[e]);
  } else {
    for (int t = 0; t < T1; ++t) {
      const int n0 = node(t, 0), n1 = node(t, 1), n2 = node(t, 2), n3 = node(t, 3);
      if (!(region[n0] | region[n1] | region[n2] | region[n3])) continue;
      const double w = lumpedShare(t);
      if (region[n0]) mass[n0] += w;
      if (region[n1]) mass[n1] += w;
      if (region[n2]) mass[n2] += w;
      if (region[n3]) mass[n3] += w;
    }
  }
  for (int j : region_nodes)
    if (mass[j] > 0.0) unknown.push_back(j);
  if (!unknown.empty()) {
    Eigen::Vector3d lo = after.X.row(unknown[0]).transpose(), hi = lo;
    for (int j : unknown) {
      lo = lo.cwiseMin(after.X.row(j).transpose());
      hi = hi.cwiseMax(after.X.row(j).transpose());
    }
    const Eigen::Vector3d centre = 0.5 * (lo + hi);
    const double scale = std::max(0.5 * (hi - lo).maxCoeff(), 1e-12);
    Row10 target = Row10::Zero();
    for (int i = 0; i < N0; ++i) {
      const int j = o2n[i];
      if ((j < 0 || region[j]) && model.mass[i] != 0.0)
        target += model.mass[i] * monomials((before.X.row(i).transpose() - centre) / scale);
    }
    auto moments = [&](const Eigen::VectorXd& m) {
      Row10 p = Row10::Zero();
      for (int j : region_nodes)
        if (m[j] != 0.0) p += m[j] * monomials((after.X.row(j).transpose() - centre) / scale);
      return p;
    };
    const int clamped = correctMassMoments(after.X, unknown, target, centre, scale, options.masses, moments, mass);
    const Row10 res = target - moments(mass);
    rep.masses.unknowns = static_cast<int>(unknown.size());
    rep.masses.clamped = clamped;
    rep.masses.moment_residual = res.cwiseAbs().maxCoeff() / std::max(target.cwiseAbs().maxCoeff(), 1e-300);
  }
  for (int j : region_nodes)
    if (!(mass[j] >= 0.0 && std::isfinite(mass[j]))) return Error{"updateModelAfterCut3D: non-finite or negative mass"};
  // Springs: unchanged unless both ends are touched; edges between touched nodes anew.
  // The unchanged ones stay in the model's arrays (compacted in place by the second part,
  // once nothing can fail); prepared->springs collects the recomputed ones, which follow them.
  // Per touched node a in increasing order (the first entries of region_nodes), the edges
  // (a, b) to touched nodes b > a, in increasing b (buildModel's order), each summing its
  // tets in increasing order (as buildModel does): a's tet list is in increasing order, so
  // each b's sums are accumulated in that order, in a small table of a's neighbours (`slot`:
  // b -> entry, -1 otherwise).
  struct EdgeSum {
    int b;
    double ev, bev;
  };
  std::vector<EdgeSum> edge_sums;
  std::vector<int> slot(static_cast<size_t>(N1), -1);
  std::vector<Prepared::Spring>& springs = prepared->springs;
  springs.reserve(8 * static_cast<size_t>(rep.touched_nodes));  // about 7 edges a node towards higher-numbered ones
  for (int r = 0; r < rep.touched_nodes; ++r) {
    const int a = region_nodes[r];
    edge_sums.clear();
    for (int e = off[a]; e < off[a + 1]; ++e) {
      const int t = around[e];
      const Material* mat = nullptr;
      double vol = 0.0;
      for (int k = 0; k < 4; ++k) {
        const int b = node(t, k);
        if (b <= a || !touched[b]) continue;
        if (mat == nullptr) {
          vol = tetVolume(t);
          if (!(vol > 0.0)) return Error{"tet " + std::to_string(t) + " has non-positive volume " + std::to_string(vol)};
          mat = &model.materials[material[t]];
        }
        int& at = slot[b];
        if (at < 0) {
          at = static_cast<int>(edge_sums.size());
          edge_sums.push_back({b, 0.0, 0.0});
        }
        EdgeSum& sum = edge_sums[at];
        sum.ev += mat->young_modulus_pa * vol;
        sum.bev += mat->stiffness_damping_s * mat->young_modulus_pa * vol;
      }
    }
    for (const EdgeSum& sum : edge_sums) slot[sum.b] = -1;
    std::sort(edge_sums.begin(), edge_sums.end(), [](const EdgeSum& x, const EdgeSum& y) { return x.b < y.b; });
    for (const EdgeSum& sum : edge_sums) {
      const double len = (after.X.row(sum.b) - after.X.row(a)).norm();
      springs.push_back({a, sum.b, len, sum.ev / (len * len), sum.bev / (len * len)});
    }
  }
  rep.springs_recomputed = static_cast<int>(springs.size());
  prepared->mass = std::move(mass);
  prepared->touched = std::move(touched);
  prepared->region = std::move(region);
  rep.prepare_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return Status::Ok();
}

// The second part: drops the pieces cut free, renumbers, updates the model in place and
// estimates its stability.
Status finishUpdate(Model& model, const cutting::TetMesh& after, const cutting::TopologyChange& change,
                    const std::vector<std::uint8_t>& fixed_after, const std::vector<std::int32_t>& node_to_kept,
                    const CutUpdate3DOptions& options, Prepared& prepared, CutUpdate3DReport* report) {
  const int N0 = model.num_nodes, N1 = after.numNodes();
  if (static_cast<int>(fixed_after.size()) != N1) return Error{"updateModelAfterCut3D: fixed flags size differs from #N"};
  if (!node_to_kept.empty() && static_cast<int>(node_to_kept.size()) != N1)
    return Error{"updateModelAfterCut3D: node_to_kept size differs from #N"};
  const std::vector<std::int32_t>& o2n = change.node_old_to_new;
  CutUpdate3DReport& rep = prepared.report;
  const Eigen::VectorXd& mass = prepared.mass;
  const std::vector<std::uint8_t>& touched = prepared.touched;
  const std::vector<std::uint8_t>& region = prepared.region;
  const std::vector<Prepared::Spring>& springs = prepared.springs;

  // Pieces cut free leave; the rest is renumbered (order kept).
  std::vector<std::int32_t> keep(node_to_kept);
  if (keep.empty()) {
    keep.resize(static_cast<size_t>(N1));
    for (int i = 0; i < N1; ++i) keep[i] = i;
  }
  int N2 = 0;
  for (int i = 0; i < N1; ++i) N2 = std::max(N2, keep[i] + 1);
  Model& m = model;
  const Eigen::MatrixX3d& old_mode = m.stability_mode;  // replaced only by estimate() below
  double overlap = old_mode.rows() == N0 ? 0.0 : 1.0;
  if (old_mode.rows() == N0)
    for (int i = 0; i < N0; ++i) {
      const int j = o2n[i];
      if (j < 0 || region[j] || keep[j] < 0) overlap += old_mode.row(i).squaredNorm();
    }
  m.num_nodes = N2;
  m.mass = Eigen::VectorXd::Zero(N2);
  m.fixed.assign(static_cast<size_t>(N2), 0);
  std::vector<std::uint8_t> near(static_cast<size_t>(N2), 0);  // in the mass region
  for (int i = 0; i < N1; ++i) {
    const int j = keep[i];
    if (j < 0) continue;
    m.mass[j] = mass[i];
    m.fixed[j] = fixed_after[i] || !(mass[i] > 0.0);  // unused nodes never move
    near[j] = region[i];
  }
  m.inv_mass = Eigen::VectorXd::Zero(N2);
  for (int i = 0; i < N2; ++i)
    if (!m.fixed[i]) m.inv_mass[i] = 1.0 / m.mass[i];
  auto msSince = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
  };
  // The nodes of the stability estimate (below): near the cut, or all free nodes.
  // The previous mode near the cut: its estimate is held as a bound for the rest (see
  // tissue_update3d.hpp), for at most max_held_estimates updates in a row.
  const bool mode_near_cut = overlap > options.mode_overlap;
  const int held_before = m.stability_held;
  const bool can_hold = held_before >= 0 && held_before < options.max_held_estimates;
  rep.global_stability = !(rep.omega_previous > 0.0) || (mode_near_cut && !can_hold);
  std::vector<int> estimate_nodes;
  for (int i = 0; i < N2; ++i)
    if (!m.fixed[i] && (rep.global_stability || near[i])) estimate_nodes.push_back(i);
  rep.stability_nodes = static_cast<int>(estimate_nodes.size());
  const auto springs_start = std::chrono::steady_clock::now();
  // Unchanged springs, compacted in place (a row is read before any row at or above it is
  // written), then the recomputed ones: the order of a full copy.
  // Each old node's fate in one lookup per spring end: 2 * its kept index + (touched ? 1 : 0),
  // or -1 when it is gone (cut away or in a removed piece).
  const std::unique_ptr<std::int32_t[]> fate(new std::int32_t[static_cast<size_t>(std::max(N0, 1))]);
  for (int i = 0; i < N0; ++i) {
    const int j = o2n[i];
    fate[i] = j < 0 || keep[j] < 0 ? -1 : 2 * keep[j] + (touched[j] ? 1 : 0);
  }
  // The step's springs (those not between two anchored nodes) are counted along, per node
  // too, for fillStepSprings (buildStepSprings without its counting pass).
  m.step_springs.node_offset.assign(static_cast<size_t>(N2) + 1, 0);
  std::int32_t* const step_degree = m.step_springs.node_offset.data();
  const std::uint8_t* const fixed = m.fixed.data();
  int step_count = 0;
  auto countStep = [&](int a, int b) {
    if (fixed[a] && fixed[b]) return;
    ++step_count;
    ++step_degree[a];
    ++step_degree[b];
  };
  Eigen::Index out = 0;
  {
    std::int32_t* const sa = m.springs.col(0).data();
    std::int32_t* const sb = m.springs.col(1).data();
    double* const rest = m.rest_length.data();
    double* const stiffness = m.stiffness.data();
    double* const damping = m.damping.data();
    for (Eigen::Index s = 0, rows = m.springs.rows(); s < rows; ++s) {
      const std::int32_t fa = fate[sa[s]], fb = fate[sb[s]];
      if ((fa | fb) < 0 || (fa & fb & 1)) continue;  // an end gone, or both touched (recomputed)
      const int a = fa >> 1, b = fb >> 1;
      sa[out] = a;
      sb[out] = b;
      rest[out] = rest[s];
      stiffness[out] = stiffness[s];
      damping[out] = damping[s];
      ++out;
      countStep(a, b);
    }
  }
  Eigen::Index ns = out;
  for (const Prepared::Spring& s : springs) ns += (keep[s.a] >= 0 && keep[s.b] >= 0) ? 1 : 0;
  m.springs.conservativeResize(ns, 2);
  m.rest_length.conservativeResize(ns);
  m.stiffness.conservativeResize(ns);
  m.damping.conservativeResize(ns);
  for (int s = 0; s < static_cast<int>(springs.size()); ++s) {
    const Prepared::Spring& sp = springs[s];
    if (keep[sp.a] < 0 || keep[sp.b] < 0) continue;
    m.springs(out, 0) = keep[sp.a];
    m.springs(out, 1) = keep[sp.b];
    m.rest_length[out] = sp.rest;
    m.stiffness[out] = sp.k;
    m.damping[out] = sp.c;
    ++out;
    countStep(keep[sp.a], keep[sp.b]);
  }
  fillStepSprings(m, step_count);
  const NodeSprings node_springs = NodeSprings::of(m.step_springs);
  rep.springs_ms = msSince(springs_start);
  cutting::Positions X(N2, 3);
  for (int i = 0; i < N1; ++i)
    if (keep[i] >= 0) X.row(keep[i]) = after.X.row(i);
  Eigen::MatrixX3d mapped_mode = Eigen::MatrixX3d::Zero(N2, 3);
  if (old_mode.rows() == N0)
    for (int i = 0; i < N0; ++i) {
      const int j = o2n[i];
      if (j >= 0 && keep[j] >= 0 && !m.fixed[keep[j]]) mapped_mode.row(keep[j]) = old_mode.row(i);
    }

  // Stability: near the cut, combined with the previous estimate when its mode lies
  // elsewhere; over all free nodes otherwise.
  const ModelOptions& opt = m.options;
  double beta_max = 0.0;
  for (const Material& mat : m.materials) beta_max = std::max(beta_max, mat.stiffness_damping_s);
  auto stabilityLimit = [&](double omega) {
    if (!(omega > 0.0)) return opt.dt;
    const double zeta = 0.5 * beta_max * omega;
    return 2.0 * (std::sqrt(1.0 + zeta * zeta) - zeta) / omega;
  };
  auto substepsFor = [&](double critical) {
    return std::max(1, static_cast<int>(std::ceil(opt.dt / (opt.stability_safety * critical))));
  };
  bool carried = false;  // omega_max is the previous estimate (scaling near the cut cannot lower it)
  auto carryPrevious = [&]() {
    m.omega_max = rep.omega_previous;
    m.stability_mode = mapped_mode;
    m.stability_held = mode_near_cut && held_before >= 0 ? held_before + 1 : held_before;
    rep.held_stability = mode_near_cut;
    carried = true;
    m.critical_dt = stabilityLimit(m.omega_max);
  };
  // Whether an estimate lambda (the top eigenvalue) leads to a round of mass scaling: its
  // own estimate (not the previous one carried) with more substeps than allowed. Monotone in
  // lambda (sqrt, the limit and substepsFor are), so topEigenvalue may stop once its Ritz
  // value shows it: the round that follows replaces everything that estimate sets.
  const bool may_scale = massScalingApplies(opt);
  const std::function<bool(double)> scaling_follows = [&](double lambda) {
    const double omega = std::sqrt(lambda);
    if (!rep.global_stability && !(omega >= rep.omega_previous)) return false;  // carried
    return substepsFor(stabilityLimit(omega)) > opt.max_substeps;
  };
  LanczosScratch lanczos;
  auto estimate = [&](bool round_may_follow) {
    if (!rep.global_stability) {
      // Near the cut, an upper bound below the previous estimate settles what a Lanczos
      // estimate (a lower one) would: the previous estimate is carried over.
      const double bound = topEigenvalueBound(m, node_springs, X, estimate_nodes, rep.omega_previous * rep.omega_previous);
      if (bound * (1.0 + 1e-9) < rep.omega_previous * rep.omega_previous) {
        rep.omega_local = std::sqrt(bound);
        carryPrevious();
        return;
      }
    }
    Eigen::MatrixX3d ritz;
    int steps = 0;
    const bool stop_early = options.stop_decided_estimates && may_scale && round_may_follow;
    const double lambda = topEigenvalue(m, node_springs, X, estimate_nodes, rep.global_stability ? &mapped_mode : nullptr, options,
                                        &ritz, &steps, stop_early ? &scaling_follows : nullptr, lanczos);
    rep.lanczos_steps += steps;
    rep.omega_local = std::sqrt(lambda);
    if (rep.global_stability || rep.omega_local >= rep.omega_previous) {
      // A Lanczos estimate of its own (near the cut it is above every bound carried over).
      m.omega_max = rep.omega_local;
      m.stability_mode = std::move(ritz);
      // The rest of the mesh stays bounded by the previous estimate if that was one.
      m.stability_held = rep.global_stability || held_before >= 0 ? 0 : -1;
      rep.held_stability = false;
      carried = false;
      m.critical_dt = stabilityLimit(m.omega_max);
    } else {
      carryPrevious();
    }
  };
  const auto stability_start = std::chrono::steady_clock::now();
  estimate(true);
  // Selective mass scaling, as buildModel, on the nodes of the estimate.
  // A carried-over previous estimate is not lowered by mass near the cut: no rounds then.
  if (massScalingApplies(opt) && substepsFor(m.critical_dt) > opt.max_substeps && !carried) {
    const StepSprings& st = m.step_springs;
    double target = 0.8 * 2.0 * opt.stability_safety * opt.max_substeps / opt.dt;
    for (int round = 0; round < 4 && substepsFor(m.critical_dt) > opt.max_substeps && !carried; ++round) {
      for (int i : estimate_nodes) {
        double k_sum = 0.0;
        for (int e = st.node_offset[i]; e < st.node_offset[i + 1]; ++e) k_sum += st.stiffness[st.incident[e]];
        const double needed = 2.0 * k_sum / (target * target);
        if (m.mass[i] < needed) {
          m.added_mass += needed - m.mass[i];
          m.mass[i] = needed;
          m.inv_mass[i] = 1.0 / needed;
        }
      }
      estimate(round + 1 < 4);
      target *= 0.7;
    }
  }
  rep.stability_ms = msSince(stability_start);
  setSubsteps(m, substepsFor(m.critical_dt));
  // Only the implicit integrator holds a factorisation; XPBD and symplectic Euler read the
  // spring arrays directly, so the update above is all they need.
  m.implicit.reset();
  if (opt.integrator == Integrator::ImplicitEuler) {
    auto solver = ImplicitSolver::create(m);
    if (!solver.ok()) return Error{solver.error()};
    m.implicit = std::move(solver.value());
  }
  if (report) *report = rep;
  return Status::Ok();
}

}  // namespace

Status updateModelAfterCut3D(Model& model, const cutting::TetMesh& before, const cutting::TetMesh& after,
                             const cutting::TopologyChange& change, const std::vector<std::uint8_t>& fixed_after,
                             const std::vector<std::int32_t>& node_to_kept, const CutUpdate3DOptions& options,
                             CutUpdate3DReport* report) {
  Prepared prepared;  // (the first part leaves the model as it is)
  const Status first = prepareUpdate(model, before, after, change, options, &prepared);
  if (!first.ok()) return first;
  return finishUpdate(model, after, change, fixed_after, node_to_kept, options, prepared, report);
}

}  // namespace hysim::sim
