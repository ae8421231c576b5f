// The asynchronous cut: a pass's cut runs on the cut worker and is committed a fixed number
// of steps after the pass's exit step, so the state sequence never depends on the worker's
// timing: the same hashes as the synchronous reference, with random worker delays too.
#include <gtest/gtest.h>

#include <chrono>
#include <random>
#include <thread>

#include "alloc_counter.hpp"
#include "slab_scenes.hpp"
#include "test_dir.hpp"
#include "hysim/cutting/mesh.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/simulation.hpp"

namespace hysim::engine {
namespace {

std::unique_ptr<Simulation> threePassSim(const std::string& extra) {
  auto scene = loadScene(testing::writeThreePassSlabScene(testing::testDir("cut_commit"), extra));
  EXPECT_TRUE(scene.ok()) << scene.error();
  if (!scene.ok()) return nullptr;
  auto sim = Simulation::create(*scene);
  EXPECT_TRUE(sim.ok()) << sim.error();
  return sim.ok() ? std::move(sim.value()) : nullptr;
}

// Hashes of the state every 100 steps over the three-pass course.
std::vector<std::uint64_t> hashTrace(Simulation& sim) {
  std::vector<std::uint64_t> trace;
  for (int i = 0; i < 5200; ++i) {
    sim.step();
    if (i % 100 == 99) trace.push_back(sim.stateHash());
  }
  return trace;
}

TEST(CutCommit, TheCutReplacesTheTissueKStepsAfterTheExit) {
  auto sim = threePassSim("cut: {commit_steps: 20}\n");
  ASSERT_TRUE(sim);
  int version = sim->topologyVersion();
  std::int64_t changed_at = -1;
  for (int i = 0; i < 1300 && changed_at < 0; ++i) {
    sim->step();
    if (sim->topologyVersion() != version) changed_at = static_cast<std::int64_t>(sim->state().steps);
  }
  ASSERT_EQ(sim->passes().size(), 1u);
  const PassRecord& pass = sim->passes()[0];
  ASSERT_FALSE(pass.cut_failed) << pass.message;
  EXPECT_EQ(pass.commit_step, pass.exit_step + 20);
  // The commit happens at the start of the step after `commit_step` steps were taken.
  EXPECT_EQ(changed_at, pass.commit_step + 1);
  EXPECT_GT(pass.latency_ms, 0.0);
  EXPECT_TRUE(cutting::validate(sim->mesh()).ok());
}

TEST(CutCommit, WorkerGivesTheSameStatesAsTheSynchronousReference) {
  auto async = threePassSim("");
  auto sync = threePassSim("cut: {mode: sync}\n");
  ASSERT_TRUE(async && sync);
  EXPECT_EQ(hashTrace(*async), hashTrace(*sync));
  ASSERT_EQ(async->passes().size(), 3u);
  ASSERT_EQ(sync->passes().size(), 3u);
  for (size_t p = 0; p < 3; ++p) {
    EXPECT_EQ(async->passes()[p].commit_step, sync->passes()[p].commit_step);
    EXPECT_EQ(async->passes()[p].elements, sync->passes()[p].elements);
  }
  EXPECT_EQ(sync->stalls(), 0);
}

// The worker sleeps a random 0-60 ms before each job (K = 20 steps is 20 ms of simulated
// time, far less than the stepping takes here, so some commits wait): same states.
TEST(CutCommit, RandomWorkerDelaysDoNotChangeTheStates) {
  auto reference = threePassSim("cut: {mode: sync}\n");
  ASSERT_TRUE(reference);
  const std::vector<std::uint64_t> expected = hashTrace(*reference);
  int stalls = 0;
  for (unsigned seed : {1u, 2u}) {
    auto sim = threePassSim("");
    ASSERT_TRUE(sim);
    auto rng = std::make_shared<std::mt19937>(seed);
    sim->setCutDelayForTesting([rng] {
      std::this_thread::sleep_for(std::chrono::milliseconds(std::uniform_int_distribution<int>(0, 60)(*rng)));
    });
    EXPECT_EQ(hashTrace(*sim), expected) << "seed " << seed;
    stalls += sim->stalls();
  }
  EXPECT_GT(stalls, 0);  // the delays did make commit steps wait
}

// A commit step swaps in what the worker prepared: the steps after the exit step, the commit
// step included, allocate nothing.
TEST(CutCommit, CommitStepAllocatesNothing) {
  auto scene = loadScene(testing::writeSlabScene(testing::testDir("cut_commit"), true));
  ASSERT_TRUE(scene.ok()) << scene.error();
  auto sim = Simulation::create(*scene);
  ASSERT_TRUE(sim.ok()) << sim.error();
  int i = 0;
  for (; i < 1300 && !(*sim)->cutPending(); ++i) (*sim)->step();
  ASSERT_TRUE((*sim)->cutPending());
  long count = 0;
  {
    testing::AllocationCounter counter;
    for (int k = 0; k < 40; ++k) (*sim)->step();
    count = counter.count();
  }
  EXPECT_FALSE((*sim)->cutPending());
  ASSERT_EQ((*sim)->passes().size(), 1u);
  EXPECT_FALSE((*sim)->passes()[0].cut_failed);
  EXPECT_EQ(count, 0);
}

TEST(CutCommit, ZeroStepsCommitsOnTheNextStep) {
  auto sim = threePassSim("cut: {commit_steps: 0}\n");
  ASSERT_TRUE(sim);
  for (int i = 0; i < 1300; ++i) sim->step();
  ASSERT_EQ(sim->passes().size(), 1u);
  EXPECT_EQ(sim->passes()[0].commit_step, sim->passes()[0].exit_step);
}

TEST(CutCommit, SceneKeysAreChecked) {
  const auto dir = testing::testDir("cut_commit");
  EXPECT_TRUE(loadScene(testing::writeSlabScene(dir, true, "cut: {mode: sync, commit_steps: 5}\n")).ok());
  auto bad = loadScene(testing::writeSlabScene(dir, true, "cut: {mode: later}\n"));
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find("async or sync"), std::string::npos) << bad.error();
  EXPECT_NE(bad.error().find("slab_cut.yaml"), std::string::npos) << bad.error();
  bad = loadScene(testing::writeSlabScene(dir, true, "cut: {commit_steps: -1}\n"));
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find("commit_steps"), std::string::npos) << bad.error();
  bad = loadScene(testing::writeSlabScene(dir, true, "cut: {commit: 3}\n"));
  EXPECT_FALSE(bad.ok());
}

}  // namespace
}  // namespace hysim::engine
