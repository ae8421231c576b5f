// Scene files: the default scene loads; every kind of bad input gives a one-line message
// naming the file and the line (or the value), never a crash.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "hysim/engine/scene.hpp"
#include "hysim/engine/simulation.hpp"

namespace hysim::engine {
namespace {

namespace fs = std::filesystem;

const std::string kAssets = std::string(HYSIM_SOURCE_DIR) + "/assets";

std::string writeFile(const std::string& name, const std::string& text) {
  const fs::path dir = fs::path(HYSIM_TEST_OUTPUT_DIR) / "scenes";
  fs::create_directories(dir);
  const fs::path p = dir / name;
  std::ofstream(p) << text;
  return p.string();
}

// A valid minimal scene; tests replace one line to break it.
std::string minimalScene(const std::string& mesh = kAssets + "/uterus_myoma.msh") {
  return "name: test\n"                                             // line 1
         "mesh: " + mesh + "\n"                                     // line 2
         "materials:\n"                                             // line 3
         "  - {name: myometrium, label: 1, young_modulus_kpa: 60, density_g_cm3: 1.05}\n"  // 4
         "  - {name: myoma, label: 2, young_modulus_kpa: 150, density_g_cm3: 1.1}\n"       // 5
         "simulation:\n"                                            // line 6
         "  dt_ms: 1.0\n"                                           // line 7
         "  steps: 10\n"                                            // line 8
         "tool_path:\n"                                             // line 9
         "  - {t_s: 0, tip: [0, 2, -24], axis: [0, 0, 1]}\n";       // line 10
}

std::string replaceLine(std::string text, int line, const std::string& replacement) {
  size_t start = 0;
  for (int i = 1; i < line; ++i) start = text.find('\n', start) + 1;
  const size_t end = text.find('\n', start);
  return text.replace(start, end - start, replacement);
}

void expectError(const std::string& file_name, const std::string& text, const std::string& where,
                 const std::string& what) {
  const std::string path = writeFile(file_name, text);
  auto scene = loadScene(path);
  ASSERT_FALSE(scene.ok()) << file_name << " should fail";
  const std::string& msg = scene.error();
  EXPECT_NE(msg.find(path + where), std::string::npos) << msg;
  EXPECT_NE(msg.find(what), std::string::npos) << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos) << "one line: " << msg;
}

TEST(Scene, DefaultSceneLoads) {
  auto scene = loadScene(std::string(HYSIM_SOURCE_DIR) + "/scenes/default.yaml");
  ASSERT_TRUE(scene.ok()) << scene.error();
  EXPECT_EQ(scene->name, "default");
  EXPECT_EQ(scene->materials.size(), 2u);
  EXPECT_DOUBLE_EQ(scene->sim.dt, 1e-3);
  EXPECT_GE(scene->tool_path.size(), 2u);
  EXPECT_TRUE(fs::exists(scene->mesh_path));
  int pedal = 0;  // the default scene shaves: at least 10 passes with the cut pedal down
  for (size_t k = 1; k < scene->tool_path.size(); ++k)
    pedal += scene->tool_path[k].pedal && !scene->tool_path[k - 1].pedal;
  EXPECT_GE(pedal, 10);
  for (const char* other : {"/scenes/diagnostic.yaml", "/scenes/shaving.yaml"}) {
    auto s = loadScene(std::string(HYSIM_SOURCE_DIR) + other);
    EXPECT_TRUE(s.ok()) << other << ": " << s.error();
  }
}

TEST(Scene, MinimalSceneLoadsWithDefaults) {
  auto scene = loadScene(writeFile("minimal.yaml", minimalScene()));
  ASSERT_TRUE(scene.ok()) << scene.error();
  EXPECT_EQ(scene->steps, 10);
  EXPECT_EQ(scene->render.width, 640);
  EXPECT_NEAR(scene->materials[1].young_modulus_pa, 150e3, 1e-9);
  EXPECT_NEAR(scene->materials[1].density_g_mm3, 1.1e-3, 1e-15);
}

TEST(Scene, AssessmentAndCaseParse) {
  const std::string text = minimalScene() +
                           "figo_type: 2-5\n"
                           "difficulty: advanced\n"
                           "assessment:\n"
                           "  min_resected_pct: 70\n"
                           "  max_healthy_removed_mm3: 120\n"
                           "  perforations_allowed: 1\n"
                           "  time_limit_s: 300\n"
                           "  weights: {resection: 1, healthy: 0, safety: 2, time: 0.5}\n";
  auto scene = loadScene(writeFile("assessment.yaml", text));
  ASSERT_TRUE(scene.ok()) << scene.error();
  EXPECT_EQ(scene->figo_type, "2-5");
  EXPECT_EQ(scene->difficulty, "advanced");
  EXPECT_EQ(scene->assessment.min_resected_pct, 70.0);
  EXPECT_EQ(scene->assessment.max_healthy_removed_mm3, 120.0);
  EXPECT_EQ(scene->assessment.perforations_allowed, 1);
  EXPECT_EQ(scene->assessment.time_limit_s, 300.0);
  EXPECT_EQ(scene->assessment.weights.safety, 2.0);
  EXPECT_EQ(scene->assessment.weights.healthy, 0.0);
  // Without the section: the documented defaults.
  auto plain = loadScene(writeFile("no_assessment.yaml", minimalScene()));
  ASSERT_TRUE(plain.ok()) << plain.error();
  EXPECT_EQ(plain->assessment.min_resected_pct, AssessmentSettings{}.min_resected_pct);
  EXPECT_TRUE(plain->figo_type.empty());
}

TEST(Scene, ParsingTextInMemoryResolvesPathsAgainstTheNamedFolder) {
  auto scene = parseScene(minimalScene("uterus_myoma.msh"), kAssets + "/memory.yaml");
  ASSERT_TRUE(scene.ok()) << scene.error();
  EXPECT_EQ(scene->mesh_path, kAssets + "/uterus_myoma.msh");
  auto bad = parseScene("name: [", "memory.yaml");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().rfind("memory.yaml:", 0), 0u) << bad.error();
}

