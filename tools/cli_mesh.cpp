#include "cli_mesh.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <iostream>

#include "hysim/cutting/mesh_io.hpp"
#include "hysim/cutting/mesh_stats.hpp"
#include "hysim/engine/organ_mesh.hpp"
#include "hysim/engine/scene.hpp"
#include "organ_section.hpp"

namespace hysim::tools {
namespace {

namespace fs = std::filesystem;

// Mean edge length of the tets with a node within `band` mm of a myoma (near) and of the rest.
struct EdgeBands {
  double near_mean = 0.0, far_mean = 0.0;
};

EdgeBands edgeBands(const cutting::TetMesh& mesh, const engine::OrganSpec& organ) {
  const std::vector<engine::PlacedMyoma> placed = engine::placeMyomas(organ);
  double sum[2] = {0, 0};
  long count[2] = {0, 0};
  for (int t = 0; t < mesh.numTets(); ++t) {
    const Eigen::Vector3d c = 0.25 * (mesh.X.row(mesh.T(t, 0)) + mesh.X.row(mesh.T(t, 1)) + mesh.X.row(mesh.T(t, 2)) +
                                      mesh.X.row(mesh.T(t, 3))).transpose();
    const int k = engine::organSizeAt(organ, placed, c) <= organ.mesh.fine_mm + 1e-9 ? 0 : 1;
    for (int a = 0; a < 4; ++a) {
      for (int b = a + 1; b < 4; ++b) {
        sum[k] += (mesh.X.row(mesh.T(t, a)) - mesh.X.row(mesh.T(t, b))).norm();
        ++count[k];
      }
    }
  }
  return {count[0] ? sum[0] / count[0] : 0.0, count[1] ? sum[1] / count[1] : 0.0};
}

int copyTo(const std::string& from, const std::string& to) {
  const std::string tmp = to + ".tmp";
  std::error_code ec;
  fs::copy_file(from, tmp, fs::copy_options::overwrite_existing, ec);
  if (!ec) fs::rename(tmp, to, ec);
  if (ec) {
    const std::string why = ec.message();
    fs::remove(tmp, ec);
    std::fprintf(stderr, "hysim mesh: cannot write '%s': %s\n", to.c_str(), why.c_str());
    return 1;
  }
  return 0;
}

int meshCommand(const MeshArgs& a) {
  auto scene = engine::loadScene(a.scene);
  if (!scene.ok()) {
    std::fprintf(stderr, "hysim mesh: %s\n", scene.error().c_str());
    return 1;
  }
  if (!scene->organ.given) {
    std::fprintf(stderr, "hysim mesh: %s: the scene has no 'organ' section (it names a mesh file: %s)\n",
                 a.scene.c_str(), scene->mesh_path.c_str());
    return 1;
  }
  if (!a.section.empty()) {
    if (Status st = render::writePng(a.section, drawOrganSection(scene->organ, 320)); !st.ok()) {
      std::fprintf(stderr, "hysim mesh: %s\n", st.error().c_str());
      return 1;
    }
    if (a.section_only) return 0;
  }
  engine::OrganMeshOptions options;
  options.cache_dir = a.cache_dir;
  options.use_cache = !a.no_cache;
  options.progress = !a.json;
  auto file = engine::organMeshFile(scene->organ, options);
  if (!file.ok()) {
    std::fprintf(stderr, "hysim mesh: %s: %s\n", a.scene.c_str(), file.error().c_str());
    return 1;
  }
  auto mesh = cutting::readTetMesh(file->path);
  if (!mesh.ok()) {
    std::fprintf(stderr, "hysim mesh: %s\n", mesh.error().c_str());
    return 1;
  }
  if (!a.out.empty() && copyTo(file->path, a.out) != 0) return 1;
  const cutting::MeshStats s = cutting::computeStats(*mesh);
  const EdgeBands e = edgeBands(*mesh, scene->organ);
  nlohmann::ordered_json j;
  j["scene"] = a.scene;
  j["cache_file"] = file->path;
  j["cached"] = file->cached;
  j["mesh_s"] = file->seconds;
  j["nodes"] = s.nodes;
  j["tets"] = s.elements;
  j["edge_mean_near_myoma_mm"] = e.near_mean;
  j["edge_mean_far_mm"] = e.far_mean;
  j["q_min"] = s.q_min;
  j["q_mean"] = s.q_mean;
  j["dihedral_min_deg"] = s.dihedral_min_deg;
  if (a.json) {
    std::cout << j.dump(2) << "\n";
    return 0;
  }
  std::printf("%s: %d nodes, %d tets, %s in %.2f s\n", a.scene.c_str(), s.nodes, s.elements,
              file->cached ? "from the cache" : "meshed", file->seconds);
  std::printf("  edges: mean %.2f mm near the myomas, %.2f mm in the far wall; q*_min %.3f, q*_mean %.3f, "
              "min dihedral %.1f deg\n", e.near_mean, e.far_mean, s.q_min, s.q_mean, s.dihedral_min_deg);
  std::printf("  cache: %s\n", file->path.c_str());
  if (!a.out.empty()) std::printf("  wrote %s\n", a.out.c_str());
  return 0;
}

}  // namespace

std::shared_ptr<MeshCommand> addMeshCommand(CLI::App& app) {
  auto c = std::make_shared<MeshCommand>();
  c->mesh = app.add_subcommand("mesh", "Mesh a scene's generated organ (CGAL Mesh_3), or take it from the cache");
  c->mesh->add_option("scene", c->args.scene, "Scene file with an 'organ' section")->required();
  c->mesh->add_option("--out", c->args.out, "Write the mesh here too (Gmsh MSH 2.2)");
  c->mesh->add_option("--cache-dir", c->args.cache_dir, "Organ cache folder (default: $HYSIM_CACHE_DIR/organs, ...)");
  c->mesh->add_flag("--no-cache", c->args.no_cache, "Mesh even when the cache has this organ");
  c->mesh->add_flag("--json", c->args.json, "Print JSON");
  c->mesh->add_option("--section", c->args.section, "Write a picture (PNG) of the organ's section through the first myoma");
  c->mesh->add_flag("--section-only", c->args.section_only, "With --section: only the picture, no meshing");
  return c;
}

std::optional<int> runMeshCommand(const MeshCommand& c) {
  if (!*c.mesh) return std::nullopt;
  return meshCommand(c.args);
}

}  // namespace hysim::tools
