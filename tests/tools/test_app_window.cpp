// The trainee window as a trainee meets it, under a private X server (Xvfb) with scripted
// keys (tests/data/app/*.txt): pick a case on the start screen, cut two passes by keys, end
// the case into the debrief, go back and open the progress screen, the session stored; and the
// perforating scene's alarm on screen. Pictures are compared with
// golden images within a tolerance (the view's details depend on frame timing).
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <regex>
#include <string>

#include "hysim/render/image.hpp"
#include "require_gl.hpp"
#include "run_hysim.hpp"
#include "session_store.hpp"
#include "spawn_hysim.hpp"
#include "xvfb.hpp"

namespace hysim::testing {
namespace {

namespace fs = std::filesystem;

#ifdef HYSIM_APP_BINARY
constexpr const char* kApp = HYSIM_APP_BINARY;
#else
constexpr const char* kApp = nullptr;
#endif

// Runs hysim-app in `dir` on `display` with the data folder dir/data; stdout and stderr.
Output runApp(const std::string& display, const std::string& dir, const std::string& args) {
  Output out;
  const std::string cmd = "cd " + dir + " && DISPLAY=" + display + " HYSIM_DATA_DIR=" + dir + "/data " + kApp +
                          " " + args + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  if (pipe == nullptr) return out;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, pipe)) > 0) out.text.append(buf, n);
  const int status = pclose(pipe);
  out.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return out;
}

std::string dataFile(const std::string& name) { return std::string(HYSIM_SOURCE_DIR) + "/tests/data/" + name; }

// `shot` against the golden image: the fraction of pixels with a channel more than
// `threshold` apart must stay within `max_fraction`. A missing golden is written (then fails).
void expectLikeGolden(const std::string& shot, const std::string& golden_name, int threshold, double max_fraction) {
  auto image = render::readPng(shot);
  ASSERT_TRUE(image.ok()) << image.error();
  const std::string golden_path = dataFile("golden/" + golden_name);
  auto golden = render::readPng(golden_path);
  if (!golden.ok()) {
    fs::copy_file(shot, golden_path, fs::copy_options::overwrite_existing);
    FAIL() << "no golden image; wrote " << golden_path << " from " << shot << ": look at it, then commit it";
  }
  auto diff = render::compareImages(*image, *golden, threshold);
  ASSERT_TRUE(diff.ok()) << diff.error();
  std::printf("%s against %s: %.4f of the pixels over %d, mean %.2f\n", shot.c_str(), golden_name.c_str(),
              diff->fraction_over, threshold, diff->mean_abs_diff);
  EXPECT_LE(diff->fraction_over, max_fraction)
      << shot << " differs from " << golden_path << " (mean " << diff->mean_abs_diff << ")";
}

// The fraction of strongly red pixels (the alarm's rim).
double redFraction(const render::Image& image) {
  long red = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const std::uint8_t* p = image.pixel(x, y);
      red += p[0] > 140 && p[1] < 50 && p[2] < 50;
    }
  }
  return static_cast<double>(red) / (static_cast<double>(image.width) * image.height);
}

class AppWindow : public ::testing::Test {
 protected:
  void SetUp() override {
    if (kApp == nullptr || !Xvfb::available()) {
      HYSIM_SKIP_OR_FAIL_WITHOUT_GL("no hysim-app or no Xvfb (tools/install-deps installs it)");
    }
    ASSERT_TRUE(xvfb_.start(1024, 768)) << "Xvfb did not start";
  }
  Xvfb xvfb_;
};

TEST_F(AppWindow, StartScreenThenTwoPassesByKeysAreStored) {
  const std::string dir = freshOutputDir("AppWindow", "two_passes");
  const Output out = runApp(xvfb_.display(), dir, "--trainee Ann --input " + dataFile("app/two_passes.txt"));
  ASSERT_EQ(out.exit_code, 0) << out.text;
  EXPECT_NE(out.text.find("frame captured in start.png"), std::string::npos) << out.text;
  EXPECT_NE(out.text.find("frame captured in case.png"), std::string::npos) << out.text;
  EXPECT_NE(out.text.find("frame captured in debrief.png"), std::string::npos) << out.text;
  EXPECT_NE(out.text.find("frame captured in progress.png"), std::string::npos) << out.text;
  EXPECT_NE(out.text.find("warnings 0, perforations 0"), std::string::npos) << out.text;
  // The start screen is the same every time; the others show the session's own numbers,
  // times and dates, and the view and plots depend on the frames the keys landed in.
  expectLikeGolden(dir + "/start.png", "app_start.png", 32, 0.002);
  expectLikeGolden(dir + "/case.png", "app_two_passes.png", 64, 0.05);
  expectLikeGolden(dir + "/debrief.png", "app_debrief.png", 64, 0.03);
  expectLikeGolden(dir + "/progress.png", "app_progress.png", 64, 0.01);

  tools::SessionStore store(dir + "/data");
  ASSERT_TRUE(store.open().ok());
  auto sessions = store.list("Ann");
  ASSERT_TRUE(sessions.ok()) << sessions.error();
  ASSERT_EQ(sessions->size(), 1u);
  const tools::SessionRecord& s = sessions->front();
  EXPECT_EQ(s.case_name, "default");
  EXPECT_EQ(s.mode, "hands-on");
  EXPECT_TRUE(s.complete);
  EXPECT_GE(s.passes, 2);
  EXPECT_GT(s.myoma_resected_pct, 0.5);  // (how much depends on the frames the keys land in)
  EXPECT_EQ(s.perforations, 0);
  EXPECT_GT(s.score, 0.0);
  EXPECT_TRUE(fs::exists(s.recording)) << s.recording;
}