TEST(SceneErrors, BadAssessmentOrCase) {
  const std::string base = minimalScene() + "assessment:\n";  // line 11
  expectError("assess_pct.yaml", base + "  min_resected_pct: 120\n", ":12:", "'min_resected_pct' must be at most 100");
  expectError("assess_neg.yaml", base + "  time_limit_s: -5\n", ":12:", "'time_limit_s' must be positive");
  expectError("assess_key.yaml", base + "  max_time: 5\n", ":12:", "unknown key 'max_time' in 'assessment'");
  expectError("assess_perf.yaml", base + "  perforations_allowed: 1.5\n", ":12:", "'perforations_allowed' must be an integer");
  expectError("assess_w.yaml", base + "  weights: {resection: 0, healthy: 0, safety: 0, time: 0}\n", ":12:",
              "'assessment.weights' must not all be 0");
  expectError("assess_nan.yaml", base + "  weights: {time: .nan}\n", ":12:", "'time' must be finite");
  expectError("figo.yaml", minimalScene() + "figo_type: 9\n", ":11:", "'figo_type' must be 0 to 7 or 2-5, got '9'");
  expectError("difficulty.yaml", minimalScene() + "difficulty: hard\n", ":11:", "'difficulty' must be beginner");
}

TEST(SceneErrors, BadYaml) {
  expectError("bad_yaml.yaml", replaceLine(minimalScene(), 7, "  dt_ms: [1.0"), ":", "YAML error");
}

TEST(SceneErrors, UnknownKey) {
  expectError("unknown_key.yaml", replaceLine(minimalScene(), 7, "  dt_msec: 1.0"), ":7:",
              "unknown key 'dt_msec' in 'simulation'");
}

TEST(SceneErrors, UnknownTopLevelKey) {
  expectError("unknown_top.yaml", minimalScene() + "colour: red\n", ":11:", "unknown key 'colour'");
}

TEST(SceneErrors, WrongType) {
  expectError("wrong_type.yaml", replaceLine(minimalScene(), 8, "  steps: many"), ":8:",
              "'steps' must be an integer, got 'many'");
}

TEST(SceneErrors, WrongVectorShape) {
  expectError("wrong_vec.yaml", replaceLine(minimalScene(), 10, "  - {t_s: 0, tip: [0, 2], axis: [0, 0, 1]}"), ":10:",
              "'tip' must be a list of 3 numbers");
}

TEST(SceneErrors, NanValue) {
  expectError("nan_value.yaml", replaceLine(minimalScene(), 7, "  dt_ms: .nan"), ":7:", "'dt_ms' must be finite");
}

