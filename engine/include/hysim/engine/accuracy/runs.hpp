#pragma once
// Runs one integrator setting (or the Bullet peer) on a case for a stretch of simulated time,
// timing every step, and measures its error against a reference run.
#include <string>
#include <vector>

#include "hysim/engine/accuracy/bullet_peer.hpp"
#include "hysim/engine/accuracy/cases.hpp"
#include "hysim/sim/model.hpp"

namespace hysim::engine::accuracy {

struct Setting {
  std::string family;  // symplectic_euler, implicit_euler, xpbd, bullet, reference
  std::string label;   // e.g. "symplectic 2x auto", shown in tables and plots
  sim::ModelOptions options;
  bool bullet = false;
  BulletOptions bullet_options;
};

struct RunSpec {
  double duration_s = 0.4;
  double sample_every_s = 0.08;          // a multiple of every setting's dt
  const sim::NodeVectors* start = nullptr;  // start positions (at rest when null: the mesh)
};

struct Trajectory {
  std::vector<sim::NodeVectors> samples;  // positions at each sample time (t = k * sample_every)
  std::vector<double> probe;              // probe displacement along gravity per step (mm)
  std::vector<double> step_ms;            // wall time of each step
  double dt = 0.0;
  int substeps = 0;                       // symplectic / xpbd substeps per step
  double added_mass_g = 0.0;
  double energy_start = 0.0, energy_end = 0.0;  // kinetic + spring + gravity (nJ)
  double max_spring_energy = 0.0;               // over the samples (nJ)
  bool diverged = false;
};

// The model of a case with these options (the case's gravity and drag replace the options').
Result<sim::Model> caseModel(const AccuracyCase& c, sim::ModelOptions options);

Trajectory runTrajectory(const AccuracyCase& c, const Setting& setting, const RunSpec& spec);

// max over samples of RMS(x - x_ref) / max over samples of RMS(x_ref - rest); infinity when
// either run diverged or their samples differ in number.
double trajectoryError(const Trajectory& run, const Trajectory& reference, const cutting::Positions& rest);

// Median and 99th percentile of the steps' wall time, as milliseconds per simulated second.
struct Cost {
  double median_ms_per_s = 0.0;
  double p99_ms_per_s = 0.0;
};
Cost costOf(const Trajectory& run);

// Frequency of the probe's oscillation (Hz) from its mean-crossings, and the ratio of the
// last full swing's amplitude to the first; 0 when fewer than two crossings.
struct Oscillation {
  double frequency_hz = 0.0;
  double amplitude_ratio = 0.0;
};
Oscillation oscillationOf(const std::vector<double>& probe, double dt);

}  // namespace hysim::engine::accuracy
