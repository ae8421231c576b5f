// Recording and replay: the device states a run consumed, fed back into the same scene, give
// the same states to the last bit, also across a device change in the middle of the run; a
// scene that changed since is refused unless forced.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "slab_scenes.hpp"
#include "test_dir.hpp"
#include "hysim/engine/replay.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/simulation.hpp"
#include "hysim/haptics/recording.hpp"

namespace hysim::engine {
namespace {

namespace fs = std::filesystem;

std::unique_ptr<Simulation> makeSim(const Scene& scene) {
  auto sim = Simulation::create(scene);
  EXPECT_TRUE(sim.ok()) << sim.error();
  return sim.ok() ? std::move(sim.value()) : nullptr;
}

// Starts recording `sim` into `path`.
void startRecording(Simulation& sim, const Scene& scene, const std::string& path, haptics::RecordingWriter& w) {
  auto header = recordingHeader(scene, {}, sim.device().info().name);
  ASSERT_TRUE(header.ok()) << header.error();
  std::string error;
  ASSERT_TRUE(w.open(path, *header, error)) << error;
  ASSERT_TRUE(sim.recordInputTo(&w).ok());
}

std::shared_ptr<haptics::Recording> readBack(const std::string& path) {
  auto rec = std::make_shared<haptics::Recording>();
  std::string error;
  EXPECT_TRUE(haptics::readRecording(path, *rec, error)) << error;
  return rec;
}

std::uint64_t replayHash(const std::shared_ptr<haptics::Recording>& rec, int* passes = nullptr) {
  auto scene = loadReplayScene(*rec, false);
  EXPECT_TRUE(scene.ok()) << scene.error();
  if (!scene.ok()) return 0;
  auto sim = makeSim(scene->scene);
  auto report = replay(*sim, rec, RunOptions{});
  EXPECT_TRUE(report.ok()) << report.error();
  if (passes != nullptr) *passes = static_cast<int>(sim->passes().size());
  return report.ok() ? report->state_hash : 0;
}

TEST(Replay, ARecordedCutReplaysToTheSameStates) {
  const fs::path dir = testing::testDir("replay");
  auto scene = loadScene(testing::writeSlabScene(dir, true));
  ASSERT_TRUE(scene.ok()) << scene.error();
  auto plain = makeSim(*scene);
  auto recorded = makeSim(*scene);
  ASSERT_TRUE(plain && recorded);
  haptics::RecordingWriter w;
  startRecording(*recorded, *scene, (dir / "cut.hyrec").string(), w);
  for (int i = 0; i < 1300; ++i) {
    plain->step();
    recorded->step();
  }
  recorded->commitPendingCut();
  plain->commitPendingCut();
  std::string error;
  ASSERT_TRUE(w.finish(error)) << error;
  EXPECT_EQ(w.records(), 1301u);  // the attach, then one per step
  EXPECT_EQ(recorded->stateHash(), plain->stateHash());  // recording changes nothing
  ASSERT_EQ(recorded->passes().size(), 1u);
  int passes = 0;
  EXPECT_EQ(replayHash(readBack((dir / "cut.hyrec").string()), &passes), recorded->stateHash());
  EXPECT_EQ(passes, 1);
}

TEST(Replay, ADeviceChangeInTheMiddleIsReplayed) {
  const fs::path dir = testing::testDir("replay");
  auto scene = loadScene(testing::writeSlabScene(dir, false));
  ASSERT_TRUE(scene.ok()) << scene.error();
  auto sim = makeSim(*scene);
  ASSERT_TRUE(sim);
  haptics::RecordingWriter w;
  startRecording(*sim, *scene, (dir / "switch.hyrec").string(), w);
  for (int i = 0; i < 200; ++i) sim->step();
  auto manual = std::make_unique<haptics::ManualDevice>(sim->deviceState().pose, sim->state().time);
  haptics::ManualCommand down;
  down.velocity_scope_mm_s = {0, -20, 5};  // into the slab: contact forces
  manual->setCommand(down);
  sim->setDevice(std::move(manual));
  for (int i = 0; i < 300; ++i) sim->step();
  std::string error;
  ASSERT_TRUE(w.finish(error)) << error;
  auto rec = readBack((dir / "switch.hyrec").string());
  ASSERT_EQ(rec->states.size(), 502u);
  EXPECT_TRUE(rec->states[201].attached);
  EXPECT_GT(sim->toolForceN().norm(), 0.0);
  EXPECT_EQ(replayHash(rec), sim->stateHash());
}

TEST(Replay, AChangedSceneIsRefusedUnlessForced) {
  const fs::path dir = testing::testDir("replay");
  const std::string scene_path = testing::writeSlabScene(dir, false);
  auto scene = loadScene(scene_path);
  ASSERT_TRUE(scene.ok()) << scene.error();
  auto sim = makeSim(*scene);
  haptics::RecordingWriter w;
  startRecording(*sim, *scene, (dir / "old.hyrec").string(), w);
  for (int i = 0; i < 10; ++i) sim->step();
  std::string error;
  ASSERT_TRUE(w.finish(error)) << error;
  auto rec = readBack((dir / "old.hyrec").string());
  ASSERT_TRUE(loadReplayScene(*rec, false).ok());
  std::ofstream(scene_path, std::ios::app) << "# an instructor's edit\n";
  auto refused = loadReplayScene(*rec, false);
  ASSERT_FALSE(refused.ok());
  auto now = sceneContentHash(*loadScene(scene_path));
  ASSERT_TRUE(now.ok());
  EXPECT_NE(refused.error().find(hashHex(*now)), std::string::npos) << refused.error();
  EXPECT_NE(refused.error().find(hashHex(rec->header.scene_hash)), std::string::npos) << refused.error();
  auto forced = loadReplayScene(*rec, true);
  ASSERT_TRUE(forced.ok()) << forced.error();
  EXPECT_TRUE(forced->changed);
}

TEST(Replay, AnotherBuildsRecordingIsRefusedUnlessForced) {
  const fs::path dir = testing::testDir("replay");
  auto scene = loadScene(testing::writeSlabScene(dir, false));
  ASSERT_TRUE(scene.ok()) << scene.error();
  auto sim = makeSim(*scene);
  haptics::RecordingWriter w;
  startRecording(*sim, *scene, (dir / "old.hyrec").string(), w);
  sim->step();
  std::string error;
  ASSERT_TRUE(w.finish(error)) << error;
  auto rec = readBack((dir / "old.hyrec").string());
  EXPECT_EQ(rec->header.hysim_version, hysimVersion());
  rec->header.hysim_version = "0.0 (an old commit)";
  auto refused = loadReplayScene(*rec, false);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().find("0.0 (an old commit)"), std::string::npos) << refused.error();
  EXPECT_NE(refused.error().find(hysimVersion()), std::string::npos) << refused.error();
  auto forced = loadReplayScene(*rec, true);
  ASSERT_TRUE(forced.ok()) << forced.error();
  EXPECT_TRUE(forced->version_changed);
  EXPECT_FALSE(forced->changed);
}

TEST(Replay, TheMeshIsPartOfTheScenesContent) {
  const fs::path dir = testing::testDir("replay");
  auto scene = loadScene(testing::writeSlabScene(dir, false));
  ASSERT_TRUE(scene.ok()) << scene.error();
  const auto before = sceneContentHash(*scene);
  std::ofstream(scene->mesh_path, std::ios::app) << "\n";
  const auto after = sceneContentHash(*scene);
  ASSERT_TRUE(before.ok() && after.ok());
  EXPECT_NE(*before, *after);
}

TEST(Replay, RecordingStartsBeforeTheFirstStep) {
  const fs::path dir = testing::testDir("replay");
  auto scene = loadScene(testing::writeSlabScene(dir, false));
  ASSERT_TRUE(scene.ok()) << scene.error();
  auto sim = makeSim(*scene);
  sim->step();
  haptics::RecordingWriter w;
  EXPECT_FALSE(sim->recordInputTo(&w).ok());
}

}  // namespace
}  // namespace hysim::engine