TEST(SceneErrors, NegativeValue) {
  expectError("negative.yaml",
              replaceLine(minimalScene(), 4, "  - {name: myometrium, label: 1, young_modulus_kpa: -60, density_g_cm3: 1.05}"),
              ":4:", "'young_modulus_kpa' must be positive");
}

TEST(SceneErrors, LoopExtensionOutOfRange) {
  expectError("extension.yaml",
              replaceLine(minimalScene(), 10, "  - {t_s: 0, tip: [0, 0, 0], axis: [0, 0, 1], extension_mm: 120}"), ":10:",
              "'extension_mm' must be in [0, 100]");
}

TEST(SceneErrors, MissingRequiredKey) {
  expectError("missing_key.yaml", replaceLine(minimalScene(), 1, "# no name"), ":", "missing required key 'name'");
}

TEST(SceneErrors, MissingMeshFile) {
  expectError("missing_mesh.yaml", minimalScene("/nonexistent/uterus.msh"), ":2:",
              "'mesh' file '/nonexistent/uterus.msh' does not exist");
}

TEST(SceneErrors, UnknownIntegrator) {
  expectError("integrator.yaml", replaceLine(minimalScene(), 8, "  integrator: rk4"), ":8:",
              "'integrator' must be symplectic_euler, implicit_euler or xpbd, got 'rk4'");
}

TEST(Scene, XpbdIntegratorParses) {
  std::string text = replaceLine(minimalScene(), 8, "  integrator: xpbd\n  xpbd_substeps: 12\n  xpbd_iterations: 2");
  auto scene = loadScene(writeFile("xpbd.yaml", text));
  ASSERT_TRUE(scene.ok()) << scene.error();
  EXPECT_EQ(scene->sim.integrator, sim::Integrator::Xpbd);
  EXPECT_EQ(scene->sim.xpbd_substeps, 12);
  EXPECT_EQ(scene->sim.xpbd_iterations, 2);
  text = replaceLine(minimalScene(), 8, "  integrator: xpbd\n  xpbd_substeps: auto");
  auto automatic = loadScene(writeFile("xpbd_auto.yaml", text));
  ASSERT_TRUE(automatic.ok()) << automatic.error();
  EXPECT_EQ(automatic->sim.xpbd_substeps, 0);
  EXPECT_EQ(automatic->sim.xpbd_iterations, 1);
  // The scene runs: the tool moves through the tissue with XPBD steps, no warning.
  auto sim = Simulation::create(*scene);
  ASSERT_TRUE(sim.ok()) << sim.error();
  EXPECT_EQ((*sim)->model().substeps, 12);
  for (int i = 0; i < 20; ++i) (*sim)->step();
  EXPECT_EQ((*sim)->state().warnings, 0);
  EXPECT_TRUE((*sim)->state().x.allFinite());
}

TEST(SceneErrors, BadXpbdValues) {
  expectError("xpbd_name.yaml", replaceLine(minimalScene(), 8, "  integrator: XPBD2"), ":8:",
              "'integrator' must be symplectic_euler, implicit_euler or xpbd, got 'XPBD2'");
  expectError("xpbd_substeps.yaml", replaceLine(minimalScene(), 8, "  xpbd_substeps: 0"), ":8:",
              "'xpbd_substeps' must be between 1 and 10000, got 0");
  expectError("xpbd_iterations.yaml", replaceLine(minimalScene(), 8, "  xpbd_iterations: many"), ":8:",
              "'xpbd_iterations' must be an integer, got 'many'");
}

TEST(Scene, CouplingParses) {
  auto scene = loadScene(writeFile("coupling.yaml", minimalScene() + "coupling: {mode: rigid, stiffness_n_per_mm: 0.5}\n"));
  ASSERT_TRUE(scene.ok()) << scene.error();
  EXPECT_EQ(scene->coupling.mode, CouplingSettings::Mode::Rigid);
  EXPECT_DOUBLE_EQ(scene->coupling.stiffness_n_per_mm, 0.5);
  EXPECT_DOUBLE_EQ(scene->coupling.damping_n_s_per_mm, 0.0);  // the default: from the passivity bound
}

TEST(SceneErrors, BadCoupling) {
  expectError("coupling_mode.yaml", minimalScene() + "coupling: {mode: glue}\n", ":11:",
              "'coupling.mode' must be spring or rigid, got 'glue'");
  expectError("coupling_k.yaml", minimalScene() + "coupling: {stiffness_n_per_mm: -1}\n", ":11:",
              "'stiffness_n_per_mm' must be positive");
}