TEST_F(AppWindow, PerforatingSceneShowsTheAlarm) {
  const std::string dir = freshOutputDir("AppWindow", "perforation");
  const Output out = runApp(xvfb_.display(), dir,
                            std::string(HYSIM_SOURCE_DIR) + "/scenes/type2_perforation.yaml --trainee Bo " +
                                "--alarm-screenshot alarm.png --input " + dataFile("app/perforation_alarm.txt"));
  ASSERT_EQ(out.exit_code, 0) << out.text;
  std::smatch m;
  const std::regex line("engine event at ([0-9.]+) s, raised at the step of ([0-9.]+) s, drawn ([0-9.]+) ms");
  ASSERT_TRUE(std::regex_search(out.text, m, line)) << out.text;
  const double event_s = std::stod(m[1]), raised_s = std::stod(m[2]);
  EXPECT_GE(raised_s, event_s);
  EXPECT_LE(raised_s - event_s, 0.050);  // simulated time: the alarm's step is the event's
  auto alarm = render::readPng(dir + "/alarm.png");
  ASSERT_TRUE(alarm.ok()) << alarm.error();
  EXPECT_GT(redFraction(*alarm), 0.02);  // the red rim around the view
  EXPECT_NE(out.text.find("perforations 1, alarms 1"), std::string::npos) << out.text;
}

// The debrief's replay plays the session's recording to the very state the session ended in.
TEST_F(AppWindow, ReplayFromTheDebriefEndsOnTheSessionsState) {
  const std::string dir = freshOutputDir("AppWindow", "replay");
  const Output out = runApp(xvfb_.display(), dir,
                            std::string(HYSIM_SOURCE_DIR) + "/scenes/default.yaml --input " + dataFile("app/replay.txt"));
  ASSERT_EQ(out.exit_code, 0) << out.text;
  std::smatch session, replay;
  ASSERT_TRUE(std::regex_search(out.text, session, std::regex("perforations 0, alarms 0, state_hash ([0-9a-f]+)")))
      << out.text;
  ASSERT_TRUE(std::regex_search(out.text, replay, std::regex("replay of .* finished: .* state_hash ([0-9a-f]+)")))
      << out.text;
  EXPECT_EQ(replay[1], session[1]);
}

// A trainee session killed midway keeps its file and row, marked incomplete.
TEST_F(AppWindow, KilledMidSessionLeavesAnIncompleteSession) {
  const std::string dir = freshOutputDir("AppWindow", "killed");
  const std::string cmd = "cd " + dir + " && DISPLAY=" + xvfb_.display() + " HYSIM_DATA_DIR=" + dir + "/data exec " +
                          kApp + " " + HYSIM_SOURCE_DIR + "/scenes/default.yaml --trainee Cy >/dev/null 2>&1";
  const pid_t pid = fork();
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", cmd.c_str(), nullptr);
    _exit(127);
  }
  ASSERT_TRUE(waitForFileEndingIn(dir + "/data/sessions", ".json")) << "no session file";
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // a little into the session
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);

  tools::SessionStore store(dir + "/data");
  ASSERT_TRUE(store.open().ok());
  auto sessions = store.list("Cy");
  ASSERT_TRUE(sessions.ok()) << sessions.error();
  ASSERT_EQ(sessions->size(), 1u);
  EXPECT_FALSE(sessions->front().complete);
  EXPECT_EQ(sessions->front().case_name, "default");
}

// A data folder that cannot be made is said clearly; the case still runs.
TEST_F(AppWindow, UnusableDataFolderIsSaid) {
  const std::string dir = freshOutputDir("AppWindow", "unusable");
  const Output out = runApp(xvfb_.display(), dir,
                            std::string(HYSIM_SOURCE_DIR) + "/scenes/default.yaml --frames 5 --data-dir /dev/null/hysim");
  EXPECT_EQ(out.exit_code, 0) << out.text;
  EXPECT_NE(out.text.find("/dev/null/hysim"), std::string::npos) << out.text;
  EXPECT_NE(out.text.find("5 frames"), std::string::npos) << out.text;
}

}  // namespace
}  // namespace hysim::testing
