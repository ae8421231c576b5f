#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "hysim/haptics/udp_packet.hpp"

namespace hysim::haptics {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

UdpStatePacket awkwardState() {
  UdpStatePacket p;
  p.sequence = 0xFFFFFFFEu;
  p.buttons = kUdpButtonPedal | kUdpButtonLens | (1u << 31);
  p.peer_time_s = 12345.678901234567;
  p.tip_mm = {-0.0, std::numeric_limits<double>::denorm_min(), 1e300};
  p.orientation_wxyz = {0.7071, 0.0001, -0.7071, 0.0};  // |q| ~ 0.99996: within tolerance, not unit
  p.velocity_mm_s = {1.0 / 3.0, -2.5e-9, 7.0};
  p.angular_velocity_rad_s = {std::numeric_limits<double>::max(), -std::numeric_limits<double>::min(), 0.1};
  p.extension_mm = 50.0;
  p.extension_velocity_mm_s = -3.25;
  return p;
}

std::uint64_t bits(double v) { return std::bit_cast<std::uint64_t>(v); }

void expectSameBits(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  for (int i = 0; i < 3; ++i) EXPECT_EQ(bits(a[i]), bits(b[i])) << "component " << i;
}

std::vector<std::uint8_t> bytesOf(const UdpStatePacket& p) {
  const auto a = encodeState(p);
  return {a.begin(), a.end()};
}

void putDouble(std::vector<std::uint8_t>& bytes, std::size_t offset, double v) {
  const std::uint64_t b = bits(v);
  for (int i = 0; i < 8; ++i) bytes[offset + i] = static_cast<std::uint8_t>(b >> (8 * i));
}

UdpPacketError decodeStateBytes(const std::vector<std::uint8_t>& bytes) {
  UdpStatePacket out;
  return decodeState(bytes, out);
}

TEST(UdpPacket, StateRoundTripIsBitExact) {
  const UdpStatePacket in = awkwardState();
  const auto bytes = encodeState(in);
  UdpStatePacket out;
  ASSERT_EQ(decodeState(bytes, out), UdpPacketError::None);
  EXPECT_EQ(out.sequence, in.sequence);
  EXPECT_EQ(out.buttons, in.buttons);
  EXPECT_EQ(bits(out.peer_time_s), bits(in.peer_time_s));
  expectSameBits(out.tip_mm, in.tip_mm);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(bits(out.orientation_wxyz[i]), bits(in.orientation_wxyz[i]));
  expectSameBits(out.velocity_mm_s, in.velocity_mm_s);
  expectSameBits(out.angular_velocity_rad_s, in.angular_velocity_rad_s);
  EXPECT_EQ(bits(out.extension_mm), bits(in.extension_mm));
  EXPECT_EQ(bits(out.extension_velocity_mm_s), bits(in.extension_velocity_mm_s));
  EXPECT_EQ(encodeState(out), bytes);  // and back to the same bytes
}

TEST(UdpPacket, ForceRoundTripIsBitExact) {
  UdpForcePacket in;
  in.sequence = 0x80000001u;
  in.ack_sequence = 0xFFFFFFFFu;
  in.flags = kUdpFlagStale | kUdpFlagDisconnected;
  in.force_n = {-0.0, 1.0 / 7.0, -2.9999999999999996};
  const auto bytes = encodeForce(in);
  UdpForcePacket out;
  ASSERT_EQ(decodeForce(bytes, out), UdpPacketError::None);
  EXPECT_EQ(out.sequence, in.sequence);
  EXPECT_EQ(out.ack_sequence, in.ack_sequence);
  EXPECT_EQ(out.flags, in.flags);
  expectSameBits(out.force_n, in.force_n);
  EXPECT_EQ(encodeForce(out), bytes);
}

// The documented table (haptics/README.md): fields little-endian at these offsets.
TEST(UdpPacket, StateLayoutMatchesTheDocumentedOffsets) {
  UdpStatePacket p;
  p.sequence = 0x04030201u;
  p.buttons = 0x0A0B0C0Du;
  p.peer_time_s = 1.0;          // 0x3FF0000000000000
  p.tip_mm = {2.0, 0, 0};       // 0x4000000000000000
  p.orientation_wxyz = {-1.0, 0, 0, 0};  // 0xBFF0000000000000
  p.velocity_mm_s = {0, 0, 0.5};         // 0x3FE0000000000000
  p.angular_velocity_rad_s = {4.0, 0, 0};  // 0x4010000000000000
  p.extension_mm = 8.0;                    // 0x4020000000000000
  p.extension_velocity_mm_s = 16.0;        // 0x4030000000000000
  const auto b = encodeState(p);
  ASSERT_EQ(b.size(), 144u);
  EXPECT_EQ(std::memcmp(b.data(), "HYSD", 4), 0);
  EXPECT_EQ(b[4], 1); EXPECT_EQ(b[5], 0);  // version
  EXPECT_EQ(b[6], 1); EXPECT_EQ(b[7], 0);  // type: state
  EXPECT_EQ(b[8], 0x01); EXPECT_EQ(b[9], 0x02); EXPECT_EQ(b[10], 0x03); EXPECT_EQ(b[11], 0x04);
  EXPECT_EQ(b[12], 0x0D); EXPECT_EQ(b[15], 0x0A);
  auto high = [&b](std::size_t offset) { return b[offset + 7]; };  // sign and exponent byte
  EXPECT_EQ(high(16), 0x3F); EXPECT_EQ(b[22], 0xF0);  // peer time
  EXPECT_EQ(high(24), 0x40);                          // tip x
  EXPECT_EQ(high(48), 0xBF);                          // quaternion w
  EXPECT_EQ(high(96), 0x3F); EXPECT_EQ(b[102], 0xE0); // velocity z
  EXPECT_EQ(high(104), 0x40); EXPECT_EQ(b[110], 0x10);  // angular velocity x
  EXPECT_EQ(high(128), 0x40); EXPECT_EQ(b[134], 0x20);  // extension
  EXPECT_EQ(high(136), 0x40); EXPECT_EQ(b[142], 0x30);  // extension velocity
}

TEST(UdpPacket, ForceLayoutMatchesTheDocumentedOffsets) {
  UdpForcePacket p;
  p.sequence = 0x04030201u;
  p.ack_sequence = 0x08070605u;
  p.flags = 0x03u;
  p.force_n = {0, 0, -1.0};
  const auto b = encodeForce(p);
  ASSERT_EQ(b.size(), 48u);
  EXPECT_EQ(std::memcmp(b.data(), "HYSF", 4), 0);
  EXPECT_EQ(b[4], 1); EXPECT_EQ(b[5], 0);
  EXPECT_EQ(b[6], 2); EXPECT_EQ(b[7], 0);  // type: force
  EXPECT_EQ(b[8], 0x01); EXPECT_EQ(b[11], 0x04);
  EXPECT_EQ(b[12], 0x05); EXPECT_EQ(b[15], 0x08);
  EXPECT_EQ(b[16], 0x03); EXPECT_EQ(b[19], 0x00);
  for (int i = 20; i < 24; ++i) EXPECT_EQ(b[i], 0) << "reserved byte " << i;
  EXPECT_EQ(b[47], 0xBF); EXPECT_EQ(b[46], 0xF0);  // force z
}

TEST(UdpPacket, WrongSizesAreRejectedIncludingOversized) {
  std::vector<std::uint8_t> bytes = bytesOf(awkwardState());
  EXPECT_EQ(decodeStateBytes({}), UdpPacketError::Size);
  bytes.pop_back();
  EXPECT_EQ(decodeStateBytes(bytes), UdpPacketError::Size);
  bytes.push_back(0);
  bytes.push_back(0);
  EXPECT_EQ(decodeStateBytes(bytes), UdpPacketError::Size);  // one byte too many
  bytes.resize(4096, 0xAB);
  EXPECT_EQ(decodeStateBytes(bytes), UdpPacketError::Size);
  const auto force = encodeForce({});
  EXPECT_EQ(decodeStateBytes({force.begin(), force.end()}), UdpPacketError::Size);
  UdpForcePacket f;
  EXPECT_EQ(decodeForce(std::span<const std::uint8_t>(force.data(), 47), f), UdpPacketError::Size);
  std::vector<std::uint8_t> long_force(force.begin(), force.end());
  long_force.push_back(0);
  EXPECT_EQ(decodeForce(long_force, f), UdpPacketError::Size);
}

TEST(UdpPacket, HeaderFieldsAreRejectedWithTheirReason) {
  const std::vector<std::uint8_t> good = bytesOf(awkwardState());
  auto with = [&good](std::size_t offset, std::uint8_t value) {
    std::vector<std::uint8_t> b = good;
    b[offset] = value;
    return decodeStateBytes(b);
  };
  EXPECT_EQ(with(0, 'h'), UdpPacketError::Magic);
  EXPECT_EQ(with(3, 'F'), UdpPacketError::Magic);  // a force packet's magic
  EXPECT_EQ(with(4, 2), UdpPacketError::Version);
  EXPECT_EQ(with(5, 1), UdpPacketError::Version);  // 0x0101: the high byte counts
  EXPECT_EQ(with(6, 2), UdpPacketError::Type);
  EXPECT_EQ(with(7, 1), UdpPacketError::Type);

  const auto force = encodeForce({});
  std::vector<std::uint8_t> f(force.begin(), force.end());
  UdpForcePacket out;
  f[2] = 'X';
  EXPECT_EQ(decodeForce(f, out), UdpPacketError::Magic);
  f[2] = 'S';
  f[4] = 0;
  EXPECT_EQ(decodeForce(f, out), UdpPacketError::Version);
  f[4] = 1;
  f[6] = 1;
  EXPECT_EQ(decodeForce(f, out), UdpPacketError::Type);
  f[6] = 2;
  f[20] = 0xFF;  // reserved: ignored
  EXPECT_EQ(decodeForce(f, out), UdpPacketError::None);
}

TEST(UdpPacket, EveryNonFiniteNumberIsRejected) {
  const std::vector<std::uint8_t> good = bytesOf(awkwardState());
  for (std::size_t offset = 16; offset < kUdpStatePacketSize; offset += 8) {
    for (double bad : {kNaN, kInf, -kInf}) {
      std::vector<std::uint8_t> b = good;
      putDouble(b, offset, bad);
      EXPECT_EQ(decodeStateBytes(b), UdpPacketError::NonFinite) << "offset " << offset << " value " << bad;
    }
  }
  for (int i = 0; i < 3; ++i) {
    UdpForcePacket p;
    p.force_n[i] = kNaN;
    const auto bytes = encodeForce(p);
    UdpForcePacket out;
    out.sequence = 77;
    EXPECT_EQ(decodeForce(bytes, out), UdpPacketError::NonFinite);
    EXPECT_EQ(out.sequence, 77u);  // a refused packet leaves the output alone
  }
}

TEST(UdpPacket, QuaternionMustBeUnitWithinTolerance) {
  UdpStatePacket p = awkwardState();
  auto reason = [&p](double w, double x, double y, double z) {
    p.orientation_wxyz = {w, x, y, z};
    return decodeStateBytes(bytesOf(p));
  };
  EXPECT_EQ(reason(1, 0, 0, 0), UdpPacketError::None);
  EXPECT_EQ(reason(1.0009, 0, 0, 0), UdpPacketError::None);
  EXPECT_EQ(reason(0.9991, 0, 0, 0), UdpPacketError::None);
  EXPECT_EQ(reason(1.0011, 0, 0, 0), UdpPacketError::Quaternion);
  EXPECT_EQ(reason(0.9989, 0, 0, 0), UdpPacketError::Quaternion);
  EXPECT_EQ(reason(0, 0, 0, 0), UdpPacketError::Quaternion);
  EXPECT_EQ(reason(1, 1, 0, 0), UdpPacketError::Quaternion);
  EXPECT_EQ(reason(1e300, 1e300, 0, 0), UdpPacketError::Quaternion);  // the norm overflows to inf
}

TEST(UdpPacket, ExtensionMustLieInItsRange) {
  UdpStatePacket p = awkwardState();
  auto reason = [&p](double extension) {
    p.extension_mm = extension;
    return decodeStateBytes(bytesOf(p));
  };
  EXPECT_EQ(reason(0.0), UdpPacketError::None);
  EXPECT_EQ(reason(-0.0), UdpPacketError::None);
  EXPECT_EQ(reason(50.0), UdpPacketError::None);
  EXPECT_EQ(reason(-1e-9), UdpPacketError::Extension);
  EXPECT_EQ(reason(50.000001), UdpPacketError::Extension);
  EXPECT_EQ(reason(1e9), UdpPacketError::Extension);
}

TEST(UdpPacket, ReasonsHaveDistinctDescriptions) {
  std::vector<std::string> seen;
  for (int i = 0; i < kUdpPacketErrorCount; ++i) {
    const std::string text = describe(static_cast<UdpPacketError>(i));
    EXPECT_FALSE(text.empty());
    for (const std::string& other : seen) EXPECT_NE(text, other);
    seen.push_back(text);
  }
}

TEST(UdpPacket, DeviceStateNormalisesTheQuaternionIntoToolPoseColumns) {
  UdpStatePacket p;
  const double s = std::sqrt(0.5) * 1.0008;  // a quarter turn about world y, |q| = 1.0008
  p.orientation_wxyz = {s, 0, s, 0};
  p.buttons = kUdpButtonPedal | kUdpButtonLens;
  p.tip_mm = {1, 2, 3};
  p.extension_mm = 4;
  p.velocity_mm_s = {5, 6, 7};
  const DeviceState state = deviceStateFromPacket(p);
  const Eigen::Matrix3d& r = state.pose.rotation;
  EXPECT_LT((r.transpose() * r - Eigen::Matrix3d::Identity()).norm(), 1e-14);
  EXPECT_LT((r.col(2) - Eigen::Vector3d(1, 0, 0)).norm(), 1e-14);  // shaft axis: body z to world x
  EXPECT_LT((r.col(1) - Eigen::Vector3d(0, 1, 0)).norm(), 1e-14);  // up stays up
  EXPECT_TRUE(state.pose.pedal);
  EXPECT_EQ(state.buttons, 3u);
  EXPECT_EQ(state.pose.tip, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(state.pose.extension_mm, 4.0);
  EXPECT_EQ(state.velocity_mm_s, Eigen::Vector3d(5, 6, 7));
  p.buttons = kUdpButtonLens;
  EXPECT_FALSE(deviceStateFromPacket(p).pose.pedal);
}

TEST(UdpPacket, PeerPacketFromADeviceStateKeepsThePose) {
  DeviceState s;
  s.pose.tip = {10, -20, 30};
  s.pose.rotation = frameFromAxisUp(Eigen::Vector3d(1, 2, -3).normalized(), Eigen::Vector3d(0, 1, 0));
  s.pose.extension_mm = 12.5;
  s.pose.pedal = true;
  s.angular_velocity_rad_s = {0.1, 0.2, 0.3};
  const UdpStatePacket p = statePacketFromDevice(s, 42, 1.5);
  EXPECT_EQ(p.sequence, 42u);
  EXPECT_EQ(p.buttons & kUdpButtonPedal, kUdpButtonPedal);
  UdpStatePacket decoded;
  ASSERT_EQ(decodeState(encodeState(p), decoded), UdpPacketError::None);
  const DeviceState back = deviceStateFromPacket(decoded);
  EXPECT_LT((back.pose.rotation - s.pose.rotation).norm(), 1e-14);
  EXPECT_EQ(back.pose.tip, s.pose.tip);
  EXPECT_EQ(back.angular_velocity_rad_s, s.angular_velocity_rad_s);
  EXPECT_TRUE(back.pose.pedal);
}

// What an accepted state packet must satisfy, checked independently of the decoder.
void expectWellFormed(const std::vector<std::uint8_t>& bytes, const UdpStatePacket& p) {
  ASSERT_EQ(bytes.size(), kUdpStatePacketSize);
  EXPECT_EQ(std::memcmp(bytes.data(), "HYSD\x01\x00\x01\x00", 8), 0);
  EXPECT_TRUE(p.tip_mm.allFinite() && p.velocity_mm_s.allFinite() && p.angular_velocity_rad_s.allFinite());
  EXPECT_TRUE(std::isfinite(p.peer_time_s) && std::isfinite(p.extension_velocity_mm_s));
  const auto& q = p.orientation_wxyz;
  EXPECT_NEAR(std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]), 1.0, kUdpQuaternionNormTolerance);
  EXPECT_GE(p.extension_mm, 0.0);
  EXPECT_LE(p.extension_mm, kUdpMaxExtensionMm);
  const auto again = encodeState(p);
  EXPECT_TRUE(std::equal(again.begin(), again.end(), bytes.begin()));  // nothing was misread
  const DeviceState state = deviceStateFromPacket(p);
  EXPECT_TRUE(state.pose.rotation.allFinite());
}

