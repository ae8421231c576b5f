#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <vector>

#include "hysim/haptics/little_endian.hpp"
#include "hysim/haptics/recording.hpp"
#include "hysim/haptics/replay_device.hpp"
#include "test_dir.hpp"

namespace hysim::haptics {
namespace {

namespace fs = std::filesystem;

RecordingHeader sampleHeader() {
  RecordingHeader h;
  h.scene_hash = 0x0123456789abcdefull;
  h.dt_s = 1e-3;
  h.scene_path = "/scenes/default.yaml";
  h.chips_mode = "simulate";
  h.hysim_version = "0.1 (test)";
  h.device_name = "test pad";
  return h;
}

// Random but plausible states: any doubles for positions and velocities, a proper rotation.
std::vector<DeviceState> sampleStates(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-100.0, 100.0);
  std::vector<DeviceState> states(n);
  for (int i = 0; i < n; ++i) {
    DeviceState& s = states[i];
    s.time_s = 1e-3 * i;
    s.pose.tip = {u(rng), u(rng), u(rng)};
    s.pose.rotation = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
    s.pose.extension_mm = std::abs(u(rng)) / 10.0;
    s.pose.pedal = i % 3 == 0;
    s.velocity_mm_s = {u(rng), u(rng), u(rng)};
    s.angular_velocity_rad_s = {u(rng), u(rng), u(rng)};
    s.extension_velocity_mm_s = u(rng);
    s.buttons = static_cast<std::uint32_t>(i % 4);
  }
  return states;
}

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

template <class M>
bool sameBits(const M& a, const M& b) {
  return std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<size_t>(a.size())) == 0;
}

std::string writeSample(const fs::path& dir, int n, const std::string& name = "rec.hyrec") {
  const std::string path = (dir / name).string();
  RecordingWriter w;
  std::string error;
  EXPECT_TRUE(w.open(path, sampleHeader(), error)) << error;
  const auto states = sampleStates(n, 7);
  for (int i = 0; i < n; ++i) w.append(states[i], i == 0);
  EXPECT_TRUE(w.finish(error)) << error;
  return path;
}

std::vector<unsigned char> bytesOf(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<unsigned char>(std::istreambuf_iterator<char>(in), {});
}

void writeBytes(const std::string& path, const std::vector<unsigned char>& b) {
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), static_cast<long>(b.size()));
}

// Byte offset of record i in the sample file (the header's strings have known lengths).
std::size_t recordAt(int i) {
  const RecordingHeader h = sampleHeader();
  const std::size_t header = 32 + 5 * 4 + h.scene_path.size() + h.mesh_path.size() + h.chips_mode.size() +
                             h.hysim_version.size() + h.device_name.size();
  return header + static_cast<std::size_t>(i) * kRecordBytes;
}

TEST(Recording, RoundTripIsBitExact) {
  const fs::path dir = testing::testDir("Recording");
  const std::string path = writeSample(dir, 500);
  Recording rec;
  std::string error;
  ASSERT_TRUE(readRecording(path, rec, error)) << error;
  const RecordingHeader h = sampleHeader();
  EXPECT_EQ(rec.header.scene_hash, h.scene_hash);
  EXPECT_TRUE(sameBits(rec.header.dt_s, h.dt_s));
  EXPECT_EQ(rec.header.scene_path, h.scene_path);
  EXPECT_EQ(rec.header.mesh_path, "");
  EXPECT_EQ(rec.header.chips_mode, "simulate");
  EXPECT_EQ(rec.header.hysim_version, h.hysim_version);
  EXPECT_EQ(rec.header.device_name, h.device_name);
  const auto states = sampleStates(500, 7);
  ASSERT_EQ(rec.states.size(), 500u);
  for (int i = 0; i < 500; ++i) {
    const DeviceState& a = states[i];
    const DeviceState& b = rec.states[i].state;
    EXPECT_EQ(rec.states[i].attached, i == 0);
    EXPECT_TRUE(sameBits(a.time_s, b.time_s) && sameBits(a.pose.tip, b.pose.tip) &&
                sameBits(a.pose.rotation, b.pose.rotation) && sameBits(a.pose.extension_mm, b.pose.extension_mm) &&
                sameBits(a.velocity_mm_s, b.velocity_mm_s) &&
                sameBits(a.angular_velocity_rad_s, b.angular_velocity_rad_s) &&
                sameBits(a.extension_velocity_mm_s, b.extension_velocity_mm_s))
        << "record " << i;
    EXPECT_EQ(a.pose.pedal, b.pose.pedal);
    EXPECT_EQ(a.buttons, b.buttons);
  }
  EXPECT_EQ(fs::file_size(path), recordAt(500) + kRecordingEndBytes);
}

