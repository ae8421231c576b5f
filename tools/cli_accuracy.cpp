#include "cli_accuracy.hpp"

#include <cstdio>
#include <iostream>

#include "hysim/engine/accuracy/study.hpp"

namespace hysim::tools {

std::shared_ptr<AccuracyCommand> addAccuracyCommand(CLI::App& app) {
  auto c = std::make_shared<AccuracyCommand>();
  c->cmd = app.add_subcommand("accuracy",
                              "Speed against error: every integrator and the Bullet peer on a beam and the organ, against "
                              "the converged springs (R1), CalculiX (R2) and closed forms (R3)");
  c->cmd->add_option("--out", c->out, "Output folder: report.json, report.md, PNG plots, the CalculiX decks")->required();
  c->cmd->add_option("--scene", c->scene, "The organ's scene (default: scenes/default.yaml)")->check(CLI::ExistingFile);
  c->cmd->add_option("--refined-mesh", c->refined_mesh,
                     "The same organ meshed finer, for R2 on a refined mesh (default: tests/data/cutting/uterus_20k.msh)")
      ->check(CLI::ExistingFile);
  c->cmd->add_flag("--quick", c->quick, "Coarse beam, short runs, fewer settings, linear FE only (under a minute; CI)");
  c->cmd->add_flag("--quiet", c->quiet, "No progress bar");
  return c;
}

namespace {

void progressBar(double fraction, const std::string& what) {
  const int width = 30, filled = static_cast<int>(fraction * width + 0.5);
  std::fprintf(stderr, "\r[%-*.*s] %3d%% %-60.60s", width, filled, "##############################",
               static_cast<int>(fraction * 100 + 0.5), what.c_str());
  if (fraction >= 1.0) std::fprintf(stderr, "\n");
  std::fflush(stderr);
}

}  // namespace

std::optional<int> runAccuracyCommand(const AccuracyCommand& c) {
  if (c.cmd == nullptr || !*c.cmd) return std::nullopt;
  engine::accuracy::StudyOptions o;
  o.out_dir = c.out;
  o.quick = c.quick;
  o.scene_path = c.scene.empty() ? std::string(HYSIM_SOURCE_DIR) + "/scenes/default.yaml" : c.scene;
  // The finer mesh of the default organ serves only the default organ.
  if (!c.refined_mesh.empty()) o.refined_mesh = c.refined_mesh;
  else if (c.scene.empty()) o.refined_mesh = std::string(HYSIM_SOURCE_DIR) + "/tests/data/cutting/uterus_20k.msh";
  if (!c.quiet) o.progress = progressBar;
  const Status s = engine::accuracy::runAccuracyStudy(o);
  if (!s.ok()) {
    std::cerr << "\nhysim accuracy: " << s.error() << "\n";
    return 1;
  }
  if (!c.quiet) std::cout << "hysim accuracy: wrote " << c.out << "/report.md and report.json\n";
  return 0;
}

}  // namespace hysim::tools
