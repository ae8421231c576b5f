// The trainee window's scripted input (the file CI drives the app with) and the frame-rate
// figures a case prints.
#include <gtest/gtest.h>

#include "app_frame_stats.hpp"
#include "app_input_script.hpp"
#include "test_dir.hpp"

namespace hysim::tools {
namespace {

TEST(InputScript, ParsesEachClockInTimeOrder) {
  const auto script = parseInputScript(
      "# pick the case\n"
      "wall 2.0 tap Return\n"
      "wall 1.5 tap Down   # before Return\n"
      "sim 0.5 down Left Shift\n"
      "\n"
      "sim 0.25 text Ann\n"
      "sim 3 capture out/case.png\n"
      "debrief 1.5 tap C\n",
      "s.txt");
  ASSERT_TRUE(script.ok()) << script.error();
  const std::vector<ScriptEvent>& wall = script->timed.at("wall");
  ASSERT_EQ(wall.size(), 2u);
  EXPECT_EQ(wall[0].argument, "Down");
  EXPECT_EQ(wall[0].line, 3);
  EXPECT_EQ(wall[1].action, ScriptEvent::Action::Tap);
  ASSERT_EQ(script->timed.at("debrief").size(), 1u);
  EXPECT_EQ(script->timed.at("debrief")[0].argument, "C");
  ASSERT_EQ(script->sim.size(), 3u);
  EXPECT_EQ(script->sim[0].action, ScriptEvent::Action::Text);
  EXPECT_EQ(script->sim[1].argument, "Left Shift");  // a key name with a space
  EXPECT_EQ(script->sim[1].action, ScriptEvent::Action::Down);
  EXPECT_DOUBLE_EQ(script->sim[2].time_s, 3.0);
  EXPECT_EQ(script->sim[2].argument, "out/case.png");
}

TEST(InputScript, BadLinesNameTheFileAndLine) {
  const std::pair<const char*, const char*> cases[] = {
      {"wall 1 tap W\nclock 1 tap W\n", "s.txt:2: the clock must be wall, sim, start"},
      {"sim nan tap W\n", "s.txt:1: the time must be seconds"},
      {"sim -1 tap W\n", "s.txt:1: the time must be seconds"},
      {"sim 1e400 tap W\n", "s.txt:1: the time must be seconds"},
      {"sim 1x tap W\n", "s.txt:1: the time must be seconds"},
      {"wall 1 press W\n", "s.txt:1: the action must be"},
      {"wall 1 tap\n", "s.txt:1: 'tap' needs an argument"},
      {"wall 1 text 0123456789012345678901234567890123\n", "s.txt:1: text is typed at most 31 bytes"},
  };
  for (const auto& [text, error] : cases) {
    const auto script = parseInputScript(text, "s.txt");
    ASSERT_FALSE(script.ok()) << text;
    EXPECT_EQ(script.error().rfind(error, 0), 0u) << script.error();
  }
}

TEST(InputScript, AFolderOrMissingFileIsAnError) {
  const auto folder = loadInputScript(hysim::testing::testDir("InputScript").string());
  ASSERT_FALSE(folder.ok());
  EXPECT_NE(folder.error().find("not a regular file"), std::string::npos);
  EXPECT_FALSE(loadInputScript("/no/such/script.txt").ok());
}

TEST(FrameStats, RateMedianAndFactor) {
  FrameStats stats;
  for (int i = 0; i < 9; ++i) stats.addFrame(0.020);
  stats.addFrame(0.120);  // one slow frame
  EXPECT_EQ(stats.frames(), 10);
  EXPECT_NEAR(stats.fps(), 10.0 / 0.3, 1e-9);
  EXPECT_NEAR(stats.percentileMs(0.5), 20.0, 1e-9);
  EXPECT_NEAR(stats.percentileMs(1.0), 120.0, 1e-9);
  const std::string line = stats.summary(640, 480, 9.9, 10.0, 0.1);
  EXPECT_NE(line.find("640x480: 10 frames, 33.3 fps"), std::string::npos) << line;
  EXPECT_NE(line.find("real-time factor 0.990"), std::string::npos) << line;
}

}  // namespace
}  // namespace hysim::tools
