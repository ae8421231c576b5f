// Perforation: the serosa (outer uterine surface) is found among the boundary faces, the
// signed distance to it is right, and the check fires on the careless type 2 scene, not on
// the careful one, without allocating in the step.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "alloc_counter.hpp"
#include "box_mesh.hpp"
#include "hysim/cutting/mesh_io.hpp"
#include "hysim/engine/outer_wall.hpp"
#include "hysim/engine/run.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/simulation.hpp"

namespace hysim::engine {
namespace {

namespace fs = std::filesystem;

const std::string kSource = HYSIM_SOURCE_DIR;

// Value of the outer ellipsoid's implicit function (1 on the surface).
double outerEllipsoid(const Eigen::Vector3d& p) {
  return std::sqrt(std::pow(p.x() / 28.0, 2) + std::pow(p.y() / 23.0, 2) + std::pow(p.z() / 36.0, 2));
}

// Anchored like the scenes: outside the ellipsoid (25, 20, 33).
std::vector<std::uint8_t> sceneAnchors(const cutting::TetMesh& mesh) {
  std::vector<std::uint8_t> fixed(static_cast<size_t>(mesh.numNodes()), 0);
  for (int i = 0; i < mesh.numNodes(); ++i) {
    const Eigen::Vector3d p = mesh.X.row(i).transpose();
    fixed[static_cast<size_t>(i)] = std::pow(p.x() / 25, 2) + std::pow(p.y() / 20, 2) + std::pow(p.z() / 33, 2) >= 1.0;
  }
  return fixed;
}

class UterusSerosa : public ::testing::TestWithParam<const char*> {};

// The serosal faces are exactly the boundary faces on the outer ellipsoid (not the cavity,
// the myoma or the canal, which joins the cavity to the outer surface).
TEST_P(UterusSerosa, IsTheOuterEllipsoid) {
  auto mesh = cutting::readTetMesh(kSource + "/assets/" + GetParam());
  ASSERT_TRUE(mesh.ok()) << mesh.error();
  OuterWall wall;
  wall.build(*mesh, sceneAnchors(*mesh), 2.15);
  const cutting::Tris boundary = cutting::boundaryFaces(*mesh);
  int on_outer = 0;
  for (int f = 0; f < boundary.rows(); ++f) {
    bool all = true;
    for (int c = 0; c < 3; ++c) all = all && std::abs(outerEllipsoid(mesh->X.row(boundary(f, c)).transpose()) - 1.0) < 1e-3;
    on_outer += all ? 1 : 0;
  }
  EXPECT_GT(on_outer, 1000);
  EXPECT_EQ(wall.numFaces(), on_outer);
  for (int v = 0; v < wall.vertices().rows(); ++v) {
    EXPECT_NEAR(outerEllipsoid(wall.vertices().row(v).transpose()), 1.0, 1e-3) << "vertex " << v;
  }
  EXPECT_TRUE(wall.isStatic());  // the outer 3 mm are anchored
}

INSTANTIATE_TEST_SUITE_P(Assets, UterusSerosa, ::testing::Values("uterus_myoma.msh", "uterus_myoma_type2.msh"));

TEST(OuterWall, SignedDistanceInsideAndBeyond) {
  auto mesh = cutting::readTetMesh(kSource + "/assets/uterus_myoma_type2.msh");
  ASSERT_TRUE(mesh.ok()) << mesh.error();
  OuterWall wall;
  wall.build(*mesh, sceneAnchors(*mesh), 2.15);
  // Posterior wall at z = 4: the serosa is at y = -23 sqrt(1 - (4/36)^2) = -22.86; its
  // normal there is nearly -y. Facets lie inside the ellipsoid by < 0.2 mm.
  EXPECT_NEAR(wall.signedDistance({0, -21.0, 4}), 1.86, 0.2);
  EXPECT_NEAR(wall.signedDistance({0, -24.0, 4}), -1.14, 0.2);
  EXPECT_GT(wall.signedDistance({0, 0, 0}), 20.0);  // cavity centre
  EXPECT_LT(wall.signedDistance({0, 0, 50}), -10.0);  // above the fundus
}

// The grid only skips points that are surely farther inside than the band.
TEST(OuterWall, ClearanceAgreesWithSignedDistanceInTheBand) {
  auto mesh = cutting::readTetMesh(kSource + "/assets/uterus_myoma_type2.msh");
  ASSERT_TRUE(mesh.ok()) << mesh.error();
  OuterWall wall;
  const double band = 2.15;
  wall.build(*mesh, sceneAnchors(*mesh), band);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> ux(-32, 32), uy(-27, 27), uz(-40, 40);
  int in_band = 0, skipped = 0;
  for (int i = 0; i < 4000; ++i) {
    const Eigen::Vector3d p(ux(rng), uy(rng), uz(rng));
    const double sd = wall.signedDistance(p);
    const double cl = wall.clearance(p);
    if (sd < band) {
      ++in_band;
      EXPECT_DOUBLE_EQ(cl, sd) << p.transpose();
    } else {
      EXPECT_GE(cl, band) << p.transpose();
    }
    skipped += cl == band && sd != band ? 1 : 0;
  }
  EXPECT_GT(in_band, 500);
  EXPECT_GT(skipped, 200);  // the grid does spare queries
}

// A slab has no cavity: all of its boundary looks into free space. Its free nodes move, and
// so does the surface.
TEST(OuterWall, MovingSurfaceFollowsTheNodes) {
  cutting::TetMesh slab = testing::boxTetMesh(4, 3, 2, 2.0);
  std::vector<std::uint8_t> fixed(static_cast<size_t>(slab.numNodes()), 0);
  for (int i = 0; i < slab.numNodes(); ++i) fixed[static_cast<size_t>(i)] = slab.X(i, 2) == 0.0;
  OuterWall wall;
  wall.build(slab, fixed, 1.0);
  EXPECT_EQ(wall.numFaces(), wall.numBoundaryFaces());
  EXPECT_FALSE(wall.isStatic());
  EXPECT_NEAR(wall.signedDistance({4, 3, 3.5}), 0.5, 1e-12);   // inside, 0.5 below the top
  EXPECT_NEAR(wall.signedDistance({4, 3, 5.0}), -1.0, 1e-12);  // 1 above the top
  sim::NodeVectors x(slab.numNodes(), 3);
  for (int i = 0; i < slab.numNodes(); ++i) x.row(i) = slab.X.row(i);
  for (int i = 0; i < slab.numNodes(); ++i) {
    if (slab.X(i, 2) == 4.0) x(i, 2) = 6.0;  // the top rises by 2
  }
  wall.update(x);
  EXPECT_NEAR(wall.signedDistance({4, 3, 5.0}), 1.0, 1e-12);
  // The grid (made for the rest shape) stays right for the moved surface: it keeps a slack.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-2, 10);
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    const double sd = wall.signedDistance(p);
    if (sd < 1.0) EXPECT_DOUBLE_EQ(wall.clearance(p), sd) << p.transpose();
    else EXPECT_GE(wall.clearance(p), 1.0) << p.transpose();
  }
}

// The scene minus the keyframes before `from`, shifted to start at t = 0.
Scene fromKeyframe(Scene scene, size_t from) {
  const double t0 = scene.tool_path[from].time_s;
  scene.tool_path.erase(scene.tool_path.begin(), scene.tool_path.begin() + static_cast<std::ptrdiff_t>(from));
  for (auto& k : scene.tool_path) k.time_s -= t0;
  return scene;
}

// The careless pass of scenes/type2_perforation.yaml (from its 8th keyframe): pedal down at
// 1.05 s, the script swings the loop to 1 mm from the serosa by 1.55 s (the coupling lets the
// tissue hold it at about 1.3 mm), drawn back until 2.55 s.
TEST(Perforation, CarelessPassBehindTheType2MyomaPerforates) {
  auto scene = loadScene(kSource + "/scenes/type2_perforation.yaml");
  ASSERT_TRUE(scene.ok()) << scene.error();
  ASSERT_EQ(scene->tool_path.size(), 15u);
  auto sim = Simulation::create(fromKeyframe(*scene, 7));
  ASSERT_TRUE(sim.ok()) << sim.error();
  EXPECT_TRUE((*sim)->outerWall().isStatic());
  for (int i = 0; i < 1050; ++i) (*sim)->step();
  EXPECT_EQ((*sim)->perforations(), 0);
  int first = -1;
  for (int i = 1050; i < 1650 && first < 0; ++i) {
    (*sim)->step();
    if ((*sim)->perforating()) first = i;
  }
  ASSERT_GE(first, 0) << "no perforation event";
  EXPECT_EQ((*sim)->perforations(), 1);
  EXPECT_LT((*sim)->serosaClearanceMm(), 2.0);
  // The check allocates nothing while the loop cuts near the serosa.
  long count = 0;
  {
    testing::AllocationCounter counter;
    for (int i = 0; i < 50; ++i) (*sim)->step();
    count = counter.count();
  }
  EXPECT_EQ(count, 0);
  EXPECT_TRUE((*sim)->loopInTissue());
  // The rest of the pass through the report: one event, its closest approach within the
  // margin (about 1.3 mm: the coupling lets the tissue hold the loop back a little).
  RunOptions options;
  options.steps = 1200;
  auto report = run(**sim, options);
  ASSERT_TRUE(report.ok()) << report.error();
  EXPECT_EQ(report->perforations, 1);
  ASSERT_EQ(report->perforation_events.size(), 1u);
  const PerforationEvent& e = report->perforation_events[0];
  EXPECT_NEAR(e.time_s, 0.001 * (first + 1), 1e-9);
  EXPECT_GT(e.end_s, e.time_s);
  EXPECT_LT(e.end_s, 2.6);  // over once the pedal is up
  EXPECT_LT(e.min_distance_mm, 1.5);
  EXPECT_GT(e.min_distance_mm, 0.0);  // close, but not through
  EXPECT_EQ(report->state_hash != 0, true);
  EXPECT_EQ(report->warnings, 0);

  const std::string json = reportJson(*report);
  for (const char* key : {"\"perforations\": 1", "\"perforation_events\"", "\"min_distance_mm\"",
                          "\"perforation_margin_mm\": 2.0", "\"serosa_faces\"", "\"cut_ms\"", "\"passes\": 1"}) {
    EXPECT_NE(json.find(key), std::string::npos) << key << " missing in\n" << json;
  }
  const std::string text = summaryText(*report);
  EXPECT_NE(text.find("perforations      1"), std::string::npos) << text;
  EXPECT_NE(text.find("myoma resected"), std::string::npos) << text;
  // The scene's assessment allows no perforation: safety is not met, the run fails.
  const Assessment& a = summarize(*report).assessment;
  EXPECT_FALSE(a.passed);
  for (const AssessmentItem& i : a.items) {
    if (i.name == "safety") {
      EXPECT_FALSE(i.passed);
    } else if (i.name == "time") {
      EXPECT_TRUE(i.passed);
    }
  }
  EXPECT_NE(json.find("\"assessment\": {"), std::string::npos);
  EXPECT_NE(text.find("FAIL"), std::string::npos) << text;
}

// The deepest pass of scenes/type2_safe.yaml (pass 4, from its 22nd keyframe) stays clear.
TEST(Perforation, CarefulPassOverTheType2MyomaDoesNot) {
  auto scene = loadScene(kSource + "/scenes/type2_safe.yaml");
  ASSERT_TRUE(scene.ok()) << scene.error();
  ASSERT_EQ(scene->tool_path.size(), 29u);
  auto sim = Simulation::create(fromKeyframe(*scene, 21));
  ASSERT_TRUE(sim.ok()) << sim.error();
  bool cut = false;
  for (int i = 0; i < 2500; ++i) {
    (*sim)->step();
    cut = cut || (*sim)->loopInTissue();
    ASSERT_FALSE((*sim)->perforating()) << "step " << i << ": clearance " << (*sim)->serosaClearanceMm();
  }
  EXPECT_TRUE(cut);
  ASSERT_EQ((*sim)->passes().size(), 1u);
  EXPECT_GT((*sim)->passes()[0].removed_myoma_mm3, 1.0);
  EXPECT_EQ((*sim)->perforations(), 0);
  EXPECT_GE((*sim)->serosaClearanceMm(), 2.0);
}

std::string writeScene(const std::string& name, const std::string& safety) {
  const fs::path dir = fs::path(HYSIM_TEST_OUTPUT_DIR) / "perforation";
  fs::create_directories(dir);
  const fs::path p = dir / name;
  std::ofstream(p) << "name: test\n"
                      "mesh: " << kSource << "/assets/uterus_myoma.msh\n"
                      "materials:\n"
                      "  - {name: myometrium, label: 1, young_modulus_kpa: 60, density_g_cm3: 1.05}\n"
                      "safety:\n"
                   << safety
                   << "tool_path:\n"
                      "  - {t_s: 0, tip: [0, 2, -24], axis: [0, 0, 1]}\n";
  return p.string();
}

TEST(Perforation, MarginKeyIsChecked) {
  auto ok = loadScene(writeScene("ok.yaml", "  perforation_margin_mm: 1.5\n"));
  ASSERT_TRUE(ok.ok()) << ok.error();
  EXPECT_DOUBLE_EQ(ok->safety.perforation_margin_mm, 1.5);
  auto defaults = loadScene(kSource + "/scenes/default.yaml");
  ASSERT_TRUE(defaults.ok()) << defaults.error();
  EXPECT_DOUBLE_EQ(defaults->safety.perforation_margin_mm, 2.0);

  const std::string neg = writeScene("negative.yaml", "  perforation_margin_mm: -1\n");
  auto bad = loadScene(neg);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error(), neg + ":6: 'perforation_margin_mm' must not be negative, got -1");
  const std::string word = writeScene("word.yaml", "  perforation_margin_mm: wide\n");
  bad = loadScene(word);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error(), word + ":6: 'perforation_margin_mm' must be a number, got 'wide'");
  const std::string unknown = writeScene("unknown.yaml", "  perforation_margin: 2\n");
  bad = loadScene(unknown);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find(unknown + ":6: unknown key 'perforation_margin' in 'safety'"), std::string::npos) << bad.error();
}

}  // namespace
}  // namespace hysim::engine
