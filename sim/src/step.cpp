// The fixed step. Nothing here allocates: every buffer is sized when the model is built.
#include <immintrin.h>

#include <cmath>
#include <cstddef>

#include "hysim/sim/model.hpp"
#include "implicit_solver.hpp"
#include "model_internal.hpp"

namespace hysim::sim {
namespace {

// Force of every step spring on its a end (F_b = -F_a), from positions and velocities, as
// rows (x, y, z, 0) of F. Compiled for baseline x86-64 (one spring at a time) and, by hand,
// for AVX2 (4 springs at a time: their node rows loaded by 16- and 8-byte loads and
// unpacked, which beats vgatherdpd here; the four results unpacked into rows), the AVX2 one
// used where the CPU has it. Both give bit-identical results: the same IEEE-exact operations
// in the same order, no FMA (ISO C++ mode keeps contraction off and the AVX2 build does not
// enable FMA). A test checks this.
[[gnu::always_inline]] inline void springForceOne(int s, const std::int32_t* __restrict sa,
                                                  const std::int32_t* __restrict sb, const double* __restrict rest,
                                                  const double* __restrict stiffness,
                                                  const double* __restrict damping, const double* __restrict X,
                                                  const double* __restrict V, double* __restrict F) {
  const int a = 3 * sa[s], b = 3 * sb[s];  // row-major #N x 3
  const double dx = X[b] - X[a], dy = X[b + 1] - X[a + 1], dz = X[b + 2] - X[a + 2];
  // + 1e-300 keeps a zero-length spring finite (direction 0) without a branch.
  const double len = std::sqrt(dx * dx + dy * dy + dz * dz + 1e-300);
  const double inv = 1.0 / len;
  const double ux = dx * inv, uy = dy * inv, uz = dz * inv;
  const double rel = (V[b] - V[a]) * ux + (V[b + 1] - V[a + 1]) * uy + (V[b + 2] - V[a + 2]) * uz;
  const double mag = stiffness[s] * (len - rest[s]) + damping[s] * rel;
  double* row = F + 4 * static_cast<std::ptrdiff_t>(s);
  row[0] = mag * ux;
  row[1] = mag * uy;
  row[2] = mag * uz;
  row[3] = 0.0;
}

#define HYSIM_SPRING_ARGS                                                                                    \
  int count, const std::int32_t *__restrict sa, const std::int32_t *__restrict sb, const double *__restrict rest, \
      const double *__restrict stiffness, const double *__restrict damping, const double *__restrict X,           \
      const double *__restrict V, double *__restrict F
void springForcesBaseline(HYSIM_SPRING_ARGS) {
  for (int s = 0; s < count; ++s) springForceOne(s, sa, sb, rest, stiffness, damping, X, V, F);
}
// Four doubles from base[idx[0..3]] by scalar loads and inserts.
[[gnu::target("avx2"), gnu::always_inline]] inline __m256d gather4(const double* base, const std::ptrdiff_t* idx) {
  return _mm256_setr_pd(base[idx[0]], base[idx[1]], base[idx[2]], base[idx[3]]);
}
// Rows base[idx[j] .. idx[j] + 2] of four springs as (x0..x3), (y0..y3), (z0..z3): x and y by
// 16-byte loads and two unpacks, z by gather4.
[[gnu::target("avx2"), gnu::always_inline]] inline void gatherRows(const double* base, const std::ptrdiff_t* idx,
                                                                  __m256d& x, __m256d& y, __m256d& z) {
  const __m256d r02 =
      _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(base + idx[0])), _mm_loadu_pd(base + idx[2]), 1);
  const __m256d r13 =
      _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(base + idx[1])), _mm_loadu_pd(base + idx[3]), 1);
  x = _mm256_unpacklo_pd(r02, r13);
  y = _mm256_unpackhi_pd(r02, r13);
  z = gather4(base + 2, idx);
}
[[gnu::target("avx2")]] void springForcesAvx2(HYSIM_SPRING_ARGS) {
  int s = 0;
  const __m256d tiny = _mm256_set1_pd(1e-300), one = _mm256_set1_pd(1.0), zero = _mm256_setzero_pd();
  for (; s + 4 <= count; s += 4) {
    const std::ptrdiff_t ia[4] = {3 * sa[s], 3 * sa[s + 1], 3 * sa[s + 2], 3 * sa[s + 3]};
    const std::ptrdiff_t ib[4] = {3 * sb[s], 3 * sb[s + 1], 3 * sb[s + 2], 3 * sb[s + 3]};
    __m256d xa, ya, za, xb, yb, zb;
    gatherRows(X, ia, xa, ya, za);
    gatherRows(X, ib, xb, yb, zb);
    const __m256d dx = _mm256_sub_pd(xb, xa), dy = _mm256_sub_pd(yb, ya), dz = _mm256_sub_pd(zb, za);
    const __m256d len2 = _mm256_add_pd(
        _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz)), tiny);
    const __m256d len = _mm256_sqrt_pd(len2);
    const __m256d inv = _mm256_div_pd(one, len);
    const __m256d ux = _mm256_mul_pd(dx, inv), uy = _mm256_mul_pd(dy, inv), uz = _mm256_mul_pd(dz, inv);
    gatherRows(V, ia, xa, ya, za);
    gatherRows(V, ib, xb, yb, zb);
    const __m256d vx = _mm256_sub_pd(xb, xa), vy = _mm256_sub_pd(yb, ya), vz = _mm256_sub_pd(zb, za);
    const __m256d rel =
        _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(vx, ux), _mm256_mul_pd(vy, uy)), _mm256_mul_pd(vz, uz));
    const __m256d mag =
        _mm256_add_pd(_mm256_mul_pd(_mm256_loadu_pd(stiffness + s), _mm256_sub_pd(len, _mm256_loadu_pd(rest + s))),
                      _mm256_mul_pd(_mm256_loadu_pd(damping + s), rel));
    const __m256d fx = _mm256_mul_pd(mag, ux), fy = _mm256_mul_pd(mag, uy), fz = _mm256_mul_pd(mag, uz);
    // (fx, fy, fz) of springs s..s+3 into rows (fx_i, fy_i, fz_i, 0).
    const __m256d t0 = _mm256_unpacklo_pd(fx, fy), t1 = _mm256_unpackhi_pd(fx, fy);  // s, s+2 | s+1, s+3
    const __m256d t2 = _mm256_unpacklo_pd(fz, zero), t3 = _mm256_unpackhi_pd(fz, zero);
    double* row = F + 4 * static_cast<std::ptrdiff_t>(s);
    _mm_store_pd(row, _mm256_castpd256_pd128(t0));
    _mm_store_pd(row + 2, _mm256_castpd256_pd128(t2));
    _mm_store_pd(row + 4, _mm256_castpd256_pd128(t1));
    _mm_store_pd(row + 6, _mm256_castpd256_pd128(t3));
    _mm_store_pd(row + 8, _mm256_extractf128_pd(t0, 1));
    _mm_store_pd(row + 10, _mm256_extractf128_pd(t2, 1));
    _mm_store_pd(row + 12, _mm256_extractf128_pd(t1, 1));
    _mm_store_pd(row + 14, _mm256_extractf128_pd(t3, 1));
  }
  for (; s < count; ++s) springForceOne(s, sa, sb, rest, stiffness, damping, X, V, F);
}
#undef HYSIM_SPRING_ARGS

