#pragma once
// `hysim accuracy`: every integrator setting and the Bullet peer on every case, with their
// cost and their error against the references kept apart (R1 the converged spring network,
// R2 CalculiX, R3 closed forms). Writes report.json, report.md and gnuplot PNG plots.
#include <functional>
#include <string>

#include "hysim/cutting/result.hpp"

namespace hysim::engine::accuracy {

struct StudyOptions {
  std::string scene_path;     // the organ's scene (scenes/default.yaml)
  std::string refined_mesh;   // the same organ meshed finer (R2 on a refined mesh); empty: skip
  std::string out_dir;
  bool quick = false;         // coarse beam, short runs, fewer settings, linear FE only
  std::string calculix = "ccx";
  std::string gnuplot = "gnuplot";
  std::function<void(double fraction, const std::string& what)> progress;  // may be empty
};

Status runAccuracyStudy(const StudyOptions& options);

}  // namespace hysim::engine::accuracy
