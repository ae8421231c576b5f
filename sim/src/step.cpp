// The fixed step. Nothing here allocates: every buffer is sized when the model is built.
#include <cmath>

#include "hysim/sim/model.hpp"
#include "implicit_solver.hpp"

namespace hysim::sim {
namespace {

// Force of every step spring on its a end (F_b = -F_a), from positions and velocities.
// The loop has no scatter, so it vectorises: compiled twice, for baseline x86-64 and for
// AVX2 (gathers, 4 springs at a time), the AVX2 one used where the CPU has it. Both give
// bit-identical results: only IEEE-exact operations, no FMA (ISO C++ mode keeps
// contraction off and the AVX2 build does not enable FMA). A test checks this.
[[gnu::always_inline]] inline void springForcesBody(int count, const std::int32_t* __restrict sa,
                                                    const std::int32_t* __restrict sb, const double* __restrict rest,
                                                    const double* __restrict stiffness,
                                                    const double* __restrict damping, const double* __restrict X,
                                                    const double* __restrict V, double* __restrict fx,
                                                    double* __restrict fy, double* __restrict fz) {
  for (int s = 0; s < count; ++s) {
    const int a = 3 * sa[s], b = 3 * sb[s];  // row-major #N x 3
    const double dx = X[b] - X[a], dy = X[b + 1] - X[a + 1], dz = X[b + 2] - X[a + 2];
    // + 1e-300 keeps a zero-length spring finite (direction 0) without a branch.
    const double len = std::sqrt(dx * dx + dy * dy + dz * dz + 1e-300);
    const double inv = 1.0 / len;
    const double ux = dx * inv, uy = dy * inv, uz = dz * inv;
    const double rel = (V[b] - V[a]) * ux + (V[b + 1] - V[a + 1]) * uy + (V[b + 2] - V[a + 2]) * uz;
    const double mag = stiffness[s] * (len - rest[s]) + damping[s] * rel;
    fx[s] = mag * ux;
    fy[s] = mag * uy;
    fz[s] = mag * uz;
  }
}

#define HYSIM_SPRING_ARGS                                                                                    \
  int count, const std::int32_t *sa, const std::int32_t *sb, const double *rest, const double *stiffness, \
      const double *damping, const double *X, const double *V, double *fx, double *fy, double *fz
void springForcesBaseline(HYSIM_SPRING_ARGS) { springForcesBody(count, sa, sb, rest, stiffness, damping, X, V, fx, fy, fz); }
[[gnu::target("avx2")]] void springForcesAvx2(HYSIM_SPRING_ARGS) {
  springForcesBody(count, sa, sb, rest, stiffness, damping, X, V, fx, fy, fz);
}
#undef HYSIM_SPRING_ARGS

bool cpuHasAvx2() {
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
}

// f = gravity + external + spring and spring-damping forces (free nodes only: anchored
// nodes never move, their forces are not needed).
void accumulateForces(const Model& m, const NodeVectors& x, const NodeVectors& v, const StepInput& in,
                      State& s) {
  const StepSprings& st = m.step_springs;
  Eigen::MatrixX3d& sf = s.spring_force;
  auto* spring_forces = (m.options.simd && cpuHasAvx2()) ? springForcesAvx2 : springForcesBaseline;
  spring_forces(st.size(), st.a.data(), st.b.data(), st.rest_length.data(), st.stiffness.data(), st.damping.data(),
               x.data(), v.data(), sf.col(0).data(), sf.col(1).data(), sf.col(2).data());
  const double* fx = sf.col(0).data();
  const double* fy = sf.col(1).data();
  const double* fz = sf.col(2).data();
  const Eigen::Vector3d& g = m.options.gravity;
  const double* ext = in.external_force != nullptr ? in.external_force->data() : nullptr;
  double* F = s.f.data();
  for (int i = 0; i < m.num_nodes; ++i) {
    if (m.fixed[i]) continue;
    double f0 = m.mass[i] * g[0], f1 = m.mass[i] * g[1], f2 = m.mass[i] * g[2];
    if (ext != nullptr) {
      f0 += ext[3 * i];
      f1 += ext[3 * i + 1];
      f2 += ext[3 * i + 2];
    }
    for (int e = st.node_offset[i]; e < st.node_offset[i + 1]; ++e) {
      const int k = st.incident[e];
      const double sign = st.sign[e];
      f0 += sign * fx[k];
      f1 += sign * fy[k];
      f2 += sign * fz[k];
    }
    F[3 * i] = f0;
    F[3 * i + 1] = f1;
    F[3 * i + 2] = f2;
  }
}

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
  const int n = m.num_nodes;
  for (int sub = 0; sub < m.substeps; ++sub) {
    if (in.refresh_external != nullptr) in.refresh_external(in.context, s.x, s.v);
    accumulateForces(m, s.x, s.v, in, s);
    double* v = s.v.data();
    double* x = s.x.data();
    const double* f = s.f.data();
    const double* im = m.inv_mass.data();
    for (int i = 0; i < n; ++i) {
      const double hm = h * im[i];  // fixed nodes: inv_mass 0, so v stays 0
      for (int c = 3 * i; c < 3 * i + 3; ++c) {
        v[c] = (v[c] + hm * f[c]) * drag;
        x[c] += h * v[c];
      }
    }
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
  } else {
    stepSymplecticEuler(model, state, input);
  }
  ++state.steps;
  state.time = static_cast<double>(state.steps) * model.options.dt;
  checkHealth(model, state);
}

}  // namespace hysim::sim
