// The trainee app's session logic on the real scenes, driven as the app drives it but without
// a window: keyboard-equivalent input through the pivot scope cuts a chip on the default scene,
// holding W stops at the fundus, and the perforating scene raises the alarm at the engine's event.
#include <gtest/gtest.h>

#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include "app_guidance.hpp"
#include "app_keys.hpp"
#include "app_monitor.hpp"
#include "app_pivot_scope.hpp"
#include "app_scope_limits.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/simulation.hpp"
#include "test_dir.hpp"

namespace hysim::tools {
namespace {

const std::string kSource = HYSIM_SOURCE_DIR;

std::unique_ptr<engine::Simulation> load(const std::string& scene_file) {
  auto scene = engine::loadScene(kSource + "/scenes/" + scene_file);
  EXPECT_TRUE(scene.ok()) << scene.error();
  auto sim = engine::Simulation::create(*scene);
  EXPECT_TRUE(sim.ok()) << sim.error();
  return std::move(sim.value());
}

// The app's frame loop without the window: keys held for `seconds`, the depth limit renewed
// from the drawn surface every frame of `frame_steps` steps, every step watched.
class KeyboardDriver {
 public:
  KeyboardDriver(engine::Simulation& sim, SessionMonitor& monitor) : sim_(sim), monitor_(monitor) {
    scope_ = attachPivotScope(sim);
  }
  void hold(const TraineeKeys& keys, double seconds, int frame_steps = 16) {
    const int steps = static_cast<int>(seconds / sim_.scene().sim.dt + 0.5);
    for (int done = 0; done < steps;) {
      sim_.fillSnapshot(snapshot_);
      limitScope(*scope_, snapshot_.tissue, scopeSize(sim_));
      scope_->setCommand(pivotCommand(keys));
      done += stepWatched(sim_, monitor_, std::min(frame_steps, steps - done));
      at_wall_ = at_wall_ || scope_->depthLimited();
      side_ = side_ || scope_->sideLimited();
    }
  }
  haptics::PivotScopeDevice& scope() { return *scope_; }
  bool stoppedAtWall() const { return at_wall_; }
  bool stoppedAtSide() const { return side_; }