// The header's reason from the bytes alone, to check the decoder's reason on mutated packets.
UdpPacketError expectedHeaderReason(const std::vector<std::uint8_t>& b) {
  if (b.size() != kUdpStatePacketSize) return UdpPacketError::Size;
  if (std::memcmp(b.data(), "HYSD", 4) != 0) return UdpPacketError::Magic;
  if (b[4] != 1 || b[5] != 0) return UdpPacketError::Version;
  if (b[6] != 1 || b[7] != 0) return UdpPacketError::Type;
  return UdpPacketError::None;
}

// Decodes one fuzzed datagram and checks the verdict; true when it was accepted.
bool checkFuzzedState(const std::vector<std::uint8_t>& b) {
  UdpStatePacket p;
  const UdpPacketError reason = decodeState(b, p);
  const UdpPacketError header = expectedHeaderReason(b);
  if (header != UdpPacketError::None) {
    EXPECT_EQ(reason, header);
  }
  if (reason != UdpPacketError::None) return false;
  expectWellFormed(b, p);
  return true;
}

// Random datagrams and mutated valid ones (fixed seed): the decoder never crashes, refuses
// with the header's reason where the header is wrong, and whatever it accepts is well formed.
TEST(UdpPacket, FuzzedStatePacketsNeverCrashAndNeverAcceptGarbage) {
  std::mt19937_64 rng(0x48595344u);
  std::uniform_int_distribution<int> byte(0, 255);
  long accepted = 0, refused = 0;
  for (int i = 0; i < 2000; ++i) {  // random bytes of random length
    std::vector<std::uint8_t> b(std::uniform_int_distribution<std::size_t>(0, 400)(rng));
    for (auto& v : b) v = static_cast<std::uint8_t>(byte(rng));
    if (i % 4 == 0 && b.size() >= 8) std::memcpy(b.data(), "HYSD\x01\x00\x01\x00", 8);  // past the header
    if (i % 8 == 0) b.resize(kUdpStatePacketSize);
    ++(checkFuzzedState(b) ? accepted : refused);
  }
  EXPECT_EQ(accepted, 0);  // random payloads are never plausible (quaternion, extension)
  EXPECT_EQ(refused, 2000);

  const std::vector<std::uint8_t> good = bytesOf(awkwardState());
  accepted = refused = 0;
  for (int i = 0; i < 5000; ++i) {  // valid packets with a few bytes changed, cut or appended
    std::vector<std::uint8_t> b = good;
    const int flips = std::uniform_int_distribution<int>(1, 4)(rng);
    for (int k = 0; k < flips; ++k) b[std::uniform_int_distribution<std::size_t>(0, b.size() - 1)(rng)] ^=
        static_cast<std::uint8_t>(1 + byte(rng) % 255);
    if (i % 50 == 0) b.resize(std::uniform_int_distribution<std::size_t>(0, 300)(rng), 0);
    ++(checkFuzzedState(b) ? accepted : refused);
  }
  EXPECT_GT(accepted, 100);  // changes to sequence, buttons or low mantissa bits are plausible
  EXPECT_GT(refused, 100);
}

