// Meshing a generated organ with CGAL Mesh_3: a valid labelled mesh of good quality, the same
// bytes every time, a cache that returns it without meshing, and a simulation built on it.
// The organs here are meshed coarser than the scenes' (fine 2.5 mm) to keep the tests short.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "hysim/cutting/mesh_io.hpp"
#include "hysim/cutting/mesh_stats.hpp"
#include "hysim/engine/organ_mesh.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/simulation.hpp"

namespace hysim::engine {
namespace {

namespace fs = std::filesystem;

OrganSpec smallOrgan() {
  OrganSpec organ;
  organ.given = true;
  organ.mesh.fine_mm = 2.5;
  organ.mesh.coarse_mm = 5.0;
  MyomaSpec m;
  m.figo = "1";
  m.diameter_mm = 14;
  m.wall = MyomaWall::Posterior;
  m.height = 0.1;
  organ.myomas.push_back(m);
  return organ;
}

std::string freshDir(const std::string& name) {
  const fs::path dir = fs::path(HYSIM_TEST_OUTPUT_DIR) / name;
  fs::remove_all(dir);
  return dir.string();
}

std::string bytesOf(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(OrganMesh, ValidLabelledAndOfGoodQuality) {
  auto mesh = meshOrgan(smallOrgan());
  ASSERT_TRUE(mesh.ok()) << mesh.error();
  EXPECT_TRUE(cutting::validate(*mesh).ok());
  std::set<int> labels;
  for (int t = 0; t < mesh->numTets(); ++t) labels.insert(mesh->material(t));
  EXPECT_EQ(labels, (std::set<int>{kWallLabel, kFirstMyomaLabel}));
  const cutting::MeshStats s = cutting::computeStats(*mesh);
  EXPECT_GE(s.q_min, 0.05);
  EXPECT_GT(s.q_mean, 0.2);
  // The myoma's volume: a sphere of radius 7 (1437 mm3) within a few percent.
  double myoma = 0.0;
  for (int t = 0; t < mesh->numTets(); ++t) {
    if (mesh->material(t) == kFirstMyomaLabel) myoma += cutting::tetVolume(*mesh, t);
  }
  EXPECT_NEAR(myoma, 1436.8, 0.05 * 1436.8);
}

TEST(OrganMesh, WallBehindAnUncutMyomaIsTheWall) {
  auto mesh = meshOrgan(smallOrgan());
  ASSERT_TRUE(mesh.ok());
  const std::vector<double> wall = wallBehindMyomasMm(smallOrgan(), *mesh);
  ASSERT_EQ(wall.size(), 1u);
  // Uncut, the thinnest wall under the footprint is at its rim, where the endometrium is: the
  // 12 mm wall, a little less across the ellipsoids' curvature.
  EXPECT_GT(wall[0], 9.0);
  EXPECT_LT(wall[0], 12.5);
}

TEST(OrganMesh, SameOrganSameBytesAndTheCacheReturnsIt) {
  OrganMeshOptions a;
  a.cache_dir = freshDir("organ_cache_a");
  a.progress = false;
  OrganMeshOptions b = a;
  b.cache_dir = freshDir("organ_cache_b");
  auto first = organMeshFile(smallOrgan(), a);
  ASSERT_TRUE(first.ok()) << first.error();
  EXPECT_FALSE(first->cached);
  auto second = organMeshFile(smallOrgan(), b);
  ASSERT_TRUE(second.ok()) << second.error();
  EXPECT_EQ(bytesOf(first->path), bytesOf(second->path));
  auto again = organMeshFile(smallOrgan(), a);
  ASSERT_TRUE(again.ok());
  EXPECT_TRUE(again->cached);
  EXPECT_EQ(again->path, first->path);
  // Nothing but the mesh is left in the cache folder (no temporary file).
  int files = 0;
  for (const auto& e : fs::directory_iterator(a.cache_dir)) files += e.is_regular_file() ? 1 : 0;
  EXPECT_EQ(files, 1);
  // Another organ is another file.
  OrganSpec other = smallOrgan();
  other.myomas[0].diameter_mm = 12;
  auto third = organMeshFile(other, a);
  ASSERT_TRUE(third.ok());
  EXPECT_NE(third->path, first->path);
}

TEST(OrganMesh, UnusableCacheFolderIsSaid) {
  OrganMeshOptions o;
  o.cache_dir = "/dev/null/organs";
  o.progress = false;
  auto r = organMeshFile(smallOrgan(), o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("/dev/null/organs"), std::string::npos) << r.error();
}

TEST(OrganMesh, PeelingRemovesOnlyFlatSurfaceTets) {
  // A regular tet and, on one of its faces, a flat tet (three faces on the boundary).
  cutting::TetMesh m;
  m.X.resize(5, 3);
  m.X << 0, 0, 0, 1, 0, 0, 0.5, 0.8660254, 0, 0.5, 0.2886751, 0.8164966, 0.5, 0.2886751, -0.02;
  m.T.resize(2, 4);
  m.T << 0, 1, 2, 3, 0, 2, 1, 4;
  m.material.resize(2);
  m.material << 1, 1;
  ASSERT_TRUE(cutting::validate(m).ok());
  EXPECT_EQ(peelBoundarySlivers(m, 0.1), 1);
  ASSERT_EQ(m.numTets(), 1);
  EXPECT_EQ(m.numNodes(), 4);  // the flat tet's own node went with it
  EXPECT_NEAR(cutting::tetVolume(m, 0), 0.11785, 1e-4);
  EXPECT_TRUE(cutting::validate(m).ok());
  EXPECT_EQ(peelBoundarySlivers(m, 0.1), 0);  // a regular tet stays, even alone
}

TEST(OrganMesh, SimulationRunsOnAGeneratedOrgan) {
  const fs::path dir = fs::path(HYSIM_TEST_OUTPUT_DIR) / "organ_sim";
  fs::create_directories(dir);
  const fs::path path = dir / "organ.yaml";
  std::ofstream(path) << "name: generated\n"
                         "organ:\n"
                         "  myomas:\n"
                         "    - {figo: \"1\", diameter_mm: 14, wall: posterior, height: 0.1}\n"
                         "  mesh: {fine_mm: 2.5, coarse_mm: 5}\n"
                         "simulation: {steps: 200, max_substeps: 10}\n"
                         "tool_path: auto\n";
  auto scene = loadScene(path.string());
  ASSERT_TRUE(scene.ok()) << scene.error();
  ::setenv("HYSIM_CACHE_DIR", freshDir("organ_sim_cache").c_str(), 1);
  auto sim = Simulation::create(*scene);
  ::unsetenv("HYSIM_CACHE_DIR");
  ASSERT_TRUE(sim.ok()) << sim.error();
  EXPECT_FALSE((*sim)->scene().mesh_path.empty());
  int anchored = 0;
  for (auto f : (*sim)->model().fixed) anchored += f ? 1 : 0;
  EXPECT_GT(anchored, 0);
  EXPECT_LT(anchored, (*sim)->mesh().numNodes() / 2);
  EXPECT_GT((*sim)->outerWall().numFaces(), 100);
  EXPECT_NEAR((*sim)->initialMyomaVolume(), 1436.8, 0.05 * 1436.8);
  for (int i = 0; i < 200; ++i) (*sim)->step();
  EXPECT_EQ((*sim)->state().warnings, 0);
}

}  // namespace
}  // namespace hysim::engine
