#include "hysim/engine/accuracy/runs.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace hysim::engine::accuracy {
namespace {

int nearestNode(const cutting::Positions& X, const Eigen::Vector3d& p) {
  int best = 0;
  for (int i = 1; i < X.rows(); ++i)
    if ((X.row(i).transpose() - p).squaredNorm() < (X.row(best).transpose() - p).squaredNorm()) best = i;
  return best;
}

double totalEnergy(const sim::Model& m, const sim::State& s) {
  double e = sim::kineticEnergy(m, s) + sim::springEnergy(m, s);
  for (int i = 0; i < m.num_nodes; ++i) e -= m.mass[i] * s.x.row(i).dot(m.options.gravity.transpose());
  return e;
}

double rms(const sim::NodeVectors& a, const cutting::Positions& b) {
  return std::sqrt((a - b).squaredNorm() / static_cast<double>(std::max<Eigen::Index>(1, a.rows())));
}

// Records the state at each sample time and the probe every step.
struct Recorder {
  int probe_node;
  Eigen::Vector3d down;
  double z0;
  int sample_every_steps;
  void record(Trajectory& t, const sim::NodeVectors& x, long step) const {
    t.probe.push_back(x.row(probe_node).dot(down.transpose()) - z0);
    if (step % sample_every_steps == 0) t.samples.push_back(x);
  }
};

Recorder makeRecorder(const AccuracyCase& c, const RunSpec& spec, double dt) {
  Recorder r;
  r.probe_node = nearestNode(c.mesh.X, c.probe);
  r.down = c.gravity.norm() > 0 ? Eigen::Vector3d(c.gravity.normalized()) : Eigen::Vector3d(0, 0, -1);
  r.z0 = c.mesh.X.row(r.probe_node).dot(r.down.transpose());
  r.sample_every_steps = std::max(1, static_cast<int>(std::lround(spec.sample_every_s / dt)));
  return r;
}

Trajectory runBullet(const AccuracyCase& c, const Setting& setting, const RunSpec& spec) {
  Trajectory t;
  auto model = caseModel(c, setting.options);
  if (!model.ok()) {
    t.diverged = true;
    return t;
  }
  t.dt = setting.bullet_options.dt;
  BulletOptions bo = setting.bullet_options;
  bo.drag_per_s = c.drag_per_s;
  BulletPeer peer(c, *model, bo, spec.start);
  const Recorder rec = makeRecorder(c, spec, t.dt);
  const long steps = std::lround(spec.duration_s / t.dt);
  sim::NodeVectors x;
  peer.positions(x);
  rec.record(t, x, 0);
  for (long k = 1; k <= steps; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    peer.step();
    t.step_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    peer.positions(x);
    if (!x.allFinite()) t.diverged = true;
    rec.record(t, x, k);
  }
  return t;
}

}  // namespace

Result<sim::Model> caseModel(const AccuracyCase& c, sim::ModelOptions options) {
  options.gravity = c.gravity;
  options.drag_per_s = c.drag_per_s;
  return sim::buildModel(c.mesh, c.materials, c.fixed, options);
}

Trajectory runTrajectory(const AccuracyCase& c, const Setting& setting, const RunSpec& spec) {
  if (setting.bullet) return runBullet(c, setting, spec);
  Trajectory t;
  auto model = caseModel(c, setting.options);
  if (!model.ok()) {
    t.diverged = true;
    return t;
  }
  const sim::Model& m = *model;
  t.dt = m.options.dt;
  t.substeps = m.substeps;
  t.added_mass_g = m.added_mass;
  sim::State s = sim::makeState(m, c.mesh);
  if (spec.start != nullptr) s.x = *spec.start;
  const Recorder rec = makeRecorder(c, spec, t.dt);
  t.energy_start = totalEnergy(m, s);
  t.max_spring_energy = sim::springEnergy(m, s);
  rec.record(t, s.x, 0);
  const long steps = std::lround(spec.duration_s / t.dt);
  t.step_ms.reserve(static_cast<size_t>(steps));
  for (long k = 1; k <= steps; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    sim::step(m, s, {});
    t.step_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    rec.record(t, s.x, k);
    if (k % rec.sample_every_steps == 0) t.max_spring_energy = std::max(t.max_spring_energy, sim::springEnergy(m, s));
  }
  t.diverged = s.diverged;
  t.energy_end = totalEnergy(m, s);
  return t;
}

double trajectoryError(const Trajectory& run, const Trajectory& ref, const cutting::Positions& rest) {
  const double inf = std::numeric_limits<double>::infinity();
  if (run.diverged || ref.diverged || run.samples.empty() || run.samples.size() != ref.samples.size()) return inf;
  double worst = 0.0, scale = 0.0;
  for (size_t k = 0; k < run.samples.size(); ++k) {
    const double e = rms(run.samples[k], ref.samples[k]);
    if (!(e <= worst)) worst = std::isfinite(e) ? e : inf;
    scale = std::max(scale, rms(ref.samples[k], rest));
  }
  return scale > 0.0 ? worst / scale : worst;
}

Cost costOf(const Trajectory& run) {
  Cost c;
  if (run.step_ms.empty()) return c;
  std::vector<double> v = run.step_ms;
  std::sort(v.begin(), v.end());
  const double steps_per_s = 1.0 / run.dt;
  c.median_ms_per_s = v[v.size() / 2] * steps_per_s;
  c.p99_ms_per_s = v[std::min(v.size() - 1, static_cast<size_t>(0.99 * static_cast<double>(v.size())))] * steps_per_s;
  return c;
}

Oscillation oscillationOf(const std::vector<double>& probe, double dt) {
  Oscillation o;
  if (probe.size() < 4) return o;
  double mean = 0.0;
  for (double p : probe) mean += p;
  mean /= static_cast<double>(probe.size());
  std::vector<double> crossings;  // interpolated times of upward mean-crossings
  std::vector<double> peaks;      // largest |p - mean| between crossings
  double peak = 0.0;
  for (size_t k = 1; k < probe.size(); ++k) {
    const double a = probe[k - 1] - mean, b = probe[k] - mean;
    peak = std::max(peak, std::abs(b));
    if (a < 0.0 && b >= 0.0) {
      crossings.push_back((static_cast<double>(k) - 1.0 + a / (a - b)) * dt);
      peaks.push_back(peak);
      peak = 0.0;
    }
  }
  if (crossings.size() < 2) return o;
  o.frequency_hz = static_cast<double>(crossings.size() - 1) / (crossings.back() - crossings.front());
  if (peaks.size() >= 3) o.amplitude_ratio = peaks.back() / peaks[1];
  return o;
}

}  // namespace hysim::engine::accuracy