TEST(UdpPacket, FuzzedForcePacketsNeverCrashAndNeverAcceptGarbage) {
  std::mt19937_64 rng(0x48595346u);
  std::uniform_int_distribution<int> byte(0, 255);
  UdpForcePacket good;
  good.force_n = {0.5, -1.0, 2.0};
  const auto encoded = encodeForce(good);
  long accepted = 0;
  for (int i = 0; i < 3000; ++i) {
    std::vector<std::uint8_t> b(encoded.begin(), encoded.end());
    if (i % 3 == 0) {
      b.resize(std::uniform_int_distribution<std::size_t>(0, 100)(rng));
      for (auto& v : b) v = static_cast<std::uint8_t>(byte(rng));
    } else {
      b[std::uniform_int_distribution<std::size_t>(0, b.size() - 1)(rng)] ^= static_cast<std::uint8_t>(1 + byte(rng) % 255);
    }
    UdpForcePacket p;
    if (decodeForce(b, p) != UdpPacketError::None) continue;
    ++accepted;
    ASSERT_EQ(b.size(), kUdpForcePacketSize);
    EXPECT_EQ(std::memcmp(b.data(), "HYSF\x01\x00\x02\x00", 8), 0);
    EXPECT_TRUE(p.force_n.allFinite());
  }
  EXPECT_GT(accepted, 100);
}

}  // namespace
}  // namespace hysim::haptics
