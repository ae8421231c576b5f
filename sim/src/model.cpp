#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_map>

#include "hysim/sim/model.hpp"
#include "implicit_solver.hpp"
#include "model_internal.hpp"

namespace hysim::sim {
namespace {

using cutting::TetMesh;

// The six edges of a tet as local index pairs.
constexpr int kTetEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

// Highest natural frequency of the linearised spring network (springs along their rest
// directions), by power iteration on M^-1/2 K M^-1/2 over free nodes. Deterministic start.
double estimateOmegaMax(const Model& m, const cutting::Positions& X, Eigen::MatrixX3d* mode = nullptr) {
  const int n = m.num_nodes;
  Eigen::MatrixX3d u = Eigen::MatrixX3d::Zero(n, 3), w(n, 3);
  for (int i = 0; i < n; ++i) {
    if (m.fixed[i]) continue;
    // Alternating pattern excites the highest modes quickly.
    const double s = (i % 2 == 0) ? 1.0 : -1.0;
    u.row(i) = Eigen::RowVector3d(s, -0.5 * s, 0.25 * s);
  }
  double lambda = 0.0;
  for (int iter = 0; iter < 200; ++iter) {
    const double norm = u.norm();
    if (norm == 0.0) return 0.0;
    u /= norm;
    w.setZero();
    for (int s = 0; s < m.springs.rows(); ++s) {
      const int a = m.springs(s, 0), b = m.springs(s, 1);
      Eigen::RowVector3d d = X.row(b) - X.row(a);
      d /= d.norm();
      // y = M^-1/2 u (fixed nodes have zero displacement)
      const Eigen::RowVector3d ya = m.fixed[a] ? Eigen::RowVector3d::Zero() : Eigen::RowVector3d(u.row(a) / std::sqrt(m.mass[a]));
      const Eigen::RowVector3d yb = m.fixed[b] ? Eigen::RowVector3d::Zero() : Eigen::RowVector3d(u.row(b) / std::sqrt(m.mass[b]));
      const double stretch = m.stiffness[s] * (yb - ya).dot(d);
      if (!m.fixed[a]) w.row(a) += stretch * d / std::sqrt(m.mass[a]);
      if (!m.fixed[b]) w.row(b) -= stretch * d / std::sqrt(m.mass[b]);
    }
    // w = -M^-1/2 K M^-1/2 u ; Rayleigh quotient of K-tilde
    const double next = -(u.array() * w.array()).sum();
    if (mode != nullptr) *mode = u;  // the unit vector whose Rayleigh quotient is `next`
    u = -w;
    if (iter > 60 && std::abs(next - lambda) <= 1e-5 * next) {
      lambda = next;
      break;
    }
    lambda = next;
  }
  return std::sqrt(std::max(lambda, 0.0));
}

}  // namespace

void buildStepSprings(Model& m) {
  // A spring between two anchored nodes never changes length: the step skips it.
  const int ns = static_cast<int>(m.springs.rows());
  StepSprings& st = m.step_springs;
  st.node_offset.assign(m.num_nodes + 1, 0);
  const std::int32_t* const spring_a = m.springs.col(0).data();
  const std::int32_t* const spring_b = m.springs.col(1).data();
  const std::uint8_t* const fixed = m.fixed.data();
  std::int32_t* const off = st.node_offset.data();
  int count = 0;
  for (int s = 0; s < ns; ++s) {
    const int a = spring_a[s], b = spring_b[s];
    if (fixed[a] && fixed[b]) continue;
    ++count;
    ++off[a];
    ++off[b];
  }
  fillStepSprings(m, count);
}

void fillStepSprings(Model& m, int count) {
  // Sized by the count and filled by index (the arrays keep their capacity between calls).
  const int n = m.num_nodes;
  const int ns = static_cast<int>(m.springs.rows());
  StepSprings& st = m.step_springs;
  const std::int32_t* const spring_a = m.springs.col(0).data();
  const std::int32_t* const spring_b = m.springs.col(1).data();
  const std::uint8_t* const fixed = m.fixed.data();
  std::int32_t* const off = st.node_offset.data();
  // Each node's number of entries at off[i], summed into the end of its entries; the fill
  // then places each entry just below its node's last one, the springs taken backwards: a
  // node's entries in increasing spring order, off[i] ending at their start (no cursor array).
  for (int i = 1; i < n; ++i) off[i] += off[i - 1];
  if (n > 0) off[n] = off[n - 1];
  // Every entry is written below: an array that must grow is emptied first, so that growing
  // does not copy its old contents.
  auto size = [](auto& v, size_t len) {
    if (len > v.capacity()) v.clear();
    v.resize(len);
  };
  size(st.a, count);
  size(st.b, count);
  size(st.rest_length, count);
  size(st.stiffness, count);
  size(st.damping, count);
  size(st.incident, off[n]);
  size(st.sign, off[n]);
  std::int32_t* const step_a = st.a.data();
  std::int32_t* const step_b = st.b.data();
  double* const rest = st.rest_length.data();
  double* const stiffness = st.stiffness.data();
  double* const damping = st.damping.data();
  std::int32_t* const incident = st.incident.data();
  double* const sign = st.sign.data();
  for (int s = ns - 1, k = count - 1; s >= 0; --s) {
    const int a = spring_a[s], b = spring_b[s];
    if (fixed[a] && fixed[b]) continue;
    step_a[k] = a;
    step_b[k] = b;
    rest[k] = m.rest_length[s];
    stiffness[k] = m.stiffness[s];
    damping[k] = m.damping[s];
    const int ea = --off[a];
    incident[ea] = k;
    sign[ea] = 1.0;
    const int eb = --off[b];
    incident[eb] = k;
    sign[eb] = -1.0;
    --k;
  }
}

Result<Model> buildModel(const TetMesh& mesh, const std::vector<Material>& materials,
                         const std::vector<int>& fixed_nodes, const ModelOptions& options) {
  Model m;
  m.num_nodes = mesh.numNodes();
  m.materials = materials;
  m.options = options;
  if (!(options.dt > 0.0) || !std::isfinite(options.dt)) {
    return Error{"dt must be positive, got " + std::to_string(options.dt)};
  }
  if (options.integrator == Integrator::Xpbd && (options.xpbd_substeps < 0 || options.xpbd_iterations < 1)) {
    return Error{"xpbd_substeps must be >= 0 and xpbd_iterations >= 1, got " + std::to_string(options.xpbd_substeps) +
                 " and " + std::to_string(options.xpbd_iterations)};
  }
  const int nt = mesh.numTets();
  const int n = m.num_nodes;

  std::unordered_map<int, int> material_of_label;
  for (int i = 0; i < static_cast<int>(materials.size()); ++i) {
    const Material& mat = materials[i];
    if (!(mat.young_modulus_pa > 0.0) || !(mat.density_g_mm3 > 0.0) || !(mat.stiffness_damping_s >= 0.0)) {
      return Error{"material '" + mat.name + "': Young's modulus and density must be positive, damping non-negative"};
    }
    material_of_label[mat.label] = i;
  }

  // Lumped masses and per-edge Van Gelder sums, edges collected as sorted unique keys.
  m.mass = Eigen::VectorXd::Zero(n);
  std::vector<std::int64_t> edge_keys;
  edge_keys.reserve(static_cast<size_t>(nt) * 6);
  std::vector<double> edge_ev, edge_bev;  // per (tet, edge): E*V and beta*E*V
  edge_ev.reserve(edge_keys.capacity());
  edge_bev.reserve(edge_keys.capacity());
  for (int t = 0; t < nt; ++t) {
    const auto it = material_of_label.find(mesh.material[t]);
    if (it == material_of_label.end()) {
      return Error{"tet " + std::to_string(t) + " has material label " + std::to_string(mesh.material[t]) +
                   " but the scene defines no material with that label"};
    }
    const Material& mat = materials[it->second];
    const double vol = cutting::tetVolume(mesh, t);
    if (!(vol > 0.0)) return Error{"tet " + std::to_string(t) + " has non-positive volume " + std::to_string(vol)};
    for (int c = 0; c < 4; ++c) m.mass[mesh.T(t, c)] += 0.25 * mat.density_g_mm3 * vol;
    for (const auto& e : kTetEdges) {
      int a = mesh.T(t, e[0]), b = mesh.T(t, e[1]);
      if (a > b) std::swap(a, b);
      edge_keys.push_back(static_cast<std::int64_t>(a) * n + b);
      edge_ev.push_back(mat.young_modulus_pa * vol);
      edge_bev.push_back(mat.stiffness_damping_s * mat.young_modulus_pa * vol);
    }
  }
  std::vector<int> order(edge_keys.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(), [&](int i, int j) { return edge_keys[i] < edge_keys[j]; });
  std::vector<std::int64_t> keys;
  std::vector<double> sum_ev, sum_bev;
  for (int idx : order) {
    if (keys.empty() || keys.back() != edge_keys[idx]) {
      keys.push_back(edge_keys[idx]);
      sum_ev.push_back(0.0);
      sum_bev.push_back(0.0);
    }
    sum_ev.back() += edge_ev[idx];
    sum_bev.back() += edge_bev[idx];
  }
  const int ns = static_cast<int>(keys.size());
  m.springs.resize(ns, 2);
  m.rest_length.resize(ns);
  m.stiffness.resize(ns);
  m.damping.resize(ns);
  for (int s = 0; s < ns; ++s) {
    const int a = static_cast<int>(keys[s] / n), b = static_cast<int>(keys[s] % n);
    m.springs(s, 0) = a;
    m.springs(s, 1) = b;
    const double len = (mesh.X.row(b) - mesh.X.row(a)).norm();
    m.rest_length[s] = len;
    m.stiffness[s] = sum_ev[s] / (len * len);
    // beta weighted by each tet's contribution: c = sum_t beta_t E_t V_t / |e|^2
    m.damping[s] = sum_bev[s] / (len * len);
  }

  m.fixed.assign(n, 0);
  for (int i : fixed_nodes) {
    if (i < 0 || i >= n) return Error{"fixed node index " + std::to_string(i) + " out of range"};
    m.fixed[i] = 1;
  }
  m.inv_mass = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < n; ++i) {
    // Unused nodes (mass 0) are treated as fixed so the step never divides by zero.
    if (m.mass[i] <= 0.0) m.fixed[i] = 1;
    if (!m.fixed[i]) m.inv_mass[i] = 1.0 / m.mass[i];
  }
  buildStepSprings(m);

