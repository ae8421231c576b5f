// The fixed step. Nothing here allocates: every buffer is sized when the model is built.
#include <cmath>

#include "hysim/sim/model.hpp"
#include "implicit_solver.hpp"

namespace hysim::sim {
namespace {

// f = gravity + external + spring and spring-damping forces.
void accumulateForces(const Model& m, const NodeVectors& x, const NodeVectors& v, const StepInput& in,
                      NodeVectors& f) {
  const int n = m.num_nodes;
  const Eigen::RowVector3d g = m.options.gravity.transpose();
  if (in.external_force != nullptr) {
    for (int i = 0; i < n; ++i) f.row(i) = m.mass[i] * g + in.external_force->row(i);
  } else {
    for (int i = 0; i < n; ++i) f.row(i) = m.mass[i] * g;
  }
  const double* X = x.data();  // row-major: node i at X[3i .. 3i+2]
  const double* V = v.data();
  double* F = f.data();
  // Springs are sorted by their first node: the force on it is summed in registers over its
  // run of springs and stored once, which breaks the store-to-load chain through F[a].
  const PackedSpring* sp = m.packed.data();
  const PackedSpring* const end = sp + m.packed.size();
  while (sp != end) {
    const int a = sp->a;
    const double xa0 = X[3 * a], xa1 = X[3 * a + 1], xa2 = X[3 * a + 2];
    const double va0 = V[3 * a], va1 = V[3 * a + 1], va2 = V[3 * a + 2];
    double fa0 = 0.0, fa1 = 0.0, fa2 = 0.0;
    for (; sp != end && sp->a == a; ++sp) {
      const double* xb = X + 3 * sp->b;
      const double* vb = V + 3 * sp->b;
      const double dx = xb[0] - xa0, dy = xb[1] - xa1, dz = xb[2] - xa2;
      const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
      const double inv = len > 0.0 ? 1.0 / len : 0.0;
      const double ux = dx * inv, uy = dy * inv, uz = dz * inv;
      const double rel = (vb[0] - va0) * ux + (vb[1] - va1) * uy + (vb[2] - va2) * uz;
      const double mag = sp->stiffness * (len - sp->rest_length) + sp->damping * rel;
      fa0 += mag * ux; fa1 += mag * uy; fa2 += mag * uz;
      double* fb = F + 3 * sp->b;
      fb[0] -= mag * ux; fb[1] -= mag * uy; fb[2] -= mag * uz;
    }
    F[3 * a] += fa0; F[3 * a + 1] += fa1; F[3 * a + 2] += fa2;
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
    accumulateForces(m, s.x, s.v, in, s.f);
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