TEST(SceneErrors, TimeGoesBackwards) {
  expectError("backwards.yaml", minimalScene() + "  - {t_s: -1, tip: [0, 0, 0], axis: [0, 0, 1]}\n", ":11:",
              "'t_s' must not be negative");
}

TEST(Scene, ArcMoveParses) {
  auto scene = loadScene(writeFile("arc.yaml", minimalScene() +
      "  - {t_s: 1, tip: [10, 2, -14], axis: [0, 0, 1], move: arc, arc_center: [0, 2, -14]}\n"));
  ASSERT_TRUE(scene.ok()) << scene.error();
  EXPECT_EQ(scene->tool_path[1].move, haptics::Keyframe::Move::Arc);
}

TEST(SceneErrors, ArcWithoutCentreOrUndefined) {
  expectError("arc_nocenter.yaml", minimalScene() + "  - {t_s: 1, tip: [10, 2, -14], axis: [0, 0, 1], move: arc}\n",
              ":11:", "missing required key 'arc_center'");
  expectError("arc_180.yaml",
              minimalScene() + "  - {t_s: 1, tip: [0, 2, -4], axis: [0, 0, 1], move: arc, arc_center: [0, 2, -14]}\n",
              ":11:", "arc from the previous tip");
  expectError("arc_move.yaml", minimalScene() + "  - {t_s: 1, tip: [0, 2, -4], axis: [0, 0, 1], move: spiral}\n",
              ":11:", "'move' must be linear or arc, got 'spiral'");
}

TEST(SceneErrors, EmptyFileAndMissingFile) {
  expectError("empty.yaml", "", ":", "empty");
  auto scene = loadScene("/nonexistent/scene.yaml");
  ASSERT_FALSE(scene.ok());
  EXPECT_EQ(scene.error(), "cannot open '/nonexistent/scene.yaml': No such file or directory");
}

// Names and descriptions go into the JSON report, whose writer refuses bytes that are not
// UTF-8 (after the whole run): refused when the scene is loaded, with file and line.
TEST(SceneErrors, TextThatIsNotUtf8) {
  expectError("latin1_name.yaml", replaceLine(minimalScene(), 1, "name: caf\xe9"), ":1:",
              "'name' is not valid UTF-8: byte 0xe9 at offset 3 of the value");
  expectError("bad_description.yaml", minimalScene() + "description: \"ok \xc3\"\n", ":11:",
              "'description' is not valid UTF-8: byte 0xc3 at offset 3");
  expectError("bad_material.yaml",
              replaceLine(minimalScene(), 5,
                          "  - {name: \"my\xffoma\", label: 2, young_modulus_kpa: 150, density_g_cm3: 1.1}"),
              ":5:", "'materials[1].name' is not valid UTF-8: byte 0xff at offset 2");
  expectError("bad_key.yaml", minimalScene() + "caf\xe9: 1\n", ":11:", "a key in 'scene' is not valid UTF-8: byte 0xe9");
  // Valid UTF-8 is welcome.
  const std::string path = writeFile("utf8_name.yaml", replaceLine(minimalScene(), 1, "name: caf\xc3\xa9 \xe2\x80\x93 myome"));
  const auto scene = loadScene(path);
  ASSERT_TRUE(scene.ok()) << scene.error();
  EXPECT_EQ(scene->name, "caf\xc3\xa9 \xe2\x80\x93 myome");
}

// YAML parsers keep one of two equal keys silently; a scene with one is refused.
TEST(SceneErrors, DuplicateKeys) {
  expectError("dup_top.yaml", minimalScene() + "name: again\n", ":11:", "duplicate key 'name' in 'scene'");
  expectError("dup_nested.yaml", replaceLine(minimalScene(), 7, "  dt_ms: 1.0\n  dt_ms: 2.0"), ":8:",
              "duplicate key 'dt_ms' in 'simulation'");
  expectError("dup_flow.yaml", replaceLine(minimalScene(), 10, "  - {t_s: 0, t_s: 1, tip: [0, 2, -24], axis: [0, 0, 1]}"),
              ":10:", "duplicate key 't_s' in 'tool_path[0]'");
}

