// XPBD step: extended position-based dynamics (Macklin, Mueller, Chentanez 2016) taken in
// small substeps with few iterations each (Macklin et al. 2019, "Small steps in physics
// simulation"). Each spring is a distance constraint C = |x_a - x_b| - L with compliance
// alpha = 1/k, so its potential alpha^-1 C^2 / 2 is exactly the spring's energy. Its damping
// c (Model::damping, c = beta k) is XPBD's constraint damping: with alpha~ = alpha / h^2 and
// beta~ = h^2 c, the paper's gamma = alpha~ beta~ / h = c / (k h) (= beta / h). Converged,
// the update then solves h^-2 lambda = -(k C + c dC/dt), the spring and dashpot forces of a
// backward Euler substep. Nothing here allocates: State holds every buffer.
#include <algorithm>
#include <cmath>

#include "hysim/sim/model.hpp"
#include "model_internal.hpp"

namespace hysim::sim {
namespace {

// Unconstrained prediction of the free nodes, as symplectic Euler's velocity update (the
// same implicit drag factor): v = (v + h f / m) * drag with f = m g + f_ext, then x += h v.
// x_prev (the substep's start, for the velocity and the damping term) goes to `x_prev`.
void predict(const Model& m, const double* ext, double h, double drag, NodeVectors& x_prev, State& s) {
  const Eigen::Vector3d& g = m.options.gravity;
  for (int i = 0; i < m.num_nodes; ++i) {
    x_prev.row(i) = s.x.row(i);
    if (m.fixed[i]) continue;  // anchored: never moves, v stays 0
    const double hm = h * m.inv_mass[i];
    for (int c = 0; c < 3; ++c) {
      double f = m.mass[i] * g[c];
      if (ext != nullptr) f += ext[3 * i + c];
      s.v(i, c) = (s.v(i, c) + hm * f) * drag;
      s.x(i, c) += h * s.v(i, c);
    }
  }
}

// One Gauss-Seidel sweep over all springs in index order (deterministic), each projected
// with the XPBD update including damping (Macklin 2016, eq. 26):
//   dlambda = (-C - alpha~ lambda - gamma grad C . (x - x_prev)) / ((1 + gamma) w + alpha~)
// and x_a += w_a n dlambda, x_b -= w_b n dlambda (n = grad_a C, w the inverse masses).
void sweepSprings(const Model& m, double h, const NodeVectors& x_prev, State& s) {
  const int ns = static_cast<int>(m.springs.rows());
  const std::int32_t* sa = m.springs.col(0).data();
  const std::int32_t* sb = m.springs.col(1).data();
  const double* rest = m.rest_length.data();
  const double* stiffness = m.stiffness.data();
  const double* damping = m.damping.data();
  const double* w_of = m.inv_mass.data();
  const double* x0 = x_prev.data();
  double* x = s.x.data();
  double* lambda = s.xpbd_lambda.data();
  const double inv_h2 = 1.0 / (h * h);
  for (int sp = 0; sp < ns; ++sp) {
    const int a = 3 * sa[sp], b = 3 * sb[sp];  // row-major #N x 3
    const double wa = w_of[sa[sp]], wb = w_of[sb[sp]], w = wa + wb;
    const double k = stiffness[sp];
    // Both ends anchored: nothing can move. No stiffness: infinite compliance, no force.
    if (!(w > 0.0) || !(k > 0.0)) continue;
    const double alpha_t = inv_h2 / k;
    const double gamma = damping[sp] / (k * h);
    const double dx = x[a] - x[b], dy = x[a + 1] - x[b + 1], dz = x[a + 2] - x[b + 2];
    // + 1e-300 keeps a zero-length spring finite: its direction is 0, so it moves nothing.
    const double len = std::sqrt(dx * dx + dy * dy + dz * dz + 1e-300);
    const double inv = 1.0 / len;
    const double nx = dx * inv, ny = dy * inv, nz = dz * inv;
    const double rel = nx * ((x[a] - x0[a]) - (x[b] - x0[b])) + ny * ((x[a + 1] - x0[a + 1]) - (x[b + 1] - x0[b + 1])) +
                       nz * ((x[a + 2] - x0[a + 2]) - (x[b + 2] - x0[b + 2]));
    const double dl = (-(len - rest[sp]) - alpha_t * lambda[sp] - gamma * rel) / ((1.0 + gamma) * w + alpha_t);
    lambda[sp] += dl;
    const double pa = wa * dl, pb = wb * dl;
    x[a] += pa * nx;
    x[a + 1] += pa * ny;
    x[a + 2] += pa * nz;
    x[b] -= pb * nx;
    x[b + 1] -= pb * ny;
    x[b + 2] -= pb * nz;
  }
}

}  // namespace

void stepXpbd(const Model& m, State& s, const StepInput& in) {
  const double h = m.substep;
  const double drag = 1.0 / (1.0 + h * m.options.drag_per_s);
  const int iterations = std::max(1, m.options.xpbd_iterations);
  NodeVectors& x_prev = s.scratch0;
  const double* ext = in.external_force != nullptr ? in.external_force->data() : nullptr;
  // A state not sized for this model (sizeStepArrays) would be written out of bounds: freeze it.
  if (s.xpbd_lambda.size() != static_cast<size_t>(m.springs.rows()) || x_prev.rows() != m.num_nodes) {
    s.diverged = true;
    ++s.warnings;
    return;
  }
  for (int sub = 0; sub < m.substeps; ++sub) {
    if (in.refresh_external != nullptr) in.refresh_external(in.context, s.x, s.v);
    predict(m, ext, h, drag, x_prev, s);
    // lambda starts at 0 in every substep (XPBD's warm start is the predicted positions).
    std::fill(s.xpbd_lambda.begin(), s.xpbd_lambda.end(), 0.0);
    for (int it = 0; it < iterations; ++it) sweepSprings(m, h, x_prev, s);
    for (int i = 0; i < m.num_nodes; ++i)
      if (!m.fixed[i]) s.v.row(i) = (s.x.row(i) - x_prev.row(i)) / h;
  }
}

}  // namespace hysim::sim
