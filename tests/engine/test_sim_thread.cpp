// The pacing of the fixed steps to the wall clock, and the simulation thread that steps a
// Simulation paced that way: the same steps as stepping it directly, whatever the timing.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "hysim/engine/pacer.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/sim_thread.hpp"
#include "hysim/engine/simulation.hpp"

namespace hysim::engine {
namespace {

TEST(Pacer, StepsDueKeepTheFraction) {
  Pacer pacer(1e-3);
  EXPECT_EQ(pacer.due(0.0035), 3);
  EXPECT_NEAR(pacer.untilNextStep(), 0.0005, 1e-12);
  EXPECT_EQ(pacer.due(0.0006), 1);  // 0.5 ms left over + 0.6 ms
  EXPECT_EQ(pacer.due(-1.0), 0);    // a clock going back adds nothing
  EXPECT_EQ(pacer.behindS(), 0.0);
  EXPECT_EQ(pacer.lagEvents(), 0);
}

TEST(Pacer, SpeedScalesWallTime) {
  Pacer pacer(1e-3);
  EXPECT_EQ(pacer.due(0.010, 0.5), 5);
  EXPECT_EQ(pacer.due(0.010, 2.0), 20);
}

TEST(Pacer, ALagBeyondTheLimitIsGivenUpAndCounted) {
  Pacer pacer(1e-3, 0.1);
  EXPECT_EQ(pacer.due(0.5), 100);  // a 0.5 s stall: only 0.1 s is stepped
  EXPECT_NEAR(pacer.behindS(), 0.4, 1e-12);
  EXPECT_EQ(pacer.lagEvents(), 1);
  pacer.keep(30);  // 30 steps not done are due again
  EXPECT_EQ(pacer.due(0.0), 30);
  pacer.due(0.0004);
  pacer.clearDue();
  EXPECT_NEAR(pacer.untilNextStep(), 1e-3, 1e-12);
}

Scene diagnosticScene() {
  auto scene = loadScene(std::string(HYSIM_SOURCE_DIR) + "/scenes/diagnostic.yaml");
  EXPECT_TRUE(scene.ok()) << scene.error();
  return *scene;
}

// Polls until the thread has done at least `steps` steps (a guard, not a timing assertion:
// a machine too slow for it fails with a clear message instead of hanging).
long long waitForSteps(SimThread& thread, long long steps) {
  long long done = 0;
  for (int i = 0; i < 12000 && done < steps; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    done = thread.access([&] { return thread.stats().steps; });
  }
  return done;
}

TEST(SimThread, StepsLikeDirectSteppingAndCallsAfterEachStep) {
  const Scene scene = diagnosticScene();
  auto threaded = Simulation::create(scene);
  auto direct = Simulation::create(scene);
  ASSERT_TRUE(threaded.ok() && direct.ok());
  long long after_steps = 0;
  SimThread thread;
  thread.attach(threaded->get(), [&](Simulation&) { ++after_steps; });
  ASSERT_GE(waitForSteps(thread, 60), 60) << "the simulation thread did not step";
  thread.attach(nullptr);
  const long long steps = static_cast<long long>((*threaded)->state().steps);
  EXPECT_EQ(after_steps, steps);
  for (long long i = 0; i < steps; ++i) (*direct)->step();
  EXPECT_EQ((*threaded)->stateHash(), (*direct)->stateHash());
}

TEST(SimThread, PausedMeansNoSteps) {
  auto sim = Simulation::create(diagnosticScene());
  ASSERT_TRUE(sim.ok());
  SimThread thread;
  thread.attach(sim->get());
  ASSERT_GE(waitForSteps(thread, 5), 5);
  const auto paused_at = thread.access([&] {
    thread.setPaused(true);
    return (*sim)->state().steps;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_EQ(thread.access([&] { return (*sim)->state().steps; }), paused_at);
  thread.access([&] { thread.setPaused(false); });
  EXPECT_GT(waitForSteps(thread, static_cast<long long>(paused_at) + 5), static_cast<long long>(paused_at));
}

TEST(SimThread, AttachingAnotherSimulationStartsItsStatistics) {
  const Scene scene = diagnosticScene();
  auto first = Simulation::create(scene);
  auto second = Simulation::create(scene);
  ASSERT_TRUE(first.ok() && second.ok());
  SimThread thread;
  thread.attach(first->get());
  ASSERT_GE(waitForSteps(thread, 5), 5);
  thread.attach(second->get());
  const auto first_steps = (*first)->state().steps;
  ASSERT_GE(waitForSteps(thread, 3), 3);
  thread.access([&] {
    EXPECT_EQ((*first)->state().steps, first_steps);  // left alone once replaced
    EXPECT_EQ(static_cast<long long>((*second)->state().steps), thread.stats().steps);
  });
}

}  // namespace
}  // namespace hysim::engine
