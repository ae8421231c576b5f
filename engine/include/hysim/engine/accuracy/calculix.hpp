#pragma once
// Reference R2 of the accuracy study: a finite-element solution of the same body from
// CalculiX (the `ccx` program of Debian's calculix-ccx). We write its input deck from our
// mesh (quadratic tets C3D10 on our tets, or linear C3D4), run it, and read the displacements, the indenter's reaction and
// eigenfrequencies from its `.dat` output.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "hysim/engine/accuracy/cases.hpp"

namespace hysim::engine::accuracy {

struct FeOptions {
  double poisson = 0.45;       // soft tissue is nearly incompressible
  bool nlgeom = false;         // geometrically nonlinear (large displacements)
  bool quadratic = true;       // C3D10 (mid-edge nodes added); C3D4 linear tets lock in bending
  bool gravity = true;
  bool hold_indenter = false;  // the case's indenter held, moved indent_mm along its direction
  double indent_mm = 0.0;
  int increments = 1;          // at most this many load increments of equal size (nonlinear: ccx
                               // may take smaller ones); the indenter's force is read at each
  int frequencies = 0;         // > 0: an eigenvalue step instead (the lowest `frequencies` modes)
  std::string program = "ccx";
};

struct FeSolution {
  Eigen::MatrixX3d u;                     // #N x 3 displacements (mm)
  Eigen::Vector3d indenter_force{0, 0, 0};  // total reaction at the indenter nodes (uN), last increment
  std::vector<Eigen::Vector3d> indenter_forces;  // the same at each increment...
  std::vector<double> increment_times;           // ... at these step fractions (0..1]
  bool completed = true;  // false: ccx stopped early (diverged); the tables hold what it reached
  std::vector<double> frequencies_hz;
  double seconds = 0.0;                   // wall time of the ccx run
};

// The deck text (nodes, elements per material, anchored and indenter sets, one step).
std::string calculixDeck(const AccuracyCase& c, const FeOptions& options);

// Parses a `.dat` file's last displacement table, last total-force line and eigenvalue table.
Result<FeSolution> parseCalculixDat(const std::string& text, int num_nodes);

// Writes `dir/job.inp`, runs ccx there, parses `dir/job.dat`. The message names the program
// and the file when ccx is missing or fails.
Result<FeSolution> solveCalculix(const AccuracyCase& c, const FeOptions& options, const std::string& dir,
                                 const std::string& job);

// True when the program answers (ccx is installed).
bool calculixAvailable(const std::string& program = "ccx");

}  // namespace hysim::engine::accuracy
