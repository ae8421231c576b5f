#pragma once
// Displacement fields of the accuracy study: static solutions of the spring network (R1),
// comparisons between fields, and the one-number stiffness calibration against R2.
#include <cstdint>
#include <vector>

#include "hysim/engine/accuracy/cases.hpp"
#include "hysim/sim/model.hpp"

namespace hysim::engine::accuracy {

// R1: the spring network's static displacement (#N x 3, mm) under the case's gravity.
Result<Eigen::MatrixX3d> springStatic(const AccuracyCase& c, bool gravity = true, double tolerance = 1e-9);

// R1 of the indentation: the indenter moved through `depths_mm` in turn (each solve starts
// from the previous depth's answer), its reaction along the indent direction at each (uN).
// `last` receives the displacement at the last depth.
Result<std::vector<double>> springIndentation(const AccuracyCase& c, const std::vector<double>& depths_mm, bool gravity,
                                              Eigen::MatrixX3d* last = nullptr);

// RMS(a - b) / RMS(b); over the rows where `use` is 1 when given.
double relativeFieldError(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b,
                          const std::vector<std::uint8_t>* use = nullptr);

// The field `fine_u` on `fine` interpolated at `coarse`'s nodes (rest positions): linear in
// the containing tet, the nearest node's value for a node outside the fine mesh.
Eigen::MatrixX3d interpolateAtNodes(const cutting::TetMesh& fine, const Eigen::MatrixX3d& fine_u,
                                    const cutting::TetMesh& coarse);

// The stiffness scale s that best fits u_ms / s to u_fe (least squares), and the relative
// error left after it. Linear statics: scaling every spring by s divides u by s.
struct Calibration {
  double stiffness_scale = 1.0;
  double error_after = 0.0;
};
Calibration calibrate(const Eigen::MatrixX3d& u_ms, const Eigen::MatrixX3d& u_fe);

// One stiffness scale per material (E_m times s_m), fitted to u_fe by coordinate golden-section
// searches on log s_m starting from the one-number fit: in the linear range the network's
// stiffness is linear in each material's E, so the error is smooth in s.
struct MaterialCalibration {
  std::vector<int> labels;
  std::vector<double> stiffness_scales;
  double error_after = 0.0;
  int solves = 0;
};
Result<MaterialCalibration> calibratePerMaterial(const AccuracyCase& c, const Eigen::MatrixX3d& u_fe, double start_scale);

}  // namespace hysim::engine::accuracy