// Every number is finite and within +-1e9 (a physical quantity in mm, g, s or kPa).
TEST(SceneErrors, NumbersOutOfRange) {
  expectError("far_tip.yaml", replaceLine(minimalScene(), 10, "  - {t_s: 0, tip: [1e300, 2, -24], axis: [0, 0, 1]}"),
              ":10:", "'tip' must be between -1e9 and 1e9, got '1e300'");
  expectError("stiff.yaml",
              replaceLine(minimalScene(), 4,
                          "  - {name: myometrium, label: 1, young_modulus_kpa: 2e9, density_g_cm3: 1.05}"),
              ":4:", "'young_modulus_kpa' must be between -1e9 and 1e9, got '2e9'");
  // A huge axis would overflow its length: refused by the same bound, never normalised to 0.
  expectError("far_axis.yaml", replaceLine(minimalScene(), 10, "  - {t_s: 0, tip: [0, 2, -24], axis: [0, 0, 1e200]}"),
              ":10:", "'axis' must be between -1e9 and 1e9");
}

// A scene that is a device, a folder, or larger than 16 MiB is refused before it is read.
TEST(SceneErrors, NotARegularFileOrTooLarge) {
  auto scene = loadScene("/dev/zero");
  ASSERT_FALSE(scene.ok());
  EXPECT_EQ(scene.error(),
            "cannot read '/dev/zero': not a regular file (a device, FIFO or socket), refused as a scene file");
  const std::string dir = (fs::path(HYSIM_TEST_OUTPUT_DIR) / "scenes").string();
  fs::create_directories(dir);
  scene = loadScene(dir);
  ASSERT_FALSE(scene.ok());
  EXPECT_EQ(scene.error(), "cannot read '" + dir + "': Is a directory");
  const std::string huge = writeFile("huge.yaml", "name: x\n");
  fs::resize_file(huge, (16u << 20) + 1);
  scene = loadScene(huge);
  ASSERT_FALSE(scene.ok());
  EXPECT_EQ(scene.error(), "cannot read '" + huge + "': 16777217 bytes, more than the 16 MiB limit for a scene file");
  fs::remove(huge);
}

// Aliases let a small file stand for an enormous tree: the walk stops at a million nodes.
TEST(SceneErrors, AliasExpansionIsBounded) {
  std::string text = "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n";
  for (int level = 1; level <= 7; ++level) {
    const std::string prev = "*a" + std::to_string(level - 1);
    text += "a" + std::to_string(level) + ": &a" + std::to_string(level) + " [";
    for (int k = 0; k < 10; ++k) text += (k ? ", " : "") + prev;
    text += "]\n";
  }
  expectError("laughs.yaml", text, ":", "the scene expands to more than 1000000 YAML nodes (aliases?)");
}

TEST(SceneErrors, NanInMeshNamesMeshFileAndLine) {
  // Copy the asset with one coordinate replaced by nan; the scene loads, the mesh does not.
  std::ifstream in(kAssets + "/uterus_myoma.msh");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t nodes = text.find("$Nodes\n");
  ASSERT_NE(nodes, std::string::npos);
  const size_t line3 = text.find('\n', text.find('\n', nodes + 7) + 1) + 1;  // 2nd node line
  const size_t x_start = text.find(' ', line3) + 1;
  const size_t x_end = text.find(' ', x_start);
  text.replace(x_start, x_end - x_start, "nan");
  const std::string mesh = writeFile("nan_mesh.msh", text);
  int line = 1;
  for (size_t i = 0; i < x_start; ++i) line += text[i] == '\n';
  auto scene = loadScene(writeFile("nan_mesh.yaml", minimalScene(mesh)));
  ASSERT_TRUE(scene.ok()) << scene.error();
  auto sim = Simulation::create(*scene);
  ASSERT_FALSE(sim.ok());
  EXPECT_NE(sim.error().find(mesh + ":" + std::to_string(line)), std::string::npos) << sim.error();
}

TEST(SceneErrors, MaterialMissingForMeshLabel) {
  std::string text = replaceLine(minimalScene(), 5, "");
  auto scene = loadScene(writeFile("no_myoma.yaml", text));
  ASSERT_TRUE(scene.ok()) << scene.error();
  auto sim = Simulation::create(*scene);
  ASSERT_FALSE(sim.ok());
  EXPECT_NE(sim.error().find("material label 2"), std::string::npos) << sim.error();
}

}  // namespace
}  // namespace hysim::engine