 private:
  engine::Simulation& sim_;
  SessionMonitor& monitor_;
  haptics::PivotScopeDevice* scope_;
  render::RenderSnapshot snapshot_;
  bool at_wall_ = false;
  bool side_ = false;
};

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The default course's second pass by hand: tilt down over the myoma, push the loop out, hold
// the pedal, tilt down and draw the loop back through the myoma, lift out, let go.
TEST(TraineeSession, ManualPassByKeysRemovesAChip) {
  auto sim = load("default.yaml");
  const std::string log_path = (hysim::testing::testDir("TraineeSession") / "s.events.jsonl").string();
  SessionLog log;
  ASSERT_TRUE(log.open(log_path));
  SessionMonitor monitor(&log);
  KeyboardDriver keys(*sim, monitor);
  TraineeKeys k;
  k.pivot_down = true;
  keys.hold(k, 0.3);
  k = {};
  k.loop_out = true;
  keys.hold(k, 3.4);
  k = {};
  k.pedal_c = true;
  keys.hold(k, 0.05);
  EXPECT_TRUE(sim->deviceState().pose.pedal);  // C held: the electrode is active
  k.pivot_down = true;
  keys.hold(k, 0.37);
  k.pivot_down = false;
  k.loop_in = true;
  keys.hold(k, 3.0);
  k.loop_in = false;
  k.pivot_up = true;
  keys.hold(k, 0.4);
  k = {};
  keys.hold(k, 0.3);
  EXPECT_FALSE(sim->deviceState().pose.pedal);
  sim->commitPendingCut();
  monitor.afterStep(*sim);

  const GuidanceNumbers g = guidanceNumbers(*sim);
  EXPECT_GE(g.passes, 1);
  EXPECT_GE(g.chips, 1);
  EXPECT_GT(g.myoma_resected_mm3, 1.0);
  EXPECT_GT(g.myoma_resected_pct, 0.0);
  EXPECT_GT(g.electrode_active_s, 3.5);
  EXPECT_EQ(sim->perforations(), 0);
  EXPECT_EQ(sim->state().warnings, 0);
  const std::string events = readFile(log_path);
  EXPECT_NE(events.find("\"pedal_down\""), std::string::npos);
  EXPECT_NE(events.find("\"pass\""), std::string::npos);
}

// Holding W used to drive the scope through the fundus and out of the uterus.
TEST(TraineeSession, HoldingInsertStopsShortOfTheFundus) {
  auto sim = load("default.yaml");
  SessionMonitor monitor;
  KeyboardDriver keys(*sim, monitor);
  TraineeKeys k;
  k.insert = true;
  keys.hold(k, 5.0);  // 50 mm wanted; the cavity is about 40 mm long
  EXPECT_TRUE(keys.stoppedAtWall());
  const haptics::ToolPose tip = keys.scope().pose();
  EXPECT_GT(sim->outerWall().signedDistance(tip.tip), 5.0);  // well inside the uterus
  EXPECT_LT(tip.tip.z(), 24.0);                             // short of the cavity's far end
  EXPECT_EQ(sim->perforations(), 0);
}

// Deep in the cavity the tip is near the anterior wall: pivoting up towards it stops where
// it is (the shaft's side would be in the wall); pivoting away is free.
TEST(TraineeSession, PivotingStopsBeforeTheWallBeside) {
  auto sim = load("default.yaml");
  SessionMonitor monitor;
  KeyboardDriver keys(*sim, monitor);
  TraineeKeys k;
  k.insert = true;
  keys.hold(k, 2.0);
  render::RenderSnapshot snapshot;
  const auto freeUp = [&] {
    sim->fillSnapshot(snapshot);
    const haptics::ToolPose pose = keys.scope().pose();
    return forwardFreeMm(snapshot.tissue, pose.tip, pose.rotation.col(1));
  };
  const double free_before = freeUp();
  ASSERT_LT(free_before, scopeSize(*sim).shaft_radius_mm);  // the case this test is about
  k = {};
  k.pivot_up = true;
  keys.hold(k, 1.0);  // 0.3 rad wanted: about 6 mm towards the wall
  EXPECT_TRUE(keys.stoppedAtSide());
  EXPECT_GT(freeUp(), free_before - 0.3);
  const Eigen::Vector3d tip_before = keys.scope().pose().tip;
  k = {};
  k.pivot_down = true;
  keys.hold(k, 0.3);
  EXPECT_LT(keys.scope().pose().tip.y(), tip_before.y() - 1.0);
}

// The alarm is raised at the step the engine opens its perforation event, and stepping stops
// there so the app's frame draws it at once.
TEST(TraineeSession, PerforatingSceneRaisesTheAlarmWithin50ms) {
  auto sim = load("type2_perforation.yaml");
  const std::string log_path = (hysim::testing::testDir("TraineeSession") / "p.events.jsonl").string();
  SessionLog log;
  ASSERT_TRUE(log.open(log_path));
  SessionMonitor monitor(&log);
  bool raised = false;
  const int frame_steps = 100;  // a slow frame: 0.1 s of steps
  while (!raised && sim->state().steps < static_cast<std::uint64_t>(sim->scene().steps)) {
    stepWatched(*sim, monitor, frame_steps);
    raised = monitor.alarm().raised() > 0;
  }
  ASSERT_TRUE(raised) << "the perforating scene should perforate";
  ASSERT_FALSE(sim->perforationEvents().empty());
  const double event_s = sim->perforationEvents().front().time_s;
  EXPECT_LE(monitor.alarm().raisedAtS() - event_s, 0.050);
  EXPECT_GE(monitor.alarm().raisedAtS(), event_s);
  EXPECT_DOUBLE_EQ(sim->state().time, monitor.alarm().raisedAtS());  // stopped at that step
  EXPECT_TRUE(monitor.alarm().active(sim->state().time));
  Eigen::Matrix<double, Eigen::Dynamic, 3> wire;
  EXPECT_EQ(serosaBar(serosaDistanceMm(*sim, wire), sim->scene().safety.perforation_margin_mm).level,
            SerosaLevel::Danger);
  EXPECT_NE(readFile(log_path).find("\"perforation\""), std::string::npos);
}

}  // namespace
}  // namespace hysim::tools