  // Stability of symplectic Euler with stiffness damping (zeta = beta*omega/2):
  // omega*h < 2*(sqrt(1+zeta^2) - zeta).
  double beta_max = 0.0;
  for (const Material& mat : materials) beta_max = std::max(beta_max, mat.stiffness_damping_s);
  auto stabilityLimit = [&](double omega) {
    if (!(omega > 0.0)) return options.dt;
    const double zeta = 0.5 * beta_max * omega;
    return 2.0 * (std::sqrt(1.0 + zeta * zeta) - zeta) / omega;
  };
  auto substepsFor = [&](double critical) {
    return std::max(1, static_cast<int>(std::ceil(options.dt / (options.stability_safety * critical))));
  };
  m.omega_max = estimateOmegaMax(m, mesh.X, &m.stability_mode);
  m.critical_dt = stabilityLimit(m.omega_max);

  // Selective mass scaling (as explicit FE codes do): a few tiny elements (slivers from a
  // cut) must not force thousands of substeps. Nodes whose local frequency bound
  // sqrt(2 sum k / m) exceeds what max_substeps allows get mass until it does not; the
  // added mass is reported. The mass moments change by that amount, at those nodes only.
  if (massScalingApplies(options) && substepsFor(m.critical_dt) > options.max_substeps) {
    std::vector<double> k_sum(n, 0.0);
    for (int s = 0; s < ns; ++s) {
      k_sum[m.springs(s, 0)] += m.stiffness[s];
      k_sum[m.springs(s, 1)] += m.stiffness[s];
    }
    // 0.8: the power iteration approaches omega_max from below, and a flattened spectrum
    // (after scaling) converges slowly.
    double target = 0.8 * 2.0 * options.stability_safety * options.max_substeps / options.dt;
    for (int round = 0; round < 4 && substepsFor(m.critical_dt) > options.max_substeps; ++round) {
      for (int i = 0; i < n; ++i) {
        if (m.fixed[i]) continue;
        const double needed = 2.0 * k_sum[i] / (target * target);
        if (m.mass[i] < needed) {
          m.added_mass += needed - m.mass[i];
          m.mass[i] = needed;
          m.inv_mass[i] = 1.0 / needed;
        }
      }
      m.omega_max = estimateOmegaMax(m, mesh.X, &m.stability_mode);
      m.critical_dt = stabilityLimit(m.omega_max);
      target *= 0.7;  // the local bound is not the global one: tighten and retry
    }
  }
  setSubsteps(m, substepsFor(m.critical_dt));