TEST(Recording, ParsingBytesInMemoryMatchesReadingTheFile) {
  const std::string path = writeSample(testing::testDir("Recording"), 5);
  Recording read, parsed;
  std::string error;
  ASSERT_TRUE(readRecording(path, read, error)) << error;
  ASSERT_TRUE(parseRecording(bytesOf(path), "memory.hyrec", parsed, error)) << error;
  ASSERT_EQ(parsed.states.size(), read.states.size());
  EXPECT_EQ(parsed.header.scene_path, read.header.scene_path);
  for (std::size_t i = 0; i < read.states.size(); ++i) {
    EXPECT_TRUE(sameBits(parsed.states[i].state.pose.tip, read.states[i].state.pose.tip));
  }
  EXPECT_FALSE(parseRecording({}, "memory.hyrec", parsed, error));
  EXPECT_EQ(error.rfind("memory.hyrec: byte 0: ", 0), 0u) << error;
}

TEST(Recording, AnOlderFileIsReplacedOnlyWhenTheNewOneIsFinished) {
  const fs::path dir = testing::testDir("Recording");
  const std::string path = writeSample(dir, 10);
  const auto before = bytesOf(path);
  {
    RecordingWriter w;
    std::string error;
    ASSERT_TRUE(w.open(path, sampleHeader(), error)) << error;
    for (const DeviceState& s : sampleStates(20, 9)) w.append(s, false);
    EXPECT_TRUE(fs::exists(path + ".tmp"));
    EXPECT_EQ(bytesOf(path), before);  // the session dies here: the old one is intact
  }
  Recording rec;
  std::string error;
  EXPECT_TRUE(readRecording(path, rec, error)) << error;
  EXPECT_EQ(rec.states.size(), 10u);
  EXPECT_FALSE(readRecording(path + ".tmp", rec, error));  // no end marker
  EXPECT_NE(error.find("truncated"), std::string::npos) << error;
}