bool cpuHasAvx2() {
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
}

bool useAvx2(const Model& m) { return m.options.simd && cpuHasAvx2(); }

void springForces(const Model& m, const NodeVectors& x, const NodeVectors& v, State& s) {
  const StepSprings& st = m.step_springs;
  auto* spring_forces = useAvx2(m) ? springForcesAvx2 : springForcesBaseline;
  spring_forces(st.size(), st.a.data(), st.b.data(), st.rest_length.data(), st.stiffness.data(), st.damping.data(),
                x.data(), v.data(), s.spring_force.data());
}

// One substep's forces and update, node by node: f = gravity + external + the spring and
// spring-damping forces (free nodes; anchored nodes never move, their f is 0), then
// v = (v + h f / m) * drag and x += h v. A node's update reads only the spring forces (from
// the positions before the substep) and its own rows, so updating node by node is the same as
// summing every force first. The AVX2 version sums the rows (x, y, z, 0) in one register, the
// same additions in the same order.
// Node row c's force, then v = (v + hm f) * drag and x += h v.
[[gnu::always_inline]] inline void advanceNode(int c, double f0, double f1, double f2, double hm, double h, double drag,
                                               double* __restrict x, double* __restrict v, double* __restrict f) {
  f[c] = f0;
  f[c + 1] = f1;
  f[c + 2] = f2;
  v[c] = (v[c] + hm * f0) * drag;
  v[c + 1] = (v[c + 1] + hm * f1) * drag;
  v[c + 2] = (v[c + 2] + hm * f2) * drag;
  x[c] += h * v[c];
  x[c + 1] += h * v[c + 1];
  x[c + 2] += h * v[c + 2];
}

#define HYSIM_UPDATE_ARGS                                                                                        \
  const Model &m, const double *__restrict ext, double h, double drag, const double *__restrict F, double *__restrict x, \
      double *__restrict v, double *__restrict f
