// Inputs checked where they enter the hysim command line: each case exits 1 (never hangs,
// never aborts) with one line naming the argument, the value or the file and line.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "run_hysim.hpp"
#include "slab_scenes.hpp"

namespace {

namespace fs = std::filesystem;

using hysim::testing::Output;

Output hysim(const std::string& args) { return hysim::testing::runHysim(args); }

std::string outDir(const std::string& name) { return hysim::testing::freshOutputDir("input_cli", name); }

const std::string kTetMesh = "tests/data/cutting/table2_ellipsoid.msh";

// Exit status 1 and every `names` in the output.
void expectRefused(const std::string& args, const std::vector<std::string>& names) {
  SCOPED_TRACE(args);
  const Output o = hysim(args);
  EXPECT_EQ(o.exit_code, 1) << o.text;
  for (const std::string& name : names) EXPECT_NE(o.text.find(name), std::string::npos) << name << " in:\n" << o.text;
}

// Before the check these read /dev/zero until memory ran out.
TEST(InputCli, DevicesAreRefusedBeforeReading) {
  expectRefused("stats /dev/zero", {"'/dev/zero'", "not a regular file"});
  expectRefused("run --steps 1 --quiet --mesh /dev/zero", {"'/dev/zero'", "not a regular file"});
  expectRefused("run /dev/zero --steps 1 --quiet", {"'/dev/zero'", "not a regular file", "scene file"});
  expectRefused("cut " + kTetMesh + " --surface /dev/zero --out " + outDir("dev") + "/x.msh",
                {"'/dev/zero'", "not a regular file"});
}

// Before the fix, a normal whose squared length overflows was accepted and every tet was
// cut free; now every --plane / --line value must be finite and within +-1e30.
TEST(InputCli, CutValuesMustBeFiniteAndInRange) {
  const std::string out = outDir("plane") + "/x.msh";
  expectRefused("cut " + kTetMesh + " --plane 0,0,0,0,0,1e300 --out " + out,
                {"--plane", "'1e300'", "beyond +-1e+30"});
  expectRefused("cut " + kTetMesh + " --plane 0,0,0,0,0,1e999 --out " + out, {"--plane", "'1e999'", "not a finite"});
  expectRefused("cut " + kTetMesh + " --plane 0,0,0,0,0,0 --out " + out, {"--plane", "zero normal"});
  expectRefused("cut tests/data/cutting/table1_mesh1.msh --line 0,0,1e31,1 --out " + out,
                {"--line", "'1e31'", "beyond"});
  EXPECT_FALSE(fs::exists(out));
  // A tiny normal is a direction all the same; spaces separate values as commas do.
  Output o = hysim("cut " + kTetMesh + " --plane 0.5,0.3,0.2,0,0,1e-200 --out " + out);
  EXPECT_EQ(o.exit_code, 0) << o.text;
  o = hysim("cut " + kTetMesh + " --plane '0.5 0.3 0.2 0 0 1' --out " + out);
  EXPECT_EQ(o.exit_code, 0) << o.text;
}

// CLI11's own range checks let "nan" through.
TEST(InputCli, NumericOptionsMustBeFinite) {
  expectRefused("run --steps 1 --quiet --device-wait-s nan", {"--device-wait-s", "'nan'", "not a finite number"});
  expectRefused("run --steps 1 --quiet --device-wait-s 1e999", {"--device-wait-s", "'1e999'"});
  expectRefused("run --steps 1 --quiet --every 0", {"--every", "'0' is not in [1, 1e+06]"});
  expectRefused("tables --table 2 --repeats nan", {"--repeats", "'nan'"});
}

// A report path naming a folder is refused before the run, and nothing is left behind.
TEST(InputCli, ReportIntoAFolderIsRefusedAndLeavesNoTemporaryFile) {
  const std::string dir = outDir("report_dir");
  fs::create_directories(dir + "/taken");
  for (const std::string& report : {dir + "/taken", dir + "/taken/", dir + "/new/"}) {
    expectRefused("run --steps 1 --quiet --report " + report, {"--report", "names a folder"});
  }
  std::vector<std::string> left;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) left.push_back(entry.path().string());
  EXPECT_EQ(left, std::vector<std::string>{dir + "/taken"});
  expectRefused("replay scenes/default.yaml --report " + dir + "/taken", {"--report", "names a folder"});
  // A recording into a folder is refused before the run too.
  expectRefused("run --steps 1 --quiet --record " + dir + "/taken", {"cannot record into", "names a folder"});
  EXPECT_FALSE(fs::exists(dir + "/taken.tmp"));
}

