// The hysim command line, run as a user would: exit codes, messages, outputs.
#include <gtest/gtest.h>

#include "run_hysim.hpp"
#include "slab_scenes.hpp"

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;

using hysim::testing::Output;

Output hysim(const std::string& args) { return hysim::testing::runHysim(args); }

std::string outDir(const std::string& name) { return hysim::testing::freshOutputDir("cli", name); }

TEST(Cli, HelpForEachSubcommand) {
  for (const char* sub : {"run", "stats"}) {
    const Output o = hysim(std::string(sub) + " --help");
    EXPECT_EQ(o.exit_code, 0) << o.text;
    EXPECT_NE(o.text.find("Usage"), std::string::npos) << o.text;
  }
}

TEST(Cli, BadArgumentsExitNonZeroWithAMessage) {
  Output o = hysim("run --steps minus-three");
  EXPECT_NE(o.exit_code, 0);
  EXPECT_NE(o.text.find("--steps"), std::string::npos) << o.text;
  o = hysim("explode");
  EXPECT_NE(o.exit_code, 0);
  o = hysim("stats /nonexistent/mesh.msh");
  EXPECT_NE(o.exit_code, 0);
  EXPECT_NE(o.text.find("/nonexistent/mesh.msh"), std::string::npos) << o.text;
}