void integrateBaseline(HYSIM_UPDATE_ARGS) {
  const StepSprings& st = m.step_springs;
  const Eigen::Vector3d& g = m.options.gravity;
  const double* im = m.inv_mass.data();
  for (int i = 0; i < m.num_nodes; ++i) {
    double f0 = 0.0, f1 = 0.0, f2 = 0.0;
    if (!m.fixed[i]) {
      f0 = m.mass[i] * g[0];
      f1 = m.mass[i] * g[1];
      f2 = m.mass[i] * g[2];
      if (ext != nullptr) {
        f0 += ext[3 * i];
        f1 += ext[3 * i + 1];
        f2 += ext[3 * i + 2];
      }
      for (int e = st.node_offset[i]; e < st.node_offset[i + 1]; ++e) {
        const double* row = F + 4 * static_cast<std::ptrdiff_t>(st.incident[e]);
        const double sign = st.sign[e];
        f0 += sign * row[0];
        f1 += sign * row[1];
        f2 += sign * row[2];
      }
    }
    advanceNode(3 * i, f0, f1, f2, h * im[i], h, drag, x, v, f);  // fixed nodes: inv_mass 0, v stays 0
  }
}
[[gnu::target("avx2")]] void integrateAvx2(HYSIM_UPDATE_ARGS) {
  const StepSprings& st = m.step_springs;
  const Eigen::Vector3d& g = m.options.gravity;
  const __m256d gv = _mm256_setr_pd(g[0], g[1], g[2], 0.0);
  const double* im = m.inv_mass.data();
  const std::int32_t* off = st.node_offset.data();
  const std::int32_t* incident = st.incident.data();
  const double* sign = st.sign.data();
  alignas(32) double sum[4];
  for (int i = 0; i < m.num_nodes; ++i) {
    __m256d acc = _mm256_setzero_pd();
    if (!m.fixed[i]) {
      acc = _mm256_mul_pd(_mm256_set1_pd(m.mass[i]), gv);
      if (ext != nullptr) acc = _mm256_add_pd(acc, _mm256_setr_pd(ext[3 * i], ext[3 * i + 1], ext[3 * i + 2], 0.0));
      for (int e = off[i]; e < off[i + 1]; ++e) {
        const __m256d row = _mm256_load_pd(F + 4 * static_cast<std::ptrdiff_t>(incident[e]));
        acc = _mm256_add_pd(acc, _mm256_mul_pd(_mm256_set1_pd(sign[e]), row));
      }
    }
    _mm256_store_pd(sum, acc);
    advanceNode(3 * i, sum[0], sum[1], sum[2], h * im[i], h, drag, x, v, f);
  }
}
#undef HYSIM_UPDATE_ARGS

// Counts a warning and freezes the state when anything became non-finite or too fast.
bool checkHealth(const Model& m, State& s) {
  const double vmax2 = m.options.max_speed_mm_s * m.options.max_speed_mm_s;
  for (int i = 0; i < m.num_nodes; ++i) {
    const double v2 = s.v.row(i).squaredNorm();
    if (!(v2 <= vmax2) || !std::isfinite(s.x(i, 0) + s.x(i, 1) + s.x(i, 2))) {
      s.diverged = true;
      ++s.warnings;
      return false;
    }
  }
  return true;
}

void stepSymplecticEuler(const Model& m, State& s, const StepInput& in) {
  const double h = m.substep;
  const double drag = 1.0 / (1.0 + h * m.options.drag_per_s);  // implicit drag: stable for any h
  auto* integrate = useAvx2(m) ? integrateAvx2 : integrateBaseline;
  for (int sub = 0; sub < m.substeps; ++sub) {
    if (in.refresh_external != nullptr) in.refresh_external(in.context, s.x, s.v);
    springForces(m, s.x, s.v, s);
    integrate(m, in.external_force != nullptr ? in.external_force->data() : nullptr, h, drag, s.spring_force.data(),
              s.x.data(), s.v.data(), s.f.data());
  }
}

