// Chips: free pieces a cut sets loose. `remove` (default) drops them; `simulate` keeps them
// as Bullet rigid bodies that sink onto the cavity wall, collide with the tool and are drawn.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "alloc_counter.hpp"
#include "box_mesh.hpp"
#include "test_dir.hpp"
#include "hysim/cutting/mesh_io.hpp"
#include "hysim/engine/chips.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/simulation.hpp"

namespace hysim::engine {
namespace {

namespace fs = std::filesystem;

// The running test's own folder (test_dir.hpp).
fs::path outputDir() { return testing::testDir("chips"); }

// The slab of test_shaving (30 x 20 x 10 mm, top at z = 0, anchored at the bottom), with
// gravity along -z; one pass of the active loop cuts a 2 mm deep chip off the top.
// `chips_line` is the scene's `chips` entry (empty: none).
std::string writeSlabScene(const std::string& name, const std::string& chips_line) {
  const fs::path dir = outputDir();
  if (!fs::exists(dir / "slab.msh")) {
    cutting::TetMesh slab = testing::boxTetMesh(15, 10, 5, 2.0);
    for (int i = 0; i < slab.numNodes(); ++i) slab.X.row(i) -= Eigen::RowVector3d(15, 10, 10);
    EXPECT_TRUE(cutting::writeMesh((dir / "slab.msh").string(), slab).ok());
  }
  std::ofstream(dir / name)
      << "name: slab\n"
         "mesh: slab.msh\n"
         "materials:\n"
         "  - {name: myoma, label: 1, young_modulus_kpa: 150, density_g_cm3: 1.1}\n"
         "anchors:\n"
         "  - box: {min: [-20, -20, -11], max: [20, 20, -9.5]}\n"
         "simulation: {dt_ms: 1.0, steps: 1300, drag_per_s: 30, gravity_mm_s2: [0, 0, -9810]}\n"
         "tool_path:\n"
         "  - {t_s: 0.0, tip: [8, 0, 4.5], axis: [1, 0, 0], up: [0, 0, 1]}\n"
         "  - {t_s: 0.05, tip: [8, 0, 4.5], axis: [1, 0, 0], up: [0, 0, 1], pedal: true}\n"
         "  - {t_s: 1.05, tip: [-32, 0, 4.5], axis: [1, 0, 0], up: [0, 0, 1], pedal: true}\n"
         "  - {t_s: 1.10, tip: [-32, 0, 4.5], axis: [1, 0, 0], up: [0, 0, 1]}\n"
         // Then the scope backs away, up and out of the chips' way.
         "  - {t_s: 1.40, tip: [-40, 0, 15], axis: [1, 0, 0], up: [0, 0, 1]}\n"
      << chips_line << (chips_line.empty() ? "" : "\n");
  return (dir / name).string();
}

std::unique_ptr<Simulation> makeSim(const std::string& path) {
  auto scene = loadScene(path);
  EXPECT_TRUE(scene.ok()) << scene.error();
  if (!scene.ok()) return nullptr;
  auto sim = Simulation::create(*scene);
  EXPECT_TRUE(sim.ok()) << sim.error();
  return sim.ok() ? std::move(*sim) : nullptr;
}

// Steps two simulations side by side.
void stepBoth(Simulation& a, Simulation& b, int steps) {
  for (int i = 0; i < steps; ++i) {
    a.step();
    b.step();
  }
}

// Lowest z of a chip's surface in the world.
double lowestZ(const ChipBody& chip) {
  double z = 1e30;
  for (size_t v = 0; v < chip.surface.positions.size() / 3; ++v) {
    const Eigen::Vector3d p(chip.surface.positions[3 * v], chip.surface.positions[3 * v + 1],
                            chip.surface.positions[3 * v + 2]);
    z = std::min(z, (chip.position + chip.rotation * p).z());
  }
  return z;
}

TEST(Chips, SceneKeys) {
  auto scene = loadScene(writeSlabScene("simulate_short.yaml", "chips: simulate"));
  ASSERT_TRUE(scene.ok()) << scene.error();
  EXPECT_EQ(scene->chips.mode, ChipSettings::Mode::Simulate);
  scene = loadScene(writeSlabScene("default_mode.yaml", ""));
  ASSERT_TRUE(scene.ok()) << scene.error();
  EXPECT_EQ(scene->chips.mode, ChipSettings::Mode::Remove);
  scene = loadScene(writeSlabScene("simulate_map.yaml", "chips: {mode: simulate, max_chips: 4, drag_per_s: 5}"));
  ASSERT_TRUE(scene.ok()) << scene.error();
  EXPECT_EQ(scene->chips.mode, ChipSettings::Mode::Simulate);
  EXPECT_EQ(scene->chips.max_chips, 4);
  EXPECT_DOUBLE_EQ(scene->chips.drag_per_s, 5.0);
}

TEST(Chips, BadValueNamesFileLineAndKey) {
  // The scene's line 14 holds the chips entry.
  const std::string bad = writeSlabScene("bad_mode.yaml", "chips: sometimes");
  auto scene = loadScene(bad);
  ASSERT_FALSE(scene.ok());
  EXPECT_NE(scene.error().find(bad + ":14:"), std::string::npos) << scene.error();
  EXPECT_NE(scene.error().find("'chips' must be remove or simulate, got 'sometimes'"), std::string::npos) << scene.error();

  const std::string bad_key = writeSlabScene("bad_key.yaml", "chips: {mode: simulate, max: 3}");
  scene = loadScene(bad_key);
  ASSERT_FALSE(scene.ok());
  EXPECT_NE(scene.error().find(bad_key + ":14:"), std::string::npos) << scene.error();
  EXPECT_NE(scene.error().find("unknown key 'max' in 'chips'"), std::string::npos) << scene.error();

  const std::string bad_cap = writeSlabScene("bad_cap.yaml", "chips: {mode: simulate, max_chips: 0}");
  scene = loadScene(bad_cap);
  ASSERT_FALSE(scene.ok());
  EXPECT_NE(scene.error().find(bad_cap + ":14:"), std::string::npos) << scene.error();
  EXPECT_NE(scene.error().find("'max_chips' must be between 1 and 256"), std::string::npos) << scene.error();
}

// A floor: the boundary of a 40 x 40 x 4 mm box with its top at z = 0.
void setFloor(ChipWorld& world) {
  cutting::TetMesh box = testing::boxTetMesh(10, 10, 1, 4.0);
  for (int i = 0; i < box.numNodes(); ++i) box.X.row(i) -= Eigen::RowVector3d(20, 20, 4);
  sim::NodeVectors x = box.X;
  world.setCavity(x, cutting::boundaryFaces(box));
}

// A cube chip of side a centred at c.
ChipShape cubeChip(const Eigen::Vector3d& c, double a) {
  cutting::TetMesh cube = testing::boxTetMesh(1, 1, 1, a);
  ChipShape chip;
  chip.vertices = cube.X;
  for (int i = 0; i < cube.numNodes(); ++i) chip.vertices.row(i) += (c - Eigen::Vector3d::Constant(0.5 * a)).transpose();
  chip.triangles = cutting::boundaryFaces(cube);
  chip.material.assign(static_cast<size_t>(cube.numNodes()), render::SurfaceMaterial::Myoma);
  chip.centre = c;
  chip.volume_mm3 = a * a * a;
  chip.mass_g = 1.1e-3 * chip.volume_mm3;
  return chip;
}

ChipToolGeometry toolFarAway() { return ChipToolGeometry{}; }

haptics::ToolPose poseAt(const Eigen::Vector3d& tip) {
  haptics::ToolPose pose;
  pose.tip = tip;
  return pose;
}

TEST(Chips, ACubeSinksAndComesToRestOnTheFloor) {
  ChipSettings settings;
  settings.mode = ChipSettings::Mode::Simulate;
  ChipWorld world(settings, Eigen::Vector3d(0, 0, -9810), 1e-3, toolFarAway());
  world.moveTool(poseAt(Eigen::Vector3d(0, 0, 200)));  // far above the floor
  setFloor(world);
  ASSERT_GE(world.addChip(cubeChip(Eigen::Vector3d(0.3, -0.2, 6.0), 2.0)), 0);
  double previous_z = 6.0;
  bool monotone = true;
  for (int i = 0; i < 1500; ++i) {
    world.moveTool(poseAt(Eigen::Vector3d(0, 0, 200)));
    world.step();
    ASSERT_EQ(world.numChips(), 1);
    const double z = world.chips()[0].position.z();
    monotone = monotone && z <= previous_z + 0.01;  // penetration recovery lifts it by ~5 um
    previous_z = z;
  }
  const ChipBody& chip = world.chips()[0];
  EXPECT_TRUE(monotone) << "it sinks; it does not bounce";
  // At rest on the floor (z = 0): the cube's centre a half side above it (plus Bullet's
  // collision margins, 0.04 mm each).
  EXPECT_NEAR(chip.position.z(), 1.0, 0.15);
  EXPECT_GT(lowestZ(chip), -0.05);
  EXPECT_LT(chip.velocity.norm(), 1.0);
  EXPECT_NEAR(chip.position.x(), 0.3, 0.1);
  EXPECT_NEAR(chip.position.y(), -0.2, 0.1);
}

TEST(Chips, TheToolPushesAChip) {
  ChipSettings settings;
  settings.mode = ChipSettings::Mode::Simulate;
  ChipToolGeometry tool;
  tool.shaft_radius_mm = 2.0;
  tool.shaft_length_mm = 30.0;
  ChipWorld world(settings, Eigen::Vector3d(0, 0, -9810), 1e-3, tool);
  setFloor(world);
  // The sheath lies along +x (body z = world x) 2.5 mm above the floor, tip at x = -10; it
  // slides forward at 20 mm/s into a cube resting at the origin.
  haptics::ToolPose pose;
  pose.rotation << 0, 0, 1, 1, 0, 0, 0, 1, 0;  // body x = world y, body y = world z, body z = world x
  auto at = [&](double t) {
    pose.tip = Eigen::Vector3d(-6.0 + 20.0 * t, 0, 2.5);
    return pose;
  };
  world.moveTool(at(0));
  ASSERT_GE(world.addChip(cubeChip(Eigen::Vector3d(0, 0, 1.05), 2.0)), 0);
  for (int i = 1; i <= 500; ++i) {
    world.moveTool(at(1e-3 * i));
    world.step();
  }
  // The tip reached x = 4: the cube's near face (x = -1) was pushed to about x = 4 + margins.
  ASSERT_EQ(world.numChips(), 1);
  EXPECT_GT(world.chips()[0].position.x(), 4.0);
  EXPECT_GT(lowestZ(world.chips()[0]), -0.1);
}

TEST(Chips, OldestChipGoesBeyondTheCapAndChipsLeavingTheCavityAreRemoved) {
  ChipSettings settings;
  settings.mode = ChipSettings::Mode::Simulate;
  settings.max_chips = 3;
  ChipWorld world(settings, Eigen::Vector3d(0, 0, -9810), 1e-3, toolFarAway());
  world.moveTool(poseAt(Eigen::Vector3d(0, 0, 200)));
  setFloor(world);
  for (int k = 0; k < 4; ++k) world.addChip(cubeChip(Eigen::Vector3d(-12.0 + 6.0 * k, 0, 3.0), 1.5));
  ASSERT_EQ(world.numChips(), 3);
  EXPECT_EQ(world.chips()[0].id, 1);
  EXPECT_EQ(world.removedOverCap(), 1);
  // One beside the floor falls past it and out of the cavity's bounds.
  world.addChip(cubeChip(Eigen::Vector3d(30.0, 0, 3.0), 1.5));
  ASSERT_EQ(world.numChips(), 3);
  for (int i = 0; i < 3000 && world.removedOutside() == 0; ++i) world.step();
  EXPECT_EQ(world.removedOutside(), 1);
  EXPECT_EQ(world.numChips(), 2);
}

TEST(Chips, RemoveModeHasNoChipWorld) {
  auto sim = makeSim(writeSlabScene("remove.yaml", "chips: remove"));
  ASSERT_NE(sim, nullptr);
  for (int i = 0; i < 1300; ++i) sim->step();
  EXPECT_EQ(sim->chips(), nullptr);
  ASSERT_EQ(sim->passes().size(), 1u);
  EXPECT_EQ(sim->passes()[0].chips, 1);
  render::RenderSnapshot snap;
  sim->fillSnapshot(snap);
  EXPECT_TRUE(snap.chips.empty());
}

// chips: {optimize: false}: the cut leaves the chip as it cut it (only the slab is
// optimised); the chip is removed all the same, the slab's mesh is valid and its worst tet
// no worse than the unoptimised cut's bound.
TEST(Chips, ChipsLeftUnoptimisedAreRemovedTheSame) {
  const std::string leave = writeSlabScene("leave.yaml", "chips: {mode: remove, optimize: false}");
  const std::string keep = writeSlabScene("keep.yaml", "chips: {mode: remove, optimize: true}");
  auto scene = loadScene(leave);
  ASSERT_TRUE(scene.ok()) << scene.error();
  EXPECT_FALSE(scene->chips.optimize);
  EXPECT_FALSE(loadScene(writeSlabScene("default_optimize.yaml", ""))->chips.optimize);  // the default
  EXPECT_TRUE(loadScene(keep)->chips.optimize);
  auto left = makeSim(leave);
  auto optimised = makeSim(keep);
  ASSERT_NE(left, nullptr);
  ASSERT_NE(optimised, nullptr);
  stepBoth(*left, *optimised, 1300);
  ASSERT_EQ(left->passes().size(), 1u);
  ASSERT_FALSE(left->passes()[0].cut_failed) << left->passes()[0].message;
  EXPECT_EQ(left->passes()[0].chips, 1);
  EXPECT_EQ(optimised->passes()[0].chips, 1);
  EXPECT_GT(left->passes()[0].unoptimised_chip_elements, 0);
  EXPECT_EQ(optimised->passes()[0].unoptimised_chip_elements, 0);
  // The same chip to within what the optimisation moves (its volume budget).
  EXPECT_NEAR(left->passes()[0].removed_mm3, optimised->passes()[0].removed_mm3,
              0.02 * optimised->passes()[0].removed_mm3);
  EXPECT_TRUE(cutting::validate(left->mesh()).ok());
  EXPECT_GE(left->passes()[0].q_min, 0.25 * optimised->passes()[0].q_min);
  EXPECT_EQ(left->state().warnings, 0);

  const std::string bad = writeSlabScene("bad_optimize.yaml", "chips: {optimize: sometimes}");
  scene = loadScene(bad);
  ASSERT_FALSE(scene.ok());
  EXPECT_NE(scene.error().find(bad + ":14:"), std::string::npos) << scene.error();
}

// The chip cut off the slab's top sinks into the groove the loop left and stays there: it
// does not fall through the tissue. Its volume counts as resected as in remove mode.
TEST(Chips, TheCutChipRestsInItsGroove) {
  auto removed = makeSim(writeSlabScene("remove2.yaml", ""));
  auto sim = makeSim(writeSlabScene("simulate.yaml", "chips: simulate"));
  ASSERT_NE(sim, nullptr);
  ASSERT_NE(removed, nullptr);
  stepBoth(*sim, *removed, 1300);
  ASSERT_EQ(sim->passes().size(), 1u);
  ASSERT_FALSE(sim->passes()[0].cut_failed) << sim->passes()[0].message;
  EXPECT_EQ(sim->passes()[0].chips, 1);
  EXPECT_DOUBLE_EQ(sim->passes()[0].removed_mm3, removed->passes()[0].removed_mm3);
  ASSERT_NE(sim->chips(), nullptr);
  ASSERT_EQ(sim->chips()->numChips(), 1);
  const ChipBody start = sim->chips()->chips()[0];
  // The chip is built from the piece's current shape, the resected volume from its rest shape
  // (the cut happens in the rest configuration): equal up to the tissue's small deformation.
  EXPECT_NEAR(start.volume_mm3, sim->passes()[0].removed_mm3, 1e-3 * sim->passes()[0].removed_mm3);
  for (int i = 0; i < 1400; ++i) sim->step();
  ASSERT_EQ(sim->chips()->numChips(), 1);
  const Eigen::Vector3d before_last = sim->chips()->chips()[0].position;
  for (int i = 0; i < 100; ++i) sim->step();
  ASSERT_EQ(sim->chips()->numChips(), 1);
  const ChipBody& chip = sim->chips()->chips()[0];
  // The groove's bottom is 2 mm below the slab's top (z = 0); the tissue sags a little.
  EXPECT_GT(lowestZ(chip), -2.6);
  EXPECT_LT(chip.position.z(), start.position.z() + 0.5);
  // At rest: over the last 0.1 s it drifts less than 0.5 mm/s (0.12 measured; its contact
  // with the tissue jitters by hundredths of a millimetre, at up to 3 mm/s).
  const double drift_mm_s = (chip.position - before_last).norm() / 0.1;
  std::printf("chip: drift over the last 0.1 s %.3f mm/s, speed %.3f mm/s\n", drift_mm_s, chip.velocity.norm());
  EXPECT_LT(drift_mm_s, 0.5);
  EXPECT_LT((chip.position - start.position).norm(), 3.0);
  EXPECT_EQ(sim->state().warnings, 0);

  render::RenderSnapshot snap;
  sim->fillSnapshot(snap);
  ASSERT_EQ(snap.chips.size(), 1u);
  EXPECT_EQ(snap.chips[0].surface.positions.size(), chip.surface.positions.size());
  EXPECT_FLOAT_EQ(snap.chips[0].pose.position[2], static_cast<float>(chip.position.z()));
}

TEST(Chips, SameRunTwiceGivesTheSameChipPosesAndHash) {
  const std::string path = writeSlabScene("simulate_det.yaml", "chips: simulate");
  auto a = makeSim(path);
  auto b = makeSim(path);
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  for (int i = 0; i < 1800; ++i) {
    a->step();
    b->step();
  }
  ASSERT_EQ(a->chips()->numChips(), 1);
  ASSERT_EQ(b->chips()->numChips(), 1);
  EXPECT_EQ(a->chips()->chips()[0].position, b->chips()->chips()[0].position);
  EXPECT_EQ(a->chips()->chips()[0].rotation, b->chips()->chips()[0].rotation);
  EXPECT_EQ(a->stateHash(), b->stateHash());
  EXPECT_NE(a->stateHash(), sim::stateHash(a->state()));  // the chip is in the hash
}

// Steady state after the cut: the tissue settles, the chip sinks into its groove. Bullet's
// arrays only grow, so once the contacts have been seen the step allocates nothing.
TEST(Chips, StepWithAChipAllocatesNothingInSteadyState) {
  auto sim = makeSim(writeSlabScene("simulate_alloc.yaml", "chips: simulate"));
  ASSERT_NE(sim, nullptr);
  for (int i = 0; i < 1600; ++i) sim->step();
  ASSERT_EQ(sim->chips()->numChips(), 1);
  long count = 0;
  {
    testing::AllocationCounter counter;
    for (int i = 0; i < 500; ++i) sim->step();
    count = counter.count();
  }
  EXPECT_EQ(sim->chips()->numChips(), 1);
  EXPECT_EQ(count, 0);
}

// A Bullet world with 16 chips resting on a triangle-mesh floor keeps them all; the cost of
// a step is printed and recorded, not bounded (a wall-clock bound fails on a busy machine).
TEST(Chips, SixteenChipsRestOnAFloor) {
  ChipSettings settings;
  settings.mode = ChipSettings::Mode::Simulate;
  ChipWorld world(settings, Eigen::Vector3d(0, 0, -9810), 1e-3, toolFarAway());
  world.moveTool(poseAt(Eigen::Vector3d(0, 0, 200)));
  setFloor(world);
  for (int k = 0; k < 16; ++k) {
    world.addChip(cubeChip(Eigen::Vector3d(-12.0 + 8.0 * (k % 4), -12.0 + 8.0 * (k / 4), 2.0 + 0.2 * k), 2.0));
  }
  ASSERT_EQ(world.numChips(), 16);
  using Clock = std::chrono::steady_clock;
  auto t0 = Clock::now();
  for (int i = 0; i < 300; ++i) world.step();  // sinking and landing
  const double falling_us = std::chrono::duration<double, std::micro>(Clock::now() - t0).count() / 300;
  for (int i = 0; i < 300; ++i) world.step();
  t0 = Clock::now();
  for (int i = 0; i < 1000; ++i) world.step();  // at rest (some asleep)
  const double resting_us = std::chrono::duration<double, std::micro>(Clock::now() - t0).count() / 1000;
  std::printf("Bullet step, 16 chips: %.1f us while sinking, %.1f us at rest\n", falling_us, resting_us);
  RecordProperty("falling_us", std::to_string(falling_us));
  RecordProperty("resting_us", std::to_string(resting_us));
  EXPECT_EQ(world.numChips(), 16);
}

}  // namespace
}  // namespace hysim::engine
