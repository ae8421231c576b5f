// `hysim cut` (2D) and `hysim tables --table 1`, run as a user would.
#include <gtest/gtest.h>

#include "read_json.hpp"
#include "run_hysim.hpp"

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

namespace {

namespace fs = std::filesystem;

using hysim::testing::Output;

Output hysim(const std::string& args) { return hysim::testing::runHysim(args); }

std::string outDir(const std::string& name) { return hysim::testing::freshOutputDir("cli_cut2d", name); }

using hysim::testing::readJson;

const std::string kMesh1 = "tests/data/cutting/table1_mesh1.msh";
const std::string kLine1a = "--line=-5,27,105,41";  // the Table-1 cut 1a

TEST(CliCut2D, HybridCutWritesMeshAndStats) {
  const std::string dir = outDir("hybrid");
  const Output o = hysim("cut " + kMesh1 + " " + kLine1a + " --method hybrid --out " + dir + "/cut.msh --stats " + dir +
                         "/stats.json");
  ASSERT_EQ(o.exit_code, 0) << o.text;
  EXPECT_NE(o.text.find("hybrid cut"), std::string::npos) << o.text;
  const auto j = readJson(dir + "/stats.json");
  ASSERT_FALSE(j.is_discarded());
  for (const char* key : {"nodes", "elements", "size_min", "size_mean", "size_std", "edge_min", "edge_mean", "edge_std",
                          "q_min", "q_mean", "q_std", "dihedral_min_deg", "time_ms"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_LE(j["elements"].get<int>(), 66);  // 63 initial, +5%
  EXPECT_GE(j["q_min"].get<double>(), 0.27);
  EXPECT_GT(j["time_ms"].get<double>(), 0.0);
  // The output is a mesh `hysim stats` reads, with the same numbers.
  const Output s = hysim("stats " + dir + "/cut.msh --json");
  ASSERT_EQ(s.exit_code, 0) << s.text;
  const auto js = nlohmann::json::parse(s.text, nullptr, false);
  ASSERT_FALSE(js.is_discarded()) << s.text;
  EXPECT_EQ(js["elements"], j["elements"]);
  EXPECT_NEAR(js["q_min"].get<double>(), j["q_min"].get<double>(), 1e-6);
}

TEST(CliCut2D, StandardSubdivisionCollapsesQuality) {
  const std::string dir = outDir("standard");
  const Output o = hysim("cut " + kMesh1 + " " + kLine1a + " --method standard --out " + dir + "/cut.vtk --stats " +
                         dir + "/stats.json");
  ASSERT_EQ(o.exit_code, 0) << o.text;
  EXPECT_TRUE(fs::exists(dir + "/cut.vtk"));
  const auto j = readJson(dir + "/stats.json");
  ASSERT_FALSE(j.is_discarded());
  EXPECT_LT(j["q_min"].get<double>(), 0.05);
  EXPECT_GT(j["elements"].get<int>(), 63);
}

TEST(CliCut2D, BadInputGivesAMessage) {
  const std::string dir = outDir("bad");
  Output o = hysim("cut " + kMesh1 + " " + kLine1a + " --method laser --out " + dir + "/x.msh");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.text.find("laser"), std::string::npos) << o.text;
  o = hysim("cut " + kMesh1 + " --line 1,2,3 --out " + dir + "/x.msh");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.text.find("--line"), std::string::npos) << o.text;
  o = hysim("cut /nonexistent.msh --line 0,0,1,1 --out " + dir + "/x.msh");
  EXPECT_NE(o.exit_code, 0);
  EXPECT_FALSE(fs::exists(dir + "/x.msh"));
}

TEST(CliCut2D, Table1MeetsTheAcceptance) {
  const std::string dir = outDir("table1");
  const Output o = hysim("tables --table 1 --repeats 30 --json " + dir + "/t1.json --pictures " + dir + "/pics");
  // Exit 2 = an acceptance bound missed. Timings depend on the machine's load (tests run in
  // parallel), so a missed time target alone is tolerated here; README has the measured times.
  ASSERT_TRUE(o.exit_code == 0 || o.exit_code == 2) << o.text;
  const auto j = readJson(dir + "/t1.json");
  ASSERT_FALSE(j.is_discarded());
  for (const auto& f : j["acceptance_failures"])
    EXPECT_NE(f.get<std::string>().find("slower than the target"), std::string::npos) << f;
  int hybridRows = 0;
  for (const auto& row : j["rows"]) {
    if (row["method"] != "Hybrid") continue;
    ++hybridRows;
    EXPECT_GE(row["q_min"].get<double>(), 0.27) << row["test"];
    EXPECT_TRUE(row["valid"].get<bool>());
    EXPECT_GE(row["components"].get<int>(), 2);
  }
  EXPECT_EQ(hybridRows, 4);
  for (const char* png : {"mesh1_initial.png", "mesh1a_hybrid.png", "mesh2b_standard.png"})
    EXPECT_TRUE(fs::exists(fs::path(dir) / "pics" / png)) << png;
}

}  // namespace
