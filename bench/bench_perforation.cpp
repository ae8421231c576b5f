// The perforation check on the type 2 mesh: building the serosa (ray classification, BVH,
// grid) once, and the per-step check (wire points' clearance) with the loop in the cavity
// and deep in the wall near the serosa, for an anchored (static) serosa and a moving one.
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "hysim/cutting/mesh_io.hpp"
#include "hysim/engine/outer_wall.hpp"
#include "hysim/engine/tool.hpp"

namespace {

using namespace hysim;

constexpr double kBand = 2.15;  // margin 2 + wire radius 0.15

bool loadMesh(benchmark::State& bm, cutting::TetMesh& mesh, std::vector<std::uint8_t>& fixed, bool anchored) {
  auto m = cutting::readTetMesh(std::string(HYSIM_SOURCE_DIR) + "/assets/uterus_myoma_type2.msh");
  if (!m.ok()) {
    bm.SkipWithError(m.error().c_str());
    return false;
  }
  mesh = std::move(m.value());
  fixed.assign(static_cast<size_t>(mesh.numNodes()), 0);
  for (int i = 0; anchored && i < mesh.numNodes(); ++i) {
    const Eigen::Vector3d p = mesh.X.row(i).transpose();
    fixed[static_cast<size_t>(i)] = std::pow(p.x() / 25, 2) + std::pow(p.y() / 20, 2) + std::pow(p.z() / 33, 2) >= 1.0;
  }
  return true;
}

// Scope pivoting about the internal os (0, 0, -32), tip 16 mm beyond it (as in the scenes).
haptics::ToolPose pose(const Eigen::Vector3d& axis_in, double extension) {
  const Eigen::Vector3d axis = axis_in.normalized();
  const Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(axis).normalized();
  haptics::ToolPose p;
  p.tip = Eigen::Vector3d(0, 0, -32) + 16.0 * axis;
  p.rotation.col(0) = x;
  p.rotation.col(1) = axis.cross(x);
  p.rotation.col(2) = axis;
  p.extension_mm = extension;
  p.pedal = true;
  return p;
}

void BM_SerosaBuild(benchmark::State& bm) {
  cutting::TetMesh mesh;
  std::vector<std::uint8_t> fixed;
  if (!loadMesh(bm, mesh, fixed, true)) return;
  engine::OuterWall wall;
  for (auto _ : bm) wall.build(mesh, fixed, kBand);
  bm.counters["boundary_faces"] = wall.numBoundaryFaces();
  bm.counters["serosa_faces"] = wall.numFaces();
}

// One step's check: the clearance of every wire point (and, for a moving serosa, the update).
void check(benchmark::State& bm, bool anchored, const Eigen::Vector3d& axis, double extension) {
  cutting::TetMesh mesh;
  std::vector<std::uint8_t> fixed;
  if (!loadMesh(bm, mesh, fixed, anchored)) return;
  engine::OuterWall wall;
  wall.build(mesh, fixed, kBand);
  const sim::NodeVectors x = mesh.X;
  engine::LoopGeometry loop;
  Eigen::Matrix<double, Eigen::Dynamic, 3> wire;
  engine::loopPoints(loop, pose(axis, extension), wire);
  double clearance = 0.0;
  for (auto _ : bm) {
    wall.update(x);
    clearance = std::numeric_limits<double>::infinity();
    for (Eigen::Index i = 0; i < wire.rows(); ++i) {
      clearance = std::min(clearance, wall.clearance(wire.row(i).transpose()) - loop.wire_radius_mm);
    }
    benchmark::DoNotOptimize(clearance);
  }
  bm.counters["clearance_mm"] = clearance;
  bm.counters["static"] = wall.isStatic();
}

// Loop over the myoma in the cavity (type2_safe pass 1) and behind it near the serosa
// (type2_perforation pass 2, fully extended).
const Eigen::Vector3d kCavity(0.0, -0.0139, 0.9999);
const Eigen::Vector3d kDeep(0.0, -0.3416, 0.9399);

void BM_CheckStaticCavity(benchmark::State& bm) { check(bm, true, kCavity, 8.5); }
void BM_CheckStaticNearSerosa(benchmark::State& bm) { check(bm, true, kDeep, 17.0); }
void BM_CheckMovingCavity(benchmark::State& bm) { check(bm, false, kCavity, 8.5); }
void BM_CheckMovingNearSerosa(benchmark::State& bm) { check(bm, false, kDeep, 17.0); }

BENCHMARK(BM_SerosaBuild)->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK(BM_CheckStaticCavity)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CheckStaticNearSerosa)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CheckMovingCavity)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CheckMovingNearSerosa)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