// Before the fix the run went to its end and then aborted writing the report (a JSON
// type_error on the scene's name). Now the scene is refused at once, with its file and line.
TEST(InputCli, SceneTextThatIsNotUtf8IsRefusedBeforeTheRun) {
  const std::string dir = outDir("utf8");
  std::string head = hysim::testing::slabSceneHead(dir, 100);
  head.replace(head.find("name: slab"), 10, "name: slab \xe9t\xe9");
  const std::string scene = dir + "/latin1.yaml";
  std::ofstream(scene) << head << "tool_path:\n  - {t_s: 0.0, tip: [8, 0, 4.5], axis: [1, 0, 0], up: [0, 0, 1]}\n";
  expectRefused("run " + scene + " --quiet --report " + dir + "/r.json",
                {scene + ":1:", "'name' is not valid UTF-8: byte 0xe9"});
  EXPECT_FALSE(fs::exists(dir + "/r.json"));
}

// A file path that is not UTF-8 (legal on Linux) reaches the report as the recording's name:
// written with the replacement character, never an abort.
TEST(InputCli, PathsThatAreNotUtf8StillGiveAReport) {
  const std::string dir = outDir("path_utf8");
  const std::string scene = hysim::testing::writeSlabScene(dir, false);
  const Output o =
      hysim("run " + scene + " --steps 20 --quiet --record " + dir + "/rec\xff.hyrec --report " + dir + "/r.json");
  ASSERT_EQ(o.exit_code, 0) << o.text;
  std::ifstream in(dir + "/r.json");
  const auto j = nlohmann::json::parse(in, nullptr, false);
  ASSERT_FALSE(j.is_discarded());
  EXPECT_NE(j["recording"]["file"].get<std::string>().find("rec\xef\xbf\xbd.hyrec"), std::string::npos);
}

// Duplicate keys in a scene name the file, the line and the key.
TEST(InputCli, DuplicateSceneKeyIsRefused) {
  const std::string dir = outDir("dup");
  const std::string scene = dir + "/dup.yaml";
  std::ofstream(scene) << hysim::testing::slabSceneHead(dir, 100) << "name: again\n"
                       << "tool_path:\n  - {t_s: 0.0, tip: [8, 0, 4.5], axis: [1, 0, 0], up: [0, 0, 1]}\n";
  expectRefused("run " + scene + " --quiet", {scene + ":8:", "duplicate key 'name'"});
}

// Unknown element types and VTK versions name the file and line.
TEST(InputCli, MeshFormatErrorsNameFileAndLine) {
  const std::string dir = outDir("formats");
  const std::string vtk = dir + "/v9.vtk";
  std::ofstream(vtk) << "# vtk DataFile Version 9.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 0 double\n";
  expectRefused("stats " + vtk, {vtk + ":1:", "unsupported VTK version '9.0'"});
  const std::string msh = dir + "/t99.msh";
  std::ofstream(msh) << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n$EndNodes\n"
                        "$Elements\n1\n1 99 0 1\n$EndElements\n";
  expectRefused("stats " + msh, {msh + ":10:", "unknown element type 99"});
  const std::string far = dir + "/far.msh";
  std::ofstream(far) << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1e300 0 0\n3 0 1e300 0\n"
                        "4 0 0 1e300\n$EndNodes\n$Elements\n1\n1 4 0 1 2 3 4\n$EndElements\n";
  expectRefused("stats " + far, {far + ":7:", "'1e300' beyond +-1e+30 mm"});
}

}  // namespace