TEST(Cli, StatsJsonHasThePaperColumns) {
  const Output o = hysim("stats assets/uterus_myoma.msh --json");
  ASSERT_EQ(o.exit_code, 0) << o.text;
  const auto j = nlohmann::json::parse(o.text);
  for (const char* key : {"nodes", "elements", "size_min", "size_mean", "size_std", "edge_min", "edge_mean", "edge_std",
                          "q_min", "q_mean", "q_std", "dihedral_min_deg"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_GE(j["elements"].get<int>(), 10000);
  EXPECT_GT(j["q_min"].get<double>(), 0.05);  // no slivers
  EXPECT_LE(j["q_mean"].get<double>(), 1.0 / 3.0);
}

// `hysim stats` against an independent implementation (tools/meshgen/mesh-quality.awk, plain
// awk arithmetic written separately from the C++) on the checked-in uterus mesh.
TEST(Cli, StatsAgreeWithIndependentAwkComputation) {
  const Output o = hysim("stats assets/uterus_myoma.msh --json");
  ASSERT_EQ(o.exit_code, 0) << o.text;
  const auto j = nlohmann::json::parse(o.text);
  Output awk;
  {
    const std::string cmd = std::string("cd ") + HYSIM_SOURCE_DIR +
                            " && awk -f tools/meshgen/mesh-quality.awk assets/uterus_myoma.msh | grep '^all '";
    FILE* pipe = popen(cmd.c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    char buf[512] = {0};
    ASSERT_NE(fgets(buf, sizeof(buf), pipe), nullptr);
    pclose(pipe);
    awk.text = buf;
  }
  // all  tets vol_min vol_sum e_min e_mean(per tet) e_max q_min q_mean q<.1 dih_min dih_max inv
  std::istringstream in(awk.text);
  std::string tag;
  double tets, vol_min, vol_sum, e_min, e_mean, e_max, q_min, q_mean, q_low, dih_min;
  in >> tag >> tets >> vol_min >> vol_sum >> e_min >> e_mean >> e_max >> q_min >> q_mean >> q_low >> dih_min;
  ASSERT_EQ(tag, "all") << awk.text;
  EXPECT_EQ(j["elements"].get<int>(), static_cast<int>(tets));
  EXPECT_NEAR(j["size_min"].get<double>(), vol_min, 1e-4);
  EXPECT_NEAR(j["size_mean"].get<double>(), vol_sum / tets, 1e-3);
  EXPECT_NEAR(j["edge_min"].get<double>(), e_min, 1e-3);
  EXPECT_NEAR(j["q_min"].get<double>(), q_min, 1e-4);
  EXPECT_NEAR(j["q_mean"].get<double>(), q_mean, 1e-4);
  EXPECT_NEAR(j["dihedral_min_deg"].get<double>(), dih_min, 1e-2);
}

TEST(Cli, RunWritesFramesAndReport) {
  const std::string dir = outDir("run");
  const Output o = hysim("run --steps 20 --every 10 --frames " + dir + "/frames --report " + dir + "/report.json");
  ASSERT_EQ(o.exit_code, 0) << o.text;
  EXPECT_TRUE(fs::exists(dir + "/frames/frame_00000.png"));
  EXPECT_TRUE(fs::exists(dir + "/frames/frame_00002.png"));
  std::ifstream in(dir + "/report.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["steps"].get<int>(), 20);
  EXPECT_EQ(j["frames"].get<int>(), 3);
  EXPECT_DOUBLE_EQ(j["dt"].get<double>(), 0.001);
  for (const char* key : {"nodes", "elements", "springs", "state_hash", "warnings"}) EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_TRUE(j["step_us"].contains("median"));
  EXPECT_TRUE(j["step_us"].contains("p99"));
  EXPECT_EQ(j["state_hash"].get<std::string>().size(), 16u);
}

TEST(Cli, RunPrintsTheMetricsSummaryUnlessQuiet) {
  const std::string dir = outDir("summary");
  const Output o = hysim("run --steps 20 --report " + dir + "/report.json");
  ASSERT_EQ(o.exit_code, 0) << o.text;
  for (const char* line : {"myoma resected    0 mm3 (0.0% of 2057 mm3)", "healthy removed   0 mm3",
                           "perforations      0 (margin 2.0 mm to the serosa)", "passes            0 (cut ms median",
                           "electrode active  0.00 s", "path length"}) {
    EXPECT_NE(o.text.find(line), std::string::npos) << line << " missing in\n" << o.text;
  }
  std::ifstream in(dir + "/report.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["perforations"].get<int>(), 0);
  EXPECT_TRUE(j["perforation_events"].is_array());
  EXPECT_DOUBLE_EQ(j["perforation_margin_mm"].get<double>(), 2.0);
  EXPECT_TRUE(j["cut_ms"].contains("median"));
  EXPECT_TRUE(j["cut_ms"].contains("max"));
  const Output quiet = hysim("run --steps 20 --quiet");
  ASSERT_EQ(quiet.exit_code, 0) << quiet.text;
  EXPECT_EQ(quiet.text, "");
}

TEST(Cli, BadSceneFailsAndKeepsTheOldReport) {
  const std::string dir = outDir("bad");
  std::ofstream(dir + "/report.json") << "{\"kept\": true}\n";
  std::ofstream(dir + "/bad.yaml") << "name: x\nmesh: " << HYSIM_SOURCE_DIR << "/assets/uterus_myoma.msh\nmaterials: 3\n";
  const Output o = hysim("run " + dir + "/bad.yaml --report " + dir + "/report.json");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.text.find(dir + "/bad.yaml:3"), std::string::npos) << o.text;
  std::ifstream in(dir + "/report.json");
  EXPECT_TRUE(nlohmann::json::parse(in)["kept"].get<bool>());
}

TEST(Cli, RunTakesAnotherMeshOfTheOrgan) {
  const std::string dir = outDir("mesh");
  const Output o = hysim("run --steps 5 --quiet --mesh tests/data/cutting/uterus_20k.msh --report " + dir + "/report.json");
  ASSERT_EQ(o.exit_code, 0) << o.text;
  std::ifstream in(dir + "/report.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["elements"].get<int>(), 20971);  // the scene's own mesh has 12,139
  EXPECT_EQ(j["steps"].get<int>(), 5);
}

TEST(Cli, RunRefusesAMissingOrWrongMesh) {
  const std::string dir = outDir("badmesh");
  std::ofstream(dir + "/report.json") << "{\"kept\": true}\n";
  Output o = hysim("run --steps 5 --mesh /nonexistent/organ.msh --report " + dir + "/report.json");
  EXPECT_NE(o.exit_code, 0);
  EXPECT_NE(o.text.find("/nonexistent/organ.msh"), std::string::npos) << o.text;
  // A surface, not a tet mesh.
  o = hysim("run --steps 5 --mesh assets/resectoscope.stl --report " + dir + "/report.json");
  EXPECT_NE(o.exit_code, 0);
  EXPECT_NE(o.text.find("resectoscope.stl"), std::string::npos) << o.text;
  std::ifstream in(dir + "/report.json");
  EXPECT_TRUE(nlohmann::json::parse(in)["kept"].get<bool>());
}

TEST(Cli, SameSceneTwiceSameHash) {
  const std::string dir = outDir("hash");
  ASSERT_EQ(hysim("run --steps 100 --quiet --report " + dir + "/a.json").exit_code, 0);
  ASSERT_EQ(hysim("run --steps 100 --quiet --report " + dir + "/b.json").exit_code, 0);
  std::ifstream a(dir + "/a.json"), b(dir + "/b.json");
  EXPECT_EQ(nlohmann::json::parse(a)["state_hash"], nlohmann::json::parse(b)["state_hash"]);
}

// The real-time mode paces the same state sequence to the wall clock with the haptic thread
// beside it; the synchronous cut and a run pinned to one core give the same states too.
TEST(Cli, RealtimeRunIsTheSameRunWithTheHapticThread) {
  const std::string dir = outDir("realtime");
  const std::string scene = hysim::testing::writeSlabScene(dir, true);
  auto report = [&](const std::string& name, const std::string& flags, const std::string& prefix = "") {
    const Output o = hysim::testing::runHysim("run " + scene + " --quiet " + flags + " --report " + dir + "/" + name,
                                              prefix);
    EXPECT_EQ(o.exit_code, 0) << o.text;
    std::ifstream in(dir + "/" + name);
    return nlohmann::json::parse(in);
  };
  const auto fast = report("fast.json", "");
  const auto paced = report("paced.json", "--realtime");
  const auto one_core = report("one_core.json", "--realtime", "taskset -c 0");
  const auto sync = report("sync.json", "--sync-cut");
  EXPECT_EQ(fast["passes"].get<int>(), 1);
  for (const auto* r : {&paced, &one_core, &sync}) EXPECT_EQ((*r)["state_hash"], fast["state_hash"]);
  EXPECT_FALSE(fast["realtime"].get<bool>());
  EXPECT_EQ(sync["cut_mode"], "sync");
  EXPECT_EQ(sync["stalls"].get<int>(), 0);
  for (const auto* r : {&paced, &one_core}) {
    EXPECT_TRUE((*r)["realtime"].get<bool>());
    // 1.3 s of simulated time at 1 kHz; the counts, not the timing, are asserted.
    EXPECT_GT((*r)["haptic_ticks"].get<long>(), 500);
    EXPECT_GT((*r)["haptic_period_us"]["p50"].get<double>(), 0.0);
    EXPECT_GE((*r)["wall_s"].get<double>(), 1.2);
    EXPECT_GT((*r)["cut_latency_ms"]["median"].get<double>(), 0.0);
    EXPECT_EQ((*r)["per_pass"][0]["commit_step"].get<int>() - (*r)["per_pass"][0]["exit_step"].get<int>(), 20);
  }
}

}  // namespace