void stepImplicitEuler(const Model& m, State& s, const StepInput& in) {
  const ImplicitSolver& solver = *m.implicit;
  const double h = m.options.dt;
  const int n = m.num_nodes;
  const int nf = solver.numFree();
  const std::vector<int>& free_nodes = solver.freeNodes();
  NodeVectors& x0 = s.scratch0;    // x_n
  NodeVectors& base = s.scratch1;  // constant part of the right-hand side (full #N rows)
  x0 = s.x;
  if (in.refresh_external != nullptr) in.refresh_external(in.context, s.x, s.v);
  const double alpha = m.options.drag_per_s;
  const Eigen::Vector3d& g = m.options.gravity;

  // base = M y / h^2 + alpha M x_n / h + L_c x_n / h, with y = x_n + h v_n + h^2 (g + f_ext/m)
  for (int i = 0; i < n; ++i) {
    Eigen::RowVector3d acc = g.transpose();
    if (in.external_force != nullptr && m.inv_mass[i] > 0.0) acc += in.external_force->row(i) * m.inv_mass[i];
    const Eigen::RowVector3d y = x0.row(i) + h * s.v.row(i) + h * h * acc;
    base.row(i) = m.mass[i] * (y / (h * h) + alpha * x0.row(i) / h);
  }
  for (int sp = 0; sp < m.springs.rows(); ++sp) {
    const int a = m.springs(sp, 0), b = m.springs(sp, 1);
    const Eigen::RowVector3d d = (m.damping[sp] / h) * (x0.row(a) - x0.row(b));
    base.row(a) += d;
    base.row(b) -= d;
  }
  // Initial guess: inertial prediction.
  for (int i = 0; i < n; ++i) {
    if (m.fixed[i]) continue;
    s.x.row(i) = x0.row(i) + h * s.v.row(i);
  }
  for (int it = 0; it < m.options.implicit_iterations; ++it) {
    // Local step: projected spring directions, accumulated into f (full rows).
    s.f = base;
    for (int sp = 0; sp < m.springs.rows(); ++sp) {
      const int a = m.springs(sp, 0), b = m.springs(sp, 1);
      Eigen::RowVector3d d = s.x.row(a) - s.x.row(b);
      const double len = d.norm();
      if (len > 0.0) d *= m.rest_length[sp] / len;
      const Eigen::RowVector3d kd = m.stiffness[sp] * d;
      s.f.row(a) += kd;
      s.f.row(b) -= kd;
    }
    // Global step over free nodes.
    auto rhs = s.solve0.topRows(nf);
    for (int k = 0; k < nf; ++k) rhs.row(k) = s.f.row(free_nodes[k]);
    for (const ImplicitSolver::FixedLink& link : solver.fixedLinks()) rhs.row(link.free) += link.w * s.x.row(link.node);
    auto tmp = s.solve1.topRows(nf);
    solver.solveInPlace(rhs, tmp);
    for (int k = 0; k < nf; ++k) s.x.row(free_nodes[k]) = rhs.row(k);
  }
  for (int i = 0; i < n; ++i) {
    if (m.fixed[i]) continue;
    s.v.row(i) = (s.x.row(i) - x0.row(i)) / h;
  }
}

}  // namespace

Result<std::shared_ptr<const ImplicitSolver>> ImplicitSolver::create(const Model& m) {
  auto solver = std::make_shared<ImplicitSolver>();
  const int n = m.num_nodes;
  const double h = m.options.dt;
  solver->free_index_.assign(n, -1);
  for (int i = 0; i < n; ++i) {
    if (!m.fixed[i]) {
      solver->free_index_[i] = static_cast<int>(solver->free_nodes_.size());
      solver->free_nodes_.push_back(i);
    }
  }
  const int nf = solver->numFree();
  solver->mass_scale_ = 1.0 / (h * h) + m.options.drag_per_s / h;
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(static_cast<size_t>(nf) + 4 * m.springs.rows());
  for (int k = 0; k < nf; ++k) trip.emplace_back(k, k, solver->mass_scale_ * m.mass[solver->free_nodes_[k]]);
  for (int sp = 0; sp < m.springs.rows(); ++sp) {
    const int a = m.springs(sp, 0), b = m.springs(sp, 1);
    const double w = m.stiffness[sp] + m.damping[sp] / h;
    const int fa = solver->free_index_[a], fb = solver->free_index_[b];
    if (fa >= 0) trip.emplace_back(fa, fa, w);
    if (fb >= 0) trip.emplace_back(fb, fb, w);
    if (fa >= 0 && fb >= 0) {
      trip.emplace_back(fa, fb, -w);
      trip.emplace_back(fb, fa, -w);
    } else if (fa >= 0) {
      solver->fixed_links_.push_back({fa, b, w});
    } else if (fb >= 0) {
      solver->fixed_links_.push_back({fb, a, w});
    }
  }
  Eigen::SparseMatrix<double> A(nf, nf);
  A.setFromTriplets(trip.begin(), trip.end());
  solver->ldlt_.compute(A);
  if (solver->ldlt_.info() != Eigen::Success) return Error{"implicit integrator: factorisation failed"};
  solver->inv_diag_ = solver->ldlt_.vectorD().cwiseInverse();
  return std::shared_ptr<const ImplicitSolver>(std::move(solver));
}

void step(const Model& model, State& state, const StepInput& input) {
  if (state.diverged) return;
  if (model.options.integrator == Integrator::ImplicitEuler && model.implicit) {
    stepImplicitEuler(model, state, input);
  } else if (model.options.integrator == Integrator::Xpbd) {
    stepXpbd(model, state, input);
  } else {
    stepSymplecticEuler(model, state, input);
  }
  ++state.steps;
  state.time = static_cast<double>(state.steps) * model.options.dt;
  checkHealth(model, state);
}

}  // namespace hysim::sim
