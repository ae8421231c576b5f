// `hysim run --record` and `hysim replay`, as a user runs them: the replay reproduces the
// state_hash (also pinned to one core), a changed scene needs --force, and a broken recording
// is an error naming the byte, with the old report kept.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "read_json.hpp"
#include "run_hysim.hpp"
#include "slab_scenes.hpp"

namespace {

using hysim::testing::Output;
using hysim::testing::runHysim;

using hysim::testing::readJson;

TEST(ReplayCli, ARecordedRunReplaysToTheSameHash) {
  const std::string dir = hysim::testing::freshOutputDir("replay_cli", "same_hash");
  const std::string scene = hysim::testing::writeSlabScene(dir, true);
  const std::string rec = dir + "/session.hyrec";
  Output o = runHysim("run " + scene + " --quiet --record " + rec + " --report " + dir + "/run.json");
  ASSERT_EQ(o.exit_code, 0) << o.text;
  const auto run = readJson(dir + "/run.json");
  EXPECT_EQ(run["recording"]["states"].get<int>(), 1301);
  EXPECT_EQ(run["device"]["name"], "scripted");
  for (const std::string prefix : {"", "taskset -c 0"}) {
    o = runHysim("replay " + rec + " --report " + dir + "/replay.json", prefix);
    ASSERT_EQ(o.exit_code, 0) << o.text;
    EXPECT_NE(o.text.find("state_hash " + run["state_hash"].get<std::string>()), std::string::npos) << o.text;
    const auto replay = readJson(dir + "/replay.json");
    EXPECT_EQ(replay["state_hash"], run["state_hash"]) << prefix;
    EXPECT_EQ(replay["passes"], run["passes"]);
    EXPECT_EQ(replay["myoma_resected_mm3"], run["myoma_resected_mm3"]);
    EXPECT_TRUE(replay["recording"]["replay"].get<bool>());
    EXPECT_FALSE(replay["recording"]["scene_changed"].get<bool>());
  }
}

TEST(ReplayCli, AChangedSceneNeedsForceAndIsFlagged) {
  const std::string dir = hysim::testing::freshOutputDir("replay_cli", "changed");
  const std::string scene = hysim::testing::writeSlabScene(dir, false);
  const std::string rec = dir + "/session.hyrec";
  ASSERT_EQ(runHysim("run " + scene + " --quiet --steps 50 --record " + rec).exit_code, 0);
  std::ofstream(scene, std::ios::app) << "# edited\n";
  Output o = runHysim("replay " + rec);
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.text.find("changed since the recording"), std::string::npos) << o.text;
  o = runHysim("replay " + rec + " --force --report " + dir + "/forced.json");
  EXPECT_EQ(o.exit_code, 0) << o.text;
  EXPECT_TRUE(readJson(dir + "/forced.json")["recording"]["scene_changed"].get<bool>());
}

TEST(ReplayCli, ABrokenRecordingIsAnErrorAndTheOldReportStays) {
  const std::string dir = hysim::testing::freshOutputDir("replay_cli", "broken");
  const std::string scene = hysim::testing::writeSlabScene(dir, false);
  const std::string rec = dir + "/session.hyrec";
  ASSERT_EQ(runHysim("run " + scene + " --quiet --steps 50 --record " + rec).exit_code, 0);
  std::ofstream(dir + "/old.json") << "{\"kept\": true}\n";
  std::filesystem::resize_file(rec, std::filesystem::file_size(rec) - 100);
  const Output o = runHysim("replay " + rec + " --report " + dir + "/old.json");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.text.find("byte "), std::string::npos) << o.text;
  EXPECT_NE(o.text.find("truncated"), std::string::npos) << o.text;
  EXPECT_TRUE(readJson(dir + "/old.json")["kept"].get<bool>());
  EXPECT_NE(runHysim("replay " + dir + "/missing.hyrec").exit_code, 0);
}

}  // namespace
