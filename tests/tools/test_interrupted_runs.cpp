// A run stopped midway: SIGINT/SIGTERM end it cleanly with a partial report (exit 4); SIGKILL at
// any moment leaves every file it writes (frames, report, session files) complete or absent.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <thread>

#include "hysim/render/image.hpp"
#include "run_hysim.hpp"
#include "session_store.hpp"
#include "spawn_hysim.hpp"

namespace hysim {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::vector<fs::path> sessionFiles(const fs::path& data) {
  std::vector<fs::path> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(data / "sessions", ec))
    if (e.path().extension() == ".json") out.push_back(e.path());
  return out;
}

TEST(InterruptedRun, SigintAndSigtermWriteAPartialReport) {
  for (const int signal : {SIGINT, SIGTERM}) {
    const fs::path dir = testing::freshOutputDir("InterruptedRun", "signal_" + std::to_string(signal));
    const std::string report = (dir / "report.json").string();
    const pid_t pid = testing::spawnHysim(
        {"run", "--quiet", "--report", report, "--trainee", "Cleo", "--data-dir", (dir / "data").string()});
    ASSERT_GT(pid, 0);
    ASSERT_TRUE(testing::waitForFileEndingIn(dir / "data" / "sessions", ".json"));
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    kill(pid, signal);
    EXPECT_EQ(testing::waitStatus(pid), 4) << "signal " << signal;
    std::ifstream in(report);
    ASSERT_TRUE(in) << "no report after signal " << signal;
    const nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_TRUE(j["partial"].get<bool>());
    EXPECT_GT(j["steps"].get<int>(), 0);
    EXPECT_LT(j["steps"].get<int>(), 96700);  // the default scene's
    EXPECT_TRUE(j.contains("assessment"));
    const auto files = sessionFiles(dir / "data");
    ASSERT_EQ(files.size(), 1u);
    auto session = tools::readSessionFile(files[0].string());
    ASSERT_TRUE(session.ok()) << session.error();
    EXPECT_FALSE(session->complete);  // stopped early: listed as incomplete, with what it did
    EXPECT_NEAR(session->duration_s, 1e-3 * j["steps"].get<int>(), 1e-9);
  }
}

// Checks every file a run wrote: each frame a whole PNG, the report whole JSON, each session
// file readable. Temporaries (*.tmp) are not results; they may stay after a kill.
// Returns the number of frames found.
int expectEveryFileWhole(const fs::path& dir) {
  int frames = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file() || e.path().extension() == ".tmp") continue;
    const std::string ext = e.path().extension().string();
    if (ext == ".png") {
      auto image = render::readPng(e.path().string());
      EXPECT_TRUE(image.ok()) << e.path() << ": " << (image.ok() ? "" : image.error());
      ++frames;
    } else if (e.path().filename() == "report.json") {
      std::ifstream in(e.path());
      const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
      EXPECT_FALSE(j.is_discarded()) << e.path();
      EXPECT_TRUE(j.contains("state_hash")) << e.path();
    } else if (ext == ".json") {
      EXPECT_TRUE(tools::readSessionFile(e.path().string()).ok()) << e.path();
    }
  }
  return frames;
}

TEST(InterruptedRun, KilledAtFiftyRandomMomentsLeavesNoBrokenFile) {
  const std::vector<std::string> base = {"run", "scenes/diagnostic.yaml", "--quiet", "--steps", "300", "--every", "10"};
  const auto argsFor = [&base](const fs::path& dir) {
    std::vector<std::string> a = base;
    const std::vector<std::string> outputs = {"--frames",  (dir / "frames").string(), "--report",
                                              (dir / "report.json").string(), "--trainee", "Dan",
                                              "--data-dir", (dir / "data").string()};
    a.insert(a.end(), outputs.begin(), outputs.end());
    return a;
  };
  // One whole run first: how long a run takes here, and that it writes every kind of file.
  const fs::path whole = testing::freshOutputDir("InterruptedRun", "whole");
  const auto t0 = Clock::now();
  ASSERT_EQ(testing::waitStatus(testing::spawnHysim(argsFor(whole))), 0);
  const double run_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  EXPECT_EQ(expectEveryFileWhole(whole), 31);
  std::mt19937 rng(20261129);
  std::uniform_real_distribution<double> when(0.0, 0.8 * run_ms);  // (start-up included)
  int killed = 0, with_frames = 0;
  for (int k = 0; k < 50; ++k) {
    const fs::path dir = testing::freshOutputDir("InterruptedRun", "kill_" + std::to_string(k));
    const pid_t pid = testing::spawnHysim(argsFor(dir));
    ASSERT_GT(pid, 0);
    std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(when(rng)));
    kill(pid, SIGKILL);
    killed += testing::waitStatus(pid) == 128 + SIGKILL;
    with_frames += expectEveryFileWhole(dir) > 0;
  }
  std::printf("killed %d of 50 runs before they ended; %d had written frames\n", killed, with_frames);
  EXPECT_GE(killed, 20);  // most kills land during the runs, not after them
  EXPECT_GE(with_frames, 5);
}

}  // namespace
}  // namespace hysim
