// `hysim accuracy --quick`, run as a user would: the report, the plots and the orderings the
// study must show (what CI runs of the speed-against-error study).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "run_hysim.hpp"

namespace hysim::testing {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

const json* findRun(const json& sweep, const std::string& label) {
  for (const json& r : sweep["runs"])
    if (r["label"] == label) return &r;
  return nullptr;
}

const json* findRow(const json& cutting, const std::string& method, int cuts) {
  for (const json& r : cutting["rows"])
    if (r["method"] == method && r["cuts"] == cuts) return &r;
  return nullptr;
}

TEST(AccuracyCli, QuickStudyWritesTheReportPlotsAndOrderings) {
  const std::string dir = freshOutputDir("accuracy", "quick");
  const Output out = runHysim("accuracy --quick --quiet --out " + dir);
  ASSERT_EQ(out.exit_code, 0) << out.text;
  for (const char* f : {"report.json", "report.md", "pareto_beam.png", "pareto_organ_sag.png", "pareto_organ_release.png",
                        "indentation.png"})
    EXPECT_TRUE(fs::exists(fs::path(dir) / f)) << f;
  std::ifstream in(fs::path(dir) / "report.json");
  const json r = json::parse(in);
  // The beam's references agree with each other: C3D10 within 5% of Euler-Bernoulli.
  const json& beam = r["beam"];
  const double r3 = beam["r3"]["tip_sag_mm"];
  bool have_c3d10 = false;
  for (const json& f : beam["r2"]) {
    if (f["name"].get<std::string>().find("C3D10 linear") == std::string::npos) continue;
    have_c3d10 = true;
    EXPECT_NEAR(f["tip_sag_mm"].get<double>(), r3, 0.05 * r3);
  }
  EXPECT_TRUE(have_c3d10);
  // Symplectic Euler: error falls as substeps grow; below the automatic count it diverges.
  for (const char* c : {"beam", "organ"}) {
    const json& sweep = std::string(c) == "beam" ? beam["dynamic"] : r["organ"]["sag"];
    std::vector<double> errors;
    for (const json& run : sweep["runs"]) {
      if (run["family"] != "symplectic_euler") continue;
      errors.push_back(run["error_vs_r1"].is_null() ? INFINITY : run["error_vs_r1"].get<double>());
    }
    ASSERT_EQ(errors.size(), 3u) << c;
    EXPECT_TRUE(std::isinf(errors[0])) << c;
    EXPECT_LT(errors[2], errors[1]) << c;
    EXPECT_LT(errors[1], 0.05) << c;
  }
  // Implicit Euler converges to R1's static solution as iterations grow.
  const json* it1 = findRun(r["organ"]["sag"], "implicit dt 1 ms, 1 it");
  const json* it4 = findRun(r["organ"]["sag"], "implicit dt 1 ms, 4 it");
  ASSERT_TRUE(it1 && it4);
  EXPECT_LT((*it4)["final_error_vs_r1_static"].get<double>(), (*it1)["final_error_vs_r1_static"].get<double>());
  // One plane cut: the hybrid keeps the stable step, standard subdivision loses it.
  const json* hybrid = findRow(r["organ"]["cutting"], "hybrid", 1);
  const json* standard = findRow(r["organ"]["cutting"], "standard", 1);
  ASSERT_TRUE(hybrid && standard);
  EXPECT_GE((*hybrid)["critical_dt_ratio"].get<double>(), 0.5);
  EXPECT_LT((*standard)["critical_dt_ratio"].get<double>(), 0.1);
  EXPECT_LT((*standard)["volume_error"].get<double>(), 1e-9);  // subdivision keeps the volume
  EXPECT_FALSE(r["choice_for_default_scene"].is_null());
}

TEST(AccuracyCli, AnOutputFolderThatCannotBeMadeIsAClearError) {
  const std::string dir = freshOutputDir("accuracy", "blocked");
  std::ofstream(fs::path(dir) / "file") << "x";
  const Output out = runHysim("accuracy --quick --quiet --out " + dir + "/file/sub");
  EXPECT_EQ(out.exit_code, 1) << out.text;
  EXPECT_NE(out.text.find(dir + "/file/sub"), std::string::npos) << out.text;
}

}  // namespace
}  // namespace hysim::testing