  if (options.integrator == Integrator::ImplicitEuler) {
    auto solver = ImplicitSolver::create(m);
    if (!solver.ok()) return Error{solver.error()};
    m.implicit = std::move(solver.value());
  }
  return m;
}

State makeState(const Model& model, const TetMesh& mesh) {
  State s;
  const int n = model.num_nodes;
  s.x = mesh.X;
  s.v = NodeVectors::Zero(n, 3);
  sizeStepArrays(model, s);
  return s;
}

void sizeStepArrays(const Model& model, State& state) {
  const int n = model.num_nodes;
  state.f.setZero(n, 3);
  state.scratch0.resize(n, 3);
  state.scratch1.resize(n, 3);
  state.scratch2.resize(n, 3);
  state.spring_force.resize(4 * static_cast<size_t>(model.step_springs.size()));  // written by every substep first
  state.xpbd_lambda.resize(static_cast<size_t>(model.springs.rows()));            // zeroed by every XPBD substep
  state.solve0.resize(n, 3);
  state.solve1.resize(n, 3);
}

double kineticEnergy(const Model& model, const State& state) {
  double e = 0.0;
  for (int i = 0; i < model.num_nodes; ++i) e += 0.5 * model.mass[i] * state.v.row(i).squaredNorm();
  return e;
}

double springEnergy(const Model& model, const State& state) {
  double e = 0.0;
  for (int s = 0; s < model.springs.rows(); ++s) {
    const double len = (state.x.row(model.springs(s, 1)) - state.x.row(model.springs(s, 0))).norm();
    const double d = len - model.rest_length[s];
    e += 0.5 * model.stiffness[s] * d * d;
  }
  return e;
}

std::uint64_t stateHash(const State& state) {
  std::uint64_t h = 1469598103934665603ULL;  // FNV-1a offset basis
  auto mix = [&h](const double* data, Eigen::Index count) {
    const auto* bytes = reinterpret_cast<const unsigned char*>(data);
    for (size_t i = 0; i < static_cast<size_t>(count) * sizeof(double); ++i) {
      h ^= bytes[i];
      h *= 1099511628211ULL;  // FNV prime
    }
  };
  mix(state.x.data(), state.x.size());
  mix(state.v.data(), state.v.size());
  return h;
}

}  // namespace hysim::sim