TEST(Recording, AStateNoReplayCouldTakeFailsTheRecordingNamingIt) {
  const fs::path dir = testing::testDir("Recording");
  const std::string path = (dir / "bad.hyrec").string();
  RecordingWriter w;
  std::string error;
  ASSERT_TRUE(w.open(path, sampleHeader(), error)) << error;
  EXPECT_FALSE(w.open(path, sampleHeader(), error));  // still open
  auto states = sampleStates(5, 3);
  states[3].velocity_mm_s.x() = std::numeric_limits<double>::infinity();
  for (const DeviceState& s : states) w.append(s, false);
  EXPECT_FALSE(w.finish(error));
  EXPECT_NE(error.find("record 3: a number is not finite"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(path));
  EXPECT_TRUE(fs::exists(path + ".tmp"));  // kept for a look, never taken as a session
}

TEST(Recording, DiscardRemovesTheTemporaryFile) {
  const fs::path dir = testing::testDir("Recording");
  const std::string path = (dir / "gone.hyrec").string();
  RecordingWriter w;
  std::string error;
  ASSERT_TRUE(w.open(path, sampleHeader(), error)) << error;
  w.append(sampleStates(1, 1)[0], true);
  w.discard();
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  EXPECT_FALSE(fs::exists(path));
}

TEST(Recording, AnUnwritableFolderIsAClearError) {
  RecordingWriter w;
  std::string error;
  EXPECT_FALSE(w.open("/nonexistent-folder/x.hyrec", sampleHeader(), error));
  EXPECT_NE(error.find("/nonexistent-folder/x.hyrec.tmp"), std::string::npos) << error;
}

// One broken recording: how to break it and what the error must say.
struct Damage {
  const char* name;
  std::function<void(std::vector<unsigned char>&)> apply;
  const char* message;  // part of the error
  long offset;          // the byte the error names; -1: not checked
};

// Rewrites a double in record i and fixes its check, so only the plausibility test can fail.
void setRecordDouble(std::vector<unsigned char>& b, int i, int offset, double v) {
  unsigned char* r = b.data() + recordAt(i);
  le::putF64(r + offset, v);
  le::putU32(r + 176, le::fnv1a32(r, 176));
}

std::vector<Damage> damages() {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  return {
      {"empty", [](auto& b) { b.clear(); }, "truncated in the header", 0},
      {"bad magic", [](auto& b) { b[0] = 'X'; }, "not a hysim recording", 0},
      {"version 2", [](auto& b) { le::putU32(b.data() + 8, 2); }, "format version 2", 8},
      {"record size", [](auto& b) { le::putU32(b.data() + 12, 64); }, "record size 64", 12},
      {"dt zero", [](auto& b) { le::putF64(b.data() + 24, 0.0); }, "step dt", 24},
      {"dt nan", [nan](auto& b) { le::putF64(b.data() + 24, nan); }, "step dt", 24},
      {"huge string", [](auto& b) { le::putU32(b.data() + 32, 1u << 30); }, "at most 4096", 32},
      {"header cut in a string", [](auto& b) { b.resize(40); }, "truncated in the scene path", 36},
      {"flipped bit", [](auto& b) { b[recordAt(3) + 10] ^= 0x04; }, "record 3: damaged", static_cast<long>(recordAt(3))},
      {"nan tip", [nan](auto& b) { setRecordDouble(b, 4, 8, nan); }, "record 4: a number is not finite",
       static_cast<long>(recordAt(4))},
      {"not a rotation", [](auto& b) { setRecordDouble(b, 5, 32, 2.0); }, "not a rotation",
       static_cast<long>(recordAt(5))},
      {"extension", [](auto& b) { setRecordDouble(b, 6, 104, 250.0); }, "outside [0, 100]",
       static_cast<long>(recordAt(6))},
      {"negative extension", [](auto& b) { setRecordDouble(b, 6, 104, -1.0); }, "outside [0, 100]",
       static_cast<long>(recordAt(6))},
      {"time backwards", [](auto& b) { setRecordDouble(b, 7, 0, -5.0); }, "time goes backwards",
       static_cast<long>(recordAt(7))},
      {"pedal byte", [](auto& b) {
         unsigned char* r = b.data() + recordAt(2);
         r[172] = 2;
         le::putU32(r + 176, le::fnv1a32(r, 176));
       }, "never writes", static_cast<long>(recordAt(2))},
      {"reserved bytes", [](auto& b) {
         unsigned char* r = b.data() + recordAt(2);
         r[175] = 1;
         le::putU32(r + 176, le::fnv1a32(r, 176));
       }, "never writes", static_cast<long>(recordAt(2))},
      {"cut mid-record", [](auto& b) { b.resize(recordAt(8) + 50); }, "no end marker after 8 whole records",
       static_cast<long>(recordAt(8))},
      {"cut at a record", [](auto& b) { b.resize(recordAt(9)); }, "no end marker after 9 whole records",
       static_cast<long>(recordAt(9))},
      {"count wrong", [](auto& b) { le::putU64(b.data() + b.size() - 16, 11); }, "counts 11 records", -1},
      {"checksum wrong", [](auto& b) { b[b.size() - 1] ^= 1; }, "checksum", -1},
      {"trailing bytes", [](auto& b) { b.push_back(0); }, "no end marker", -1},
      {"record moved", [](auto& b) { std::swap_ranges(b.begin() + static_cast<long>(recordAt(1)),
                                                        b.begin() + static_cast<long>(recordAt(2)),
                                                        b.begin() + static_cast<long>(recordAt(2))); },
       "time goes backwards", static_cast<long>(recordAt(2))},
  };
}

TEST(Recording, BrokenRecordingsAreErrorsNamingTheByte) {
  const fs::path dir = testing::testDir("Recording");
  const std::string good = writeSample(dir, 12);
  const auto bytes = bytesOf(good);
  int tried = 0;
  for (const Damage& d : damages()) {
    auto broken = bytes;
    d.apply(broken);
    const std::string path = (dir / "broken.hyrec").string();
    writeBytes(path, broken);
    Recording rec;
    std::string error;
    EXPECT_FALSE(readRecording(path, rec, error)) << d.name;
    EXPECT_NE(error.find(d.message), std::string::npos) << d.name << ": " << error;
    EXPECT_EQ(error.rfind(path + ": byte ", 0), 0u) << d.name << ": " << error;
    if (d.offset >= 0) {
      EXPECT_NE(error.find("byte " + std::to_string(d.offset) + ":"), std::string::npos) << d.name << ": " << error;
    }
    ++tried;
  }
  EXPECT_GE(tried, 20);
}

TEST(Recording, NotARegularFileIsRefusedBeforeReading) {
  Recording rec;
  std::string error;
  EXPECT_FALSE(readRecording("/dev/zero", rec, error));
  EXPECT_NE(error.find("not a regular file"), std::string::npos) << error;
  EXPECT_FALSE(readRecording(testing::testDir("Recording").string(), rec, error));
  EXPECT_FALSE(readRecording("/nonexistent.hyrec", rec, error));
  // Read whole into memory, so refused unread past 4 GiB (a sparse file: no disk used).
  const std::string huge = (testing::testDir("Recording") / "huge.hyrec").string();
  std::ofstream(huge).put('x');
  std::filesystem::resize_file(huge, (std::uintmax_t{4} << 30) + 1);
  EXPECT_FALSE(readRecording(huge, rec, error));
  EXPECT_EQ(error, "cannot read '" + huge + "': 4294967297 bytes, more than the 4 GiB limit for a recording file");
  std::filesystem::remove(huge);
}

TEST(ReplayDevice, GivesTheRecordedStatesInOrderThenHoldsTheLast) {
  auto rec = std::make_shared<Recording>();
  for (const DeviceState& s : sampleStates(3, 1)) rec->states.push_back({s, false});
  rec->states[0].attached = true;
  rec->states[2].attached = true;
  auto source = std::make_shared<ReplaySource>(rec);
  EXPECT_TRUE(source->nextIsAttach());
  ReplayDevice device(source);
  EXPECT_EQ(device.read(123.0).pose.tip, rec->states[0].state.pose.tip);  // the time asked for does not matter
  EXPECT_FALSE(source->nextIsAttach());
  EXPECT_EQ(device.read(0.0).pose.tip, rec->states[1].state.pose.tip);
  EXPECT_TRUE(source->nextIsAttach());
  ReplayDevice second(source);  // a recorded device change: the next device goes on
  EXPECT_EQ(second.read(0.0).pose.tip, rec->states[2].state.pose.tip);
  EXPECT_EQ(source->readsPastEnd(), 0);
  EXPECT_EQ(second.read(0.0).pose.tip, rec->states[2].state.pose.tip);
  EXPECT_EQ(source->readsPastEnd(), 1);
  second.commandForce({0, 0, 100});
  EXPECT_NEAR(second.lastForce().norm(), second.info().max_force_n, 1e-12);
}

}  // namespace
}  // namespace hysim::haptics
