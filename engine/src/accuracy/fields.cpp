#include "fields.hpp"

#include <cmath>

#include "hysim/engine/tet_locator.hpp"
#include "hysim/sim/static_solve.hpp"

namespace hysim::engine::accuracy {

namespace {

Result<sim::Model> staticModel(const AccuracyCase& c, bool hold_indenter, bool gravity) {
  std::vector<int> fixed = c.fixed;
  if (hold_indenter) fixed.insert(fixed.end(), c.indenter.begin(), c.indenter.end());
  sim::ModelOptions options;
  options.gravity = gravity ? c.gravity : Eigen::Vector3d::Zero();
  options.max_substeps = 0;  // no mass scaling: added mass would add weight to the statics
  return sim::buildModel(c.mesh, c.materials, fixed, options);
}

}  // namespace

Result<Eigen::MatrixX3d> springStatic(const AccuracyCase& c, bool gravity, double tolerance) {
  auto model = staticModel(c, false, gravity);
  if (!model.ok()) return Error{model.error()};
  sim::State s = sim::makeState(*model, c.mesh);
  sim::StaticSolveOptions so;
  so.tolerance = tolerance;
  const sim::StaticSolveResult r = sim::solveStatic(*model, s, nullptr, so);
  if (!r.converged) return Error{c.name + ": the static solve did not converge (residual " + std::to_string(r.residual) + ")"};
  Eigen::MatrixX3d u = s.x - c.mesh.X;
  return u;
}

Result<std::vector<double>> springIndentation(const AccuracyCase& c, const std::vector<double>& depths_mm, bool gravity,
                                              Eigen::MatrixX3d* last) {
  auto model = staticModel(c, true, gravity);
  if (!model.ok()) return Error{model.error()};
  sim::State s = sim::makeState(*model, c.mesh);
  std::vector<double> forces;
  for (double depth : depths_mm) {
    for (int i : c.indenter) s.x.row(i) = c.mesh.X.row(i) + depth * c.indent_direction.transpose();
    const sim::StaticSolveResult r = sim::solveStatic(*model, s);
    if (!r.converged)
      return Error{c.name + ": the static solve at " + std::to_string(depth) + " mm did not converge (residual " +
                   std::to_string(r.residual) + ")"};
    const sim::NodeVectors f = sim::staticForces(*model, s.x, nullptr);
    double reaction = 0.0;
    for (int i : c.indenter) reaction -= f.row(i).dot(c.indent_direction.transpose());
    forces.push_back(reaction);
  }
  if (last != nullptr) *last = s.x - c.mesh.X;
  return forces;
}

double relativeFieldError(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b, const std::vector<std::uint8_t>* use) {
  double diff = 0.0, ref = 0.0;
  for (Eigen::Index i = 0; i < b.rows(); ++i) {
    if (use != nullptr && !(*use)[i]) continue;
    diff += (a.row(i) - b.row(i)).squaredNorm();
    ref += b.row(i).squaredNorm();
  }
  return ref > 0.0 ? std::sqrt(diff / ref) : std::sqrt(diff);
}

Eigen::MatrixX3d interpolateAtNodes(const cutting::TetMesh& fine, const Eigen::MatrixX3d& fine_u,
                                    const cutting::TetMesh& coarse) {
  TetLocator locator;
  const sim::NodeVectors x = fine.X;
  locator.build(fine, x, 0.5);
  Eigen::MatrixX3d u(coarse.numNodes(), 3);
  for (int i = 0; i < coarse.numNodes(); ++i) {
    const Eigen::Vector3d p = coarse.X.row(i).transpose();
    const int t = locator.locate(fine, x, p, 0.0);
    if (t < 0) {
      Eigen::Index nearest = 0;
      (fine.X.rowwise() - p.transpose()).rowwise().squaredNorm().minCoeff(&nearest);
      u.row(i) = fine_u.row(nearest);
      continue;
    }
    Eigen::Matrix3d A;
    const Eigen::Vector3d x0 = fine.X.row(fine.T(t, 0)).transpose();
    for (int k = 0; k < 3; ++k) A.col(k) = fine.X.row(fine.T(t, k + 1)).transpose() - x0;
    const Eigen::Vector3d w = A.partialPivLu().solve(p - x0);
    u.row(i) = (1.0 - w.sum()) * fine_u.row(fine.T(t, 0)) + w[0] * fine_u.row(fine.T(t, 1)) +
               w[1] * fine_u.row(fine.T(t, 2)) + w[2] * fine_u.row(fine.T(t, 3));
  }
  return u;
}

Calibration calibrate(const Eigen::MatrixX3d& u_ms, const Eigen::MatrixX3d& u_fe) {
  Calibration c;
  const double mm = (u_ms.array() * u_ms.array()).sum();
  if (!(mm > 0.0)) return c;
  const double a = (u_ms.array() * u_fe.array()).sum() / mm;  // u_fe ~ a u_ms
  c.stiffness_scale = a > 0.0 ? 1.0 / a : 1.0;
  c.error_after = relativeFieldError(a * u_ms, u_fe);
  return c;
}

namespace {

double calibrationError(const AccuracyCase& c, const std::vector<double>& scales, const Eigen::MatrixX3d& u_fe, int& solves) {
  // A material with no tets in the mesh changes nothing: it keeps scale 1 (see the caller).
  AccuracyCase scaled = c;
  for (size_t m = 0; m < scaled.materials.size(); ++m) scaled.materials[m].young_modulus_pa *= scales[m];
  ++solves;
  auto u = springStatic(scaled);
  return u.ok() ? relativeFieldError(*u, u_fe) : INFINITY;
}

// The calibration error with material m's scale set to exp(log_s), the others as they are.
double errorWithScale(const AccuracyCase& c, std::vector<double> scales, size_t m, double log_s,
                      const Eigen::MatrixX3d& u_fe, int& solves) {
  scales[m] = std::exp(log_s);
  return calibrationError(c, scales, u_fe, solves);
}

bool materialUsed(const AccuracyCase& c, int label) {
  return (c.mesh.material.array() == label).any();
}

}  // namespace

Result<MaterialCalibration> calibratePerMaterial(const AccuracyCase& c, const Eigen::MatrixX3d& u_fe, double start_scale) {
  MaterialCalibration cal;
  std::vector<double> scales(c.materials.size(), start_scale);
  const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
  for (int round = 0; round < 2; ++round) {
    for (size_t m = 0; m < scales.size(); ++m) {
      double lo = std::log(scales[m]) - std::log(3.0), hi = std::log(scales[m]) + std::log(3.0);
      if (!materialUsed(c, c.materials[m].label)) continue;
      double a = hi - phi * (hi - lo), b = lo + phi * (hi - lo);
      double fa = errorWithScale(c, scales, m, a, u_fe, cal.solves), fb = errorWithScale(c, scales, m, b, u_fe, cal.solves);
      for (int k = 0; k < 8; ++k) {
        if (fa < fb) {
          hi = b, b = a, fb = fa, a = hi - phi * (hi - lo), fa = errorWithScale(c, scales, m, a, u_fe, cal.solves);
        } else {
          lo = a, a = b, fa = fb, b = lo + phi * (hi - lo), fb = errorWithScale(c, scales, m, b, u_fe, cal.solves);
        }
      }
      scales[m] = std::exp(fa < fb ? a : b);
    }
  }
  cal.error_after = calibrationError(c, scales, u_fe, cal.solves);
  if (!std::isfinite(cal.error_after)) return Error{c.name + ": the calibrated static solve failed"};
  for (const sim::Material& m : c.materials) cal.labels.push_back(m.label);
  cal.stiffness_scales = scales;
  return cal;
}

}  // namespace hysim::engine::accuracy
