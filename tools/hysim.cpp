// hysim: the command-line entry. `hysim run` steps a scene headless and writes PNG frames
// and a JSON report (cli_run.cpp, with `hysim replay`); `hysim stats` prints mesh statistics
// with the paper's columns.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>

#include "hysim/cutting/mesh_io.hpp"
#include "hysim/cutting/mesh_stats.hpp"
#include "tool_common.hpp"
#include "cli_accuracy.hpp"
#include "cli_cut2d.hpp"
#include "cli_mesh.hpp"
#include "cli_run.hpp"
#include "cli_sessions.hpp"

using namespace hysim;

namespace {

int fail(const std::string& message) {
  std::cerr << "hysim: " << message << "\n";
  return 1;
}

int statsCommand(const std::string& path, bool json) {
  cutting::MeshStats s;
  auto tets = cutting::readTetMesh(path);
  if (tets.ok()) {
    if (auto v = cutting::validate(*tets); !v.ok()) return fail(path + ": invalid mesh: " + v.error());
    s = cutting::computeStats(*tets);
  } else {
    auto tris = cutting::readTriMesh(path);
    if (!tris.ok()) return fail(tets.error());
    if (auto v = cutting::validate(*tris); !v.ok()) return fail(path + ": invalid mesh: " + v.error());
    s = cutting::computeStats(*tris);
  }
  if (json) {
    const nlohmann::ordered_json j = tools::statsJson(s);
    std::cout << j.dump(2) << "\n";
  } else {
    std::printf("%-8s %8s %10s %10s %10s %10s %8s %8s %8s %7s %7s %7s %9s\n", "", "#N", "#E", "size_min", "size_mu",
                "size_sd", "E_min", "E_mu", "E_sd", "q_min", "q_mu", "q_sd", "angle_min");
    std::printf("%-8s %8d %10d %10.4g %10.4g %10.4g %8.4g %8.4g %8.4g %7.4f %7.4f %7.4f %9.2f\n", "mesh", s.nodes,
                s.elements, s.size_min, s.size_mean, s.size_std, s.edge_min, s.edge_mean, s.edge_std, s.q_min,
                s.q_mean, s.q_std, s.dihedral_min_deg);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"hysim: real-time hysteroscopy training simulator (headless tools)"};
  app.require_subcommand(1);

  auto run_commands = hysim::tools::addRunCommands(app);  // hysim run, hysim replay

  std::string stats_path;
  bool stats_json = false;
  CLI::App* stats_cmd = app.add_subcommand("stats", "Mesh statistics (#N, #E, size, edge, q = r_in/R_circ, angles)");
  stats_cmd->add_option("mesh", stats_path, "Mesh file (.msh or .vtk)")->required()->check(CLI::ExistingFile);
  stats_cmd->add_flag("--json", stats_json, "Print JSON");

  auto cut2d_commands = hysim::tools::addCut2dCommands(app);  // hysim cut, hysim tables
  auto accuracy_command = hysim::tools::addAccuracyCommand(app);
  auto sessions_commands = hysim::tools::addSessionsCommands(app);  // hysim sessions list|export
  auto mesh_command = hysim::tools::addMeshCommand(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11 prints the message; its exit codes differ by kind of error (105 for a failed
    // check), and hysim's bad input is exit status 1 whatever the kind (README).
    return app.exit(e) == 0 ? 0 : 1;
  }
  if (auto rc = hysim::tools::runCut2dCommands(*cut2d_commands)) return *rc;
  if (auto rc = hysim::tools::runAccuracyCommand(*accuracy_command)) return *rc;
  if (auto rc = hysim::tools::runRunCommands(*run_commands)) return *rc;
  if (auto rc = hysim::tools::runSessionsCommands(*sessions_commands)) return *rc;
  if (auto rc = hysim::tools::runMeshCommand(*mesh_command)) return *rc;
  if (*stats_cmd) return statsCommand(stats_path, stats_json);
  return 1;
}
