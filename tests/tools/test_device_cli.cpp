// `hysim run --device`: a software game controller playing a pad script through the real SDL
// driver, and the UDP bridge driven by the reference peer over loopback; both recorded and
// replayed to the same state_hash.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "read_json.hpp"
#include "run_hysim.hpp"

namespace {

using hysim::testing::Output;
using hysim::testing::runHysim;

using hysim::testing::readJson;

// The default course's first pass (the pad script of scenes/pad/default-course.yaml).
std::string writePadScript(const std::string& dir) {
  const std::string path = dir + "/pass.yaml";
  std::ofstream(path) << "- {t_s: 0.2, right_y: 1.0}\n"
                         "- {t_s: 0.7, right_y: 0.0, right_trigger: 1.0}\n"
                         "- {t_s: 4.1, right_trigger: 0.0}\n"
                         "- {t_s: 4.2, right_shoulder: true, right_y: 1.0}\n"
                         "- {t_s: 4.35, right_y: 0.0, left_trigger: 1.0}\n"
                         "- {t_s: 7.7, left_trigger: 0.0, right_shoulder: false}\n";
  return path;
}

TEST(DeviceCli, AVirtualPadCutsAChipAndItsRecordingReplays) {
  const std::string dir = hysim::testing::freshOutputDir("device_cli", "virtual_pad");
  const std::string script = writePadScript(dir);
  Output o = runHysim("run --device virtual-pad:" + script + " --steps 8000 --quiet --record " + dir +
                      "/pad.hyrec --report " + dir + "/run.json");
  ASSERT_EQ(o.exit_code, 0) << o.text;
  const auto run = readJson(dir + "/run.json");
  EXPECT_EQ(run["device"]["name"], "game controller (SDL)");
  EXPECT_TRUE(run["device"]["connected"].get<bool>());
  EXPECT_EQ(run["passes"].get<int>(), 1);
  EXPECT_GT(run["myoma_resected_mm3"].get<double>(), 10.0);  // the pass cut a chip off the myoma
  o = runHysim("replay " + dir + "/pad.hyrec --quiet --report " + dir + "/replay.json");
  ASSERT_EQ(o.exit_code, 0) << o.text;
  EXPECT_EQ(readJson(dir + "/replay.json")["state_hash"], run["state_hash"]);
}

TEST(DeviceCli, BadDeviceArgumentsAreClearErrors) {
  const std::string dir = hysim::testing::freshOutputDir("device_cli", "bad");
  std::ofstream(dir + "/bad.yaml") << "- {t_s: 0.2, right_y: 1.0}\n- {t_s: 0.1, right_stik: 1.0}\n";
  Output o = runHysim("run --steps 10 --device virtual-pad:" + dir + "/bad.yaml");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.text.find("bad.yaml:2"), std::string::npos) << o.text;
  std::ofstream(dir + "/range.yaml") << "- {t_s: 0.2, left_trigger: -0.5}\n";
  o = runHysim("run --steps 10 --device virtual-pad:" + dir + "/range.yaml");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.text.find("outside [0, 1]"), std::string::npos) << o.text;
  o = runHysim("run --steps 10 --device joystick");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.text.find("expected scripted, gamepad, virtual-pad:FILE or udp:PORT"), std::string::npos) << o.text;
  o = runHysim("run --steps 10 --device udp:99999");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.text.find("1..65535"), std::string::npos) << o.text;
  std::ofstream(dir + "/filters.yaml") << "scale: 0.5\nrotation_deg: [0, 0, 90]\nmax_sped_mm_s: 300\n";
  o = runHysim("run --steps 10 --device udp:39872 --device-filters " + dir + "/filters.yaml");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.text.find("filters.yaml:3: 'max_sped_mm_s': unknown key"), std::string::npos) << o.text;
  std::ofstream(dir + "/filters.yaml") << "scale: 0.5\nscale: 2\n";  // which one? neither
  o = runHysim("run --steps 10 --device udp:39872 --device-filters " + dir + "/filters.yaml");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.text.find("filters.yaml:2: duplicate key 'scale'"), std::string::npos) << o.text;
  std::ofstream(dir + "/dup.yaml") << "- {t_s: 0.2, right_y: 1.0, right_y: 0.5}\n";
  o = runHysim("run --steps 10 --device virtual-pad:" + dir + "/dup.yaml");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.text.find("dup.yaml:1: duplicate key 'right_y'"), std::string::npos) << o.text;
  std::ofstream(dir + "/filters.yaml") << "scale: 0\n";
  o = runHysim("run --steps 10 --device udp:39872 --device-filters " + dir + "/filters.yaml");
  EXPECT_NE(o.text.find("filters.yaml:1: 'scale': 0 is outside"), std::string::npos) << o.text;
  o = runHysim("run --steps 10 --device udp:39871 --device-wait-s 0.2");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.text.find("no state packet"), std::string::npos) << o.text;
}

// The reference peer replays the default scene's script at 1 kHz; hysim runs paced to the
// wall clock on it. What arrives is counted; the recording replays without the network.
TEST(DeviceCli, TheUdpPeerDrivesARunOverLoopback) {
  const std::string dir = hysim::testing::freshOutputDir("device_cli", "udp");
  // A port of this process's own: two test runs side by side do not meet.
  const std::string port = std::to_string(20000 + ::getpid() % 20000);
  const std::string peer = std::string(HYSIM_UDP_PEER) + " --port " + port + " --seconds 4 > " + dir +
                           "/peer.log 2>&1 &";
  const Output o = runHysim("run --device udp:" + port + " --realtime --steps 1500 --quiet --record " + dir +
                                "/udp.hyrec --report " + dir + "/run.json",
                            "(" + peer + ") ;");
  ASSERT_EQ(o.exit_code, 0) << o.text;
  const auto run = readJson(dir + "/run.json");
  const auto& device = run["device"];
  EXPECT_EQ(device["name"], "udp bridge");
  EXPECT_GT(device["packets_received"].get<long>(), 100);
  EXPECT_EQ(device["packets_malformed"].get<long>(), 0);
  const Output r = runHysim("replay " + dir + "/udp.hyrec --quiet --report " + dir + "/replay.json");
  ASSERT_EQ(r.exit_code, 0) << r.text;
  EXPECT_EQ(readJson(dir + "/replay.json")["state_hash"], run["state_hash"]);
}

}  // namespace
