// Step time of the default scene (collision/contact + mass-spring), per integrator, and with
// the device input recorded (hysim run --record), side by side.
// Each batch of 100 steps starts from the same saved state (taken after 2 s of the scripted
// path, with the loop pressing on the myoma), so every repetition does the same work.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>

#include <filesystem>

#include "hysim/engine/replay.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/simulation.hpp"
#include "hysim/haptics/recording.hpp"

namespace {

using namespace hysim;

std::string scratchRecording() {
  return (std::filesystem::temp_directory_path() / "hysim_bench_step.hyrec").string();
}

void stepBatches(benchmark::State& bm, sim::Integrator integrator, bool record = false) {
  auto scene = engine::loadScene(std::string(HYSIM_SOURCE_DIR) + "/scenes/default.yaml");
  if (!scene.ok()) {
    bm.SkipWithError(scene.error().c_str());
    return;
  }
  scene->sim.integrator = integrator;
  auto sim = engine::Simulation::create(*scene);
  if (!sim.ok()) {
    bm.SkipWithError(sim.error().c_str());
    return;
  }
  haptics::RecordingWriter recorder;
  if (record) {
    auto header = engine::recordingHeader(*scene, {}, (*sim)->device().info().name);
    std::string error;
    if (!header.ok() || !recorder.open(scratchRecording(), *header, error) || !(*sim)->recordInputTo(&recorder).ok()) {
      bm.SkipWithError(("cannot record: " + error).c_str());
      return;
    }
  }
  for (int i = 0; i < 2000; ++i) (*sim)->step();
  const sim::State saved = (*sim)->state();
  constexpr int kBatch = 100;
  for (auto _ : bm) {
    (*sim)->restoreState(saved);
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < kBatch; ++i) (*sim)->step();
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    bm.SetIterationTime(s / kBatch);  // reported per step
  }
  bm.counters["substeps"] = (*sim)->model().substeps;
  bm.counters["tets"] = (*sim)->mesh().numTets();
  if (record) {
    std::string error;
    recorder.finish(error);
    std::filesystem::remove(scratchRecording());
  }
}

void BM_StepDefaultSceneSymplecticEuler(benchmark::State& bm) { stepBatches(bm, sim::Integrator::SymplecticEuler); }
void BM_StepDefaultSceneImplicitEuler(benchmark::State& bm) { stepBatches(bm, sim::Integrator::ImplicitEuler); }
void BM_StepDefaultSceneRecorded(benchmark::State& bm) { stepBatches(bm, sim::Integrator::SymplecticEuler, true); }

BENCHMARK(BM_StepDefaultSceneSymplecticEuler)->UseManualTime()->Unit(benchmark::kMicrosecond)->Iterations(20)->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_StepDefaultSceneRecorded)->UseManualTime()->Unit(benchmark::kMicrosecond)->Iterations(20)->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_StepDefaultSceneImplicitEuler)->UseManualTime()->Unit(benchmark::kMicrosecond)->Iterations(20)->Repetitions(5)->ReportAggregatesOnly(true);

}  // namespace

BENCHMARK_MAIN();
