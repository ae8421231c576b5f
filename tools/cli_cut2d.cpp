#include "cli_cut2d.hpp"

#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "hysim/cutting/cut2d.hpp"
#include "hysim/cutting/mesh_io.hpp"
#include "hysim/cutting/mesh_stats.hpp"
#include "cli_cut3d.hpp"
#include "tables.hpp"
#include "tool_common.hpp"

namespace hysim::tools {

struct Cut2dCommands {
  CLI::App* cut = nullptr;
  CLI::App* tables = nullptr;
  std::string in, out, line, method = "hybrid", stats;
  std::string plane, surface;  // 3D cuts (cli_cut3d.cpp)
  int table = 0;
  Table1Options table1;
};

std::shared_ptr<Cut2dCommands> addCut2dCommands(CLI::App& app) {
  auto c = std::make_shared<Cut2dCommands>();
  c->cut = app.add_subcommand("cut", "Cut a planar triangle mesh along a segment (2D hybrid cutting and baselines)");
  // No CLI::ExistingFile check: the mesh readers name a missing file in the one-line error.
  c->cut->add_option("mesh", c->in, "Input mesh (.msh or .vtk; planar triangles, or tets with --plane / --surface)")
      ->required();
  c->cut->add_option("--line", c->line, "The cut segment x0,y0,x1,y1 (mm)");
  c->cut->add_option("--plane", c->plane, "Tet meshes: the cut plane px,py,pz,nx,ny,nz (mm)");
  c->cut->add_option("--surface", c->surface, "Tet meshes: an open cut surface (OBJ/STL/PLY, or .msh triangles)");
  c->cut->add_option("--method", c->method, "hybrid | standard | snap | delete (default hybrid)");
  c->cut->add_option("--out", c->out, "Output mesh (.msh or .vtk)")->required();
  c->cut->add_option("--stats", c->stats, "Write the output's statistics (hysim stats --json keys + time_ms) here");
  c->tables = app.add_subcommand("tables", "Regenerate a paper table (1: 2D hybrid cutting, 2: 3D hybrid cutting)");
  c->tables->add_option("--table", c->table, "Table number (1 or 2)")->required();
  c->tables->add_option("--json", c->table1.json_path, "Write the rows as JSON here");
  c->tables->add_option("--pictures", c->table1.pictures_dir, "Write PNG pictures of each mesh before/after here");
  c->tables->add_option("--meshes", c->table1.meshes_dir, "Write the DistMesh test meshes (.msh) here");
  c->tables->add_option("--repeats", c->table1.repeats, "Timed runs per cut (median reported)")->check(finiteRange(1, 1000));
  return c;
}

namespace {

int fail(const std::string& m) {
  std::cerr << "hysim: " << m << "\n";
  return 1;
}

int cutCommand(const Cut2dCommands& c) {
  cutting::Cut2DOptions o;
  if (!cutting::parseCutMethod(c.method, &o.method))
    return fail("--method: unknown method '" + c.method + "' (hybrid, standard, snap, delete)");
  auto parsed = parseNumberList("--line", c.line, 4, "x0,y0,x1,y1 (four numbers)", cutting::kMaxCoordinateMm);
  if (!parsed.ok()) return fail(parsed.error());
  const std::vector<double>& v = *parsed;
  auto mesh = cutting::readTriMesh(c.in);
  if (!mesh.ok()) return fail(mesh.error());
  if (!mesh->isPlanar()) return fail(c.in + ": not a planar mesh (z must be 0): hysim cut works on 2D meshes");
  if (Status st = cutting::validate(*mesh); !st.ok()) return fail(c.in + ": invalid mesh: " + st.error());
  const auto t0 = std::chrono::steady_clock::now();
  auto res = cutting::cut2d(*mesh, Eigen::Vector2d(v[0], v[1]), Eigen::Vector2d(v[2], v[3]), o);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (!res.ok()) return fail(res.error());
  if (Status st = cutting::writeMesh(c.out, res->mesh); !st.ok()) return fail(st.error());
  const auto s = cutting::computeStats(res->mesh);
  const auto& r = res->report;
  std::printf("%s cut: %d -> %d nodes, %d -> %d triangles; %d crossed edges, %d displaced, %d subdivided, %d flips, "
              "%d collapsed, %d duplicated; q_min %.3f; %.3f ms (optimisation %.3f ms)\n",
              cutting::cutMethodName(o.method), mesh->numNodes(), res->mesh.numNodes(), mesh->numTris(),
              res->mesh.numTris(), r.crossed_edges, r.displaced_nodes, r.subdivided_edges, r.edge_flips,
              r.collapsed_edges, r.duplicated_nodes, s.q_min, ms, r.optimize_ms);
  if (!c.stats.empty()) {
    nlohmann::ordered_json j = tools::statsJson(s);
    j["time_ms"] = ms;
    j["optimize_ms"] = r.optimize_ms;
    j["method"] = cutting::cutMethodName(o.method);
    j["distinct_positions"] = cutting::countDistinctPositions(res->mesh);
    std::ofstream out(c.stats);
    if (!out) return fail("cannot write '" + c.stats + "'");
    out << j.dump(2) << "\n";
  }
  return 0;
}

}  // namespace

std::optional<int> runCut2dCommands(const Cut2dCommands& c) {
  if (c.cut && *c.cut) {
    if (!c.plane.empty() || !c.surface.empty())
      return runCut3d(Cut3dArgs{c.in, c.out, c.plane, c.surface, c.method, c.stats});
    if (c.line.empty()) return fail("cut: give --line (triangle meshes) or --plane / --surface (tet meshes)");
    return cutCommand(c);
  }
  if (c.tables && *c.tables) {
    if (c.table == 2) {
      Table2Options t2;
      t2.json_path = c.table1.json_path;
      t2.pictures_dir = c.table1.pictures_dir;
      if (c.tables->count("--repeats") > 0) t2.repeats = c.table1.repeats;
      return runTable2(t2);
    }
    if (c.table != 1) return fail("--table: only tables 1 and 2 are implemented");
    return runTable1(c.table1);
  }
  return std::nullopt;
}

}  // namespace hysim::tools
