// The parametric organ: where FIGO types put a myoma, which material a point is, the graded
// sizes, the checks that refuse an organ (file, line and key named), and the planned course.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "hysim/engine/organ.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/shaving_path.hpp"
#include "hysim/haptics/trajectory.hpp"

namespace hysim::engine {
namespace {

namespace fs = std::filesystem;

OrganSpec oneMyoma(const std::string& figo, double diameter, MyomaWall wall = MyomaWall::Posterior) {
  OrganSpec organ;
  organ.given = true;
  MyomaSpec m;
  m.figo = figo;
  m.diameter_mm = diameter;
  m.wall = wall;
  m.height = 0.1667;
  organ.myomas.push_back(m);
  return organ;
}

std::string writeScene(const std::string& name, const std::string& organ_text) {
  const fs::path dir = fs::path(HYSIM_TEST_OUTPUT_DIR) / "organ_scenes";
  fs::create_directories(dir);
  const fs::path p = dir / name;
  std::ofstream(p) << "name: organ test\n"   // line 1
                   << "organ:\n"             // line 2
                   << organ_text             // from line 3
                   << "tool_path: auto\n";
  return p.string();
}

// Each call its own file: tests run in parallel processes.
void expectOrganError(const std::string& organ_text, int line, const std::string& what) {
  static int count = 0;
  const std::string name = std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
                           std::to_string(++count) + ".yaml";
  const std::string path = writeScene(name, organ_text);
  auto scene = loadScene(path);
  ASSERT_FALSE(scene.ok());
  EXPECT_NE(scene.error().find(path + ":" + std::to_string(line) + ":"), std::string::npos) << scene.error();
  EXPECT_NE(scene.error().find(what), std::string::npos) << scene.error();
}

TEST(Organ, Figo1SitsWhereTheDefaultAssetHasItsMyoma) {
  const OrganSpec organ = oneMyoma("1", 16);
  const std::vector<PlacedMyoma> p = placeMyomas(organ);
  ASSERT_EQ(p.size(), 1u);
  // assets/uterus_myoma.msh: radius 8 at (0, -9, 4), the endometrium at y = -10.85 there.
  EXPECT_NEAR(p[0].centre.x(), 0.0, 1e-9);
  EXPECT_NEAR(p[0].centre.y(), -8.85, 0.2);
  EXPECT_NEAR(p[0].centre.z(), 4.0, 0.3);
  EXPECT_NEAR(p[0].base.y(), -10.85, 0.01);
  EXPECT_LT(p[0].normal.y(), -0.99);
}

TEST(Organ, LabelsOfPoints) {
  const OrganSpec organ = oneMyoma("1", 16);
  const std::vector<PlacedMyoma> p = placeMyomas(organ);
  EXPECT_EQ(organLabel(organ, p, p[0].centre), kFirstMyomaLabel);
  EXPECT_EQ(organLabel(organ, p, Eigen::Vector3d(0, 0, 0)), 0);                // the cavity
  EXPECT_EQ(organLabel(organ, p, Eigen::Vector3d(0, 17, 0)), kWallLabel);      // anterior wall
  EXPECT_EQ(organLabel(organ, p, Eigen::Vector3d(0, 30, 0)), 0);               // beyond the serosa
  EXPECT_EQ(organLabel(organ, p, Eigen::Vector3d(0, 0, -30)), 0);              // the cervical canal
  EXPECT_EQ(organLabel(organ, p, Eigen::Vector3d(5, 0, -30)), kWallLabel);     // beside it
}

TEST(Organ, EveryTypeIsPlacedAsItsDefinitionSays) {
  // Each type's default offset must pass the type's own check (a contradiction is an error).
  const std::vector<std::pair<std::string, double>> cases = {
      {"0", 10}, {"1", 16}, {"2", 14}, {"3", 8}, {"4", 6}, {"5", 10}, {"6", 10}, {"7", 8}, {"2-5", 16}};
  for (const auto& [figo, d] : cases) {
    const std::vector<OrganProblem> problems = checkOrgan(oneMyoma(figo, d));
    EXPECT_TRUE(problems.empty()) << "FIGO " << figo << ": " << (problems.empty() ? "" : problems[0].message);
  }
}

TEST(Organ, SizesAreFineNearTheMyomaAndCoarseFarAway) {
  const OrganSpec organ = oneMyoma("2", 14);
  const std::vector<PlacedMyoma> p = placeMyomas(organ);
  EXPECT_DOUBLE_EQ(organSizeAt(organ, p, p[0].centre), 1.5);
  const Eigen::Vector3d near = p[0].centre + p[0].normal * (p[0].radius_mm + 2.5);
  EXPECT_DOUBLE_EQ(organSizeAt(organ, p, near), 1.5);
  EXPECT_DOUBLE_EQ(organSizeAt(organ, p, Eigen::Vector3d(0, 17, 30)), 4.0);
}

TEST(Organ, KeyChangesWithEveryParameter) {
  const OrganSpec a = oneMyoma("1", 16);
  OrganSpec b = a;
  b.myomas[0].height += 1e-9;
  OrganSpec c = a;
  c.mesh.fine_mm = 1.4;
  EXPECT_EQ(organKey(a), organKey(oneMyoma("1", 16)));
  EXPECT_NE(organKey(a), organKey(b));
  EXPECT_NE(organKey(a), organKey(c));
}

TEST(OrganScene, GeneratedScenesLoadWithMaterialsAnchorsAndACourse) {
  for (const char* name : {"figo0", "figo1", "figo2", "figo3", "figo4", "two_myomas", "thin_wall", "large_30mm"}) {
    const std::string path = std::string(HYSIM_SOURCE_DIR) + "/scenes/organs/" + name + ".yaml";
    auto scene = loadScene(path);
    ASSERT_TRUE(scene.ok()) << scene.error();
    EXPECT_TRUE(scene->organ.given);
    EXPECT_TRUE(scene->mesh_path.empty());
    EXPECT_EQ(scene->materials.size(), 1 + scene->organ.myomas.size()) << name;
    ASSERT_EQ(scene->anchors.size(), 1u);
    EXPECT_TRUE(scene->auto_tool_path);
    EXPECT_GT(scene->tool_path.size(), 10u) << name;
    EXPECT_GE(scene->steps, static_cast<int>(scene->tool_path.back().time_s / scene->sim.dt)) << name;
  }
}

// The loop's lowest point on every keyframe with the pedal pressed stays inside the serosa by
// the perforation margin.
TEST(OrganScene, PlannedCourseKeepsTheLoopOffTheSerosa) {
  for (const char* name : {"figo1", "figo3", "figo4", "thin_wall", "large_30mm"}) {
    auto scene = loadScene(std::string(HYSIM_SOURCE_DIR) + "/scenes/organs/" + name + ".yaml");
    ASSERT_TRUE(scene.ok()) << scene.error();
    const Eigen::Vector3d outer = outerSemiAxes(scene->organ.uterus);
    const ContactSettings& c = scene->contact;
    int active = 0;
    for (const haptics::Keyframe& k : scene->tool_path) {
      if (!k.pedal) continue;
      ++active;
      const Eigen::Matrix3d frame = haptics::frameFromAxisUp(k.axis, k.up);
      const Eigen::Vector3d bottom = k.tip + (c.loop_reach_mm + k.extension_mm) * k.axis -
                                     (c.loop_drop_mm + c.loop_radius_mm) * frame.col(1);
      const Eigen::Vector3d inner = outer - Eigen::Vector3d::Constant(scene->safety.perforation_margin_mm);
      EXPECT_LT((bottom.array() / inner.array()).matrix().squaredNorm(), 1.0) << name << " t " << k.time_s;
    }
    EXPECT_GT(active, 0) << name;
  }
}

TEST(OrganScene, BadOrgansNameTheLineAndTheKey) {
  // An unknown key, a value out of range, an unknown wall.
  expectOrganError("  myomas:\n    - {figo: \"1\", diameter_mm: 16, wall: posterior, colour: red}\n", 4, "unknown key 'colour'");
  expectOrganError("  myomas:\n    - figo: \"1\"\n      diameter_mm: 90\n      wall: posterior\n", 5,
                   "'diameter_mm' must be between 3 and 60");
  expectOrganError("  myomas:\n    - {figo: \"1\", diameter_mm: 16, wall: ceiling}\n", 4, "'wall' must be anterior");
  expectOrganError("  myomas:\n    - {figo: \"9\", diameter_mm: 16, wall: posterior}\n", 4, "'figo' must be 0 to 7");
  // A type 0 pushed into the wall: it contradicts its type.
  expectOrganError("  myomas:\n    - figo: \"0\"\n      diameter_mm: 10\n      wall: posterior\n      offset_mm: 3\n", 7,
                   "FIGO 0 myoma must lie wholly in the cavity");
  // Overlapping myomas: the second is named.
  expectOrganError("  myomas:\n    - {figo: \"1\", diameter_mm: 16, wall: posterior}\n"
                   "    - {figo: \"2\", diameter_mm: 12, wall: posterior, angle_deg: 10}\n", 5,
                   "organ.myomas[1].wall: the myoma overlaps organ.myomas[0]");
  // A myoma wholly outside the uterus.
  expectOrganError("  myomas:\n    - {figo: \"5\", diameter_mm: 8, wall: posterior, offset_mm: 40}\n", 4,
                   "outside the uterus");
  // A wall too thin for the mesh size.
  expectOrganError("  uterus:\n    wall_mm: 6\n  myomas:\n    - {figo: \"1\", diameter_mm: 8, wall: posterior}\n", 4,
                   "too thin for mesh.coarse_mm 4");
  // A submucous myoma that reaches the serosa.
  expectOrganError("  myomas:\n    - {figo: \"3\", diameter_mm: 10, wall: anterior}\n", 4, "1.5 mm from the serosa");
  // Both a mesh file and an organ.
  const std::string path = writeScene("both.yaml", "  myomas:\n    - {figo: \"1\", diameter_mm: 16, wall: posterior}\n"
                                                   "mesh: x.msh\n");
  auto both = loadScene(path);
  ASSERT_FALSE(both.ok());
  EXPECT_NE(both.error().find("either 'mesh' or 'organ'"), std::string::npos) << both.error();
}

TEST(OrganScene, AutoPathNeedsAnOrganAndAReachableMyoma) {
  expectOrganError("  myomas:\n    - {figo: \"6\", diameter_mm: 10, wall: posterior}\n", 5, "found no myoma the loop can reach");
}

}  // namespace
}  // namespace hysim::engine
