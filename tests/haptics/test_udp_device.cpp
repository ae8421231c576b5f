#include <gtest/gtest.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <thread>
#include <vector>

#include "haptics_test_util.hpp"
#include "hysim/haptics/haptic_loop.hpp"
#include "hysim/haptics/udp_device.hpp"

namespace hysim::haptics {
namespace {

using test::kMs;

// The scripted peer: a UDP socket on loopback that sends datagrams to the device's port and
// receives its force packets.
class Peer {
 public:
  explicit Peer(std::uint16_t device_port) {
    fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_in self{};
    self.sin_family = AF_INET;
    self.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::bind(fd_, reinterpret_cast<const sockaddr*>(&self), sizeof(self));
    device_.sin_family = AF_INET;
    device_.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    device_.sin_port = htons(device_port);
  }
  ~Peer() { ::close(fd_); }
  Peer(const Peer&) = delete;
  Peer& operator=(const Peer&) = delete;

  void sendBytes(const std::vector<std::uint8_t>& bytes) {
    ASSERT_EQ(::sendto(fd_, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&device_), sizeof(device_)),
              static_cast<ssize_t>(bytes.size()));
  }
  void send(const UdpStatePacket& packet) {
    const auto bytes = encodeState(packet);
    sendBytes({bytes.begin(), bytes.end()});
  }
  // The next force packet, waiting up to 5 s; false when none came or it did not decode.
  bool receiveForce(UdpForcePacket& out) {
    pollfd waiting{fd_, POLLIN, 0};
    if (::poll(&waiting, 1, 5000) <= 0) return false;
    std::uint8_t buffer[256];
    const ssize_t n = ::recv(fd_, buffer, sizeof(buffer), 0);
    return n > 0 && decodeForce(std::span<const std::uint8_t>(buffer, static_cast<std::size_t>(n)), out) ==
                        UdpPacketError::None;
  }
  bool nothingPending() {
    pollfd waiting{fd_, POLLIN, 0};
    return ::poll(&waiting, 1, 0) == 0;
  }

 private:
  int fd_ = -1;
  sockaddr_in device_{};
};

UdpStatePacket state(std::uint32_t sequence, double tip_x = 0.0) {
  UdpStatePacket p;
  p.sequence = sequence;
  p.tip_mm = {tip_x, 2.0, 3.0};
  return p;
}

// Waits (polling, up to 5 s) until the receiver thread has classified `n` datagrams in all.
bool waitForDatagrams(const NetworkDevice& device, long n) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (std::chrono::steady_clock::now() < deadline) {
    const DeviceCounters c = device.counters();
    if (c.packets_received + c.packets_late + c.packets_malformed >= n) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return false;
}

std::unique_ptr<NetworkDevice> openOn(Clock& clock) {
  std::string error;
  auto device = NetworkDevice::open(NetworkDeviceOptions{}, clock, &error);
  EXPECT_NE(device, nullptr) << error;
  return device;
}

TEST(NetworkDevice, BindsAnEphemeralPortAndRefusesBadOptions) {
  FakeClock clock;
  auto device = openOn(clock);
  ASSERT_NE(device, nullptr);
  EXPECT_NE(device->port(), 0);
  EXPECT_EQ(device->info().name, "udp bridge");

  std::string error;
  NetworkDeviceOptions taken;
  taken.port = device->port();
  EXPECT_EQ(NetworkDevice::open(taken, clock, &error), nullptr);
  EXPECT_NE(error.find("cannot bind"), std::string::npos) << error;

  NetworkDeviceOptions bad_address;
  bad_address.bind_address = "localhost:9";
  EXPECT_EQ(NetworkDevice::open(bad_address, clock, &error), nullptr);
  EXPECT_NE(error.find("IPv4"), std::string::npos) << error;

  NetworkDeviceOptions bad_timeout;
  bad_timeout.stale_timeout_s = 0.0;
  EXPECT_EQ(NetworkDevice::open(bad_timeout, clock, &error), nullptr);
  EXPECT_NE(error.find("stale timeout"), std::string::npos) << error;
}

TEST(NetworkDevice, BeforeTheFirstStateItIsDisconnectedAndSendsNothing) {
  FakeClock clock;
  auto device = openOn(clock);
  ASSERT_NE(device, nullptr);
  Peer peer(device->port());
  EXPECT_FALSE(device->connected());
  const DeviceState s = device->read(1.0);
  EXPECT_EQ(s.time_s, 1.0);
  EXPECT_EQ(s.pose.tip, Eigen::Vector3d::Zero());
  EXPECT_FALSE(s.pose.pedal);
  device->commandForce({1, 0, 0});
  EXPECT_EQ(device->lastForce(), Eigen::Vector3d::Zero());
  EXPECT_EQ(device->extraCounters().forces_sent, 0);
  EXPECT_EQ(device->counters().disconnects, 0);  // never connected: nothing went away
}

TEST(NetworkDevice, StatesArriveAndReadReturnsTheNewest) {
  FakeClock clock;
  auto device = openOn(clock);
  ASSERT_NE(device, nullptr);
  Peer peer(device->port());
  for (std::uint32_t i = 1; i <= 3; ++i) {
    UdpStatePacket p = state(i, 10.0 * i);
    p.buttons = kUdpButtonPedal | kUdpButtonLens;
    p.velocity_mm_s = {0, 0, 4};
    p.angular_velocity_rad_s = {0, 0.5, 0};
    p.extension_mm = 7;
    p.extension_velocity_mm_s = -1;
    peer.send(p);
  }
  ASSERT_TRUE(waitForDatagrams(*device, 3));
  EXPECT_TRUE(device->connected());
  const DeviceState s = device->read(7.5);
  EXPECT_EQ(s.time_s, 7.5);
  EXPECT_EQ(s.pose.tip, Eigen::Vector3d(30, 2, 3));
  EXPECT_EQ(s.pose.rotation, Eigen::Matrix3d::Identity());
  EXPECT_EQ(s.pose.extension_mm, 7.0);
  EXPECT_TRUE(s.pose.pedal);
  EXPECT_EQ(s.buttons, 3u);
  EXPECT_EQ(s.velocity_mm_s, Eigen::Vector3d(0, 0, 4));
  EXPECT_EQ(s.angular_velocity_rad_s, Eigen::Vector3d(0, 0.5, 0));
  EXPECT_EQ(s.extension_velocity_mm_s, -1.0);
  const DeviceCounters c = device->counters();
  EXPECT_EQ(c.packets_received, 3);
  EXPECT_EQ(c.packets_lost, 0);
  EXPECT_EQ(c.packets_late, 0);
  EXPECT_EQ(c.packets_malformed, 0);
}

TEST(NetworkDevice, CountsLostLateDuplicatedAndReorderedExactly) {
  FakeClock clock;
  auto device = openOn(clock);
  ASSERT_NE(device, nullptr);
  Peer peer(device->port());
  // 10, 11 in order; 12 and 13 lost in flight ... 14; then 12 arrives late (reordered), 14
  // again (duplicated), then 15; finally 13 very late.
  for (std::uint32_t seq : {10u, 11u, 14u, 12u, 14u, 15u, 13u}) peer.send(state(seq, seq));
  ASSERT_TRUE(waitForDatagrams(*device, 7));
  const DeviceCounters c = device->counters();
  EXPECT_EQ(c.packets_received, 4);  // 10, 11, 14, 15
  EXPECT_EQ(c.packets_lost, 2);      // 12 and 13 were skipped when 14 came
  EXPECT_EQ(c.packets_late, 3);      // 12, 14 again, 13
  EXPECT_EQ(device->read(0.0).pose.tip.x(), 15.0);  // the newest, never a late one
}

TEST(NetworkDevice, TheSequenceWrapsWithoutLossOrLateness) {
  FakeClock clock;
  auto device = openOn(clock);
  ASSERT_NE(device, nullptr);
  Peer peer(device->port());
  for (std::uint32_t seq : {0xFFFFFFFEu, 0xFFFFFFFFu, 0u, 2u}) peer.send(state(seq));
  peer.send(state(0xFFFFFFFFu));  // from before the wrap: late
  ASSERT_TRUE(waitForDatagrams(*device, 5));
  const DeviceCounters c = device->counters();
  EXPECT_EQ(c.packets_received, 4);
  EXPECT_EQ(c.packets_lost, 1);  // 1
  EXPECT_EQ(c.packets_late, 1);
}

TEST(NetworkDevice, MalformedAndOversizedDatagramsAreCountedByReasonAndDropped) {
  FakeClock clock;
  auto device = openOn(clock);
  ASSERT_NE(device, nullptr);
  Peer peer(device->port());
  peer.send(state(1, 1.0));
  const auto good = encodeState(state(2, 99.0));
  std::vector<std::uint8_t> oversized(good.begin(), good.end());
  oversized.push_back(0);
  std::vector<std::uint8_t> huge(good.begin(), good.end());
  huge.resize(5000, 0);  // bigger than the receive buffer: still seen as oversized
  std::vector<std::uint8_t> bad_version(good.begin(), good.end());
  bad_version[4] = 9;
  UdpStatePacket bad_quaternion = state(2, 99.0);
  bad_quaternion.orientation_wxyz = {0.5, 0, 0, 0};
  UdpStatePacket nan_tip = state(2, std::numeric_limits<double>::quiet_NaN());
  UdpStatePacket long_loop = state(2, 99.0);
  long_loop.extension_mm = 51.0;
  peer.sendBytes({'H', 'Y'});
  peer.sendBytes(oversized);
  peer.sendBytes(huge);
  peer.sendBytes(bad_version);
  peer.send(bad_quaternion);
  peer.send(nan_tip);
  peer.send(long_loop);
  peer.sendBytes({});  // an empty datagram
  peer.send(state(2, 2.0));
  ASSERT_TRUE(waitForDatagrams(*device, 10));
  const DeviceCounters c = device->counters();
  EXPECT_EQ(c.packets_received, 2);
  EXPECT_EQ(c.packets_malformed, 8);
  EXPECT_EQ(c.packets_lost, 0);  // refused datagrams do not advance the sequence
  EXPECT_EQ(c.packets_late, 0);
  const auto by = device->extraCounters().rejected_by_reason;
  EXPECT_EQ(by[static_cast<int>(UdpPacketError::Size)], 4);
  EXPECT_EQ(by[static_cast<int>(UdpPacketError::Version)], 1);
  EXPECT_EQ(by[static_cast<int>(UdpPacketError::Quaternion)], 1);
  EXPECT_EQ(by[static_cast<int>(UdpPacketError::NonFinite)], 1);
  EXPECT_EQ(by[static_cast<int>(UdpPacketError::Extension)], 1);
  EXPECT_EQ(device->read(0.0).pose.tip.x(), 2.0);
}

TEST(NetworkDevice, ForcePacketsReachThePeerClampedWithTheSequenceTheyAnswer) {
  FakeClock clock;
  auto device = openOn(clock);
  ASSERT_NE(device, nullptr);
  Peer peer(device->port());
  peer.send(state(5));
  ASSERT_TRUE(waitForDatagrams(*device, 1));
  device->read(0.0);
  device->commandForce({0, 10, 0});  // above max_force_n = 3
  EXPECT_EQ(device->lastForce(), Eigen::Vector3d(0, 3, 0));
  UdpForcePacket f;
  ASSERT_TRUE(peer.receiveForce(f));
  EXPECT_EQ(f.sequence, 0u);
  EXPECT_EQ(f.ack_sequence, 5u);
  EXPECT_EQ(f.flags, 0u);
  EXPECT_EQ(f.force_n, Eigen::Vector3d(0, 3, 0));

  peer.send(state(6));
  ASSERT_TRUE(waitForDatagrams(*device, 2));
  device->commandForce({0.25, 0, 0});  // not read yet: the force still answers state 5
  ASSERT_TRUE(peer.receiveForce(f));
  EXPECT_EQ(f.sequence, 1u);
  EXPECT_EQ(f.ack_sequence, 5u);
  EXPECT_EQ(f.force_n, Eigen::Vector3d(0.25, 0, 0));
  device->read(0.0);
  device->commandForce({std::numeric_limits<double>::quiet_NaN(), 0, 0});
  ASSERT_TRUE(peer.receiveForce(f));
  EXPECT_EQ(f.sequence, 2u);
  EXPECT_EQ(f.ack_sequence, 6u);
  EXPECT_EQ(f.force_n, Eigen::Vector3d::Zero());  // a NaN never reaches the motor
  EXPECT_EQ(device->extraCounters().forces_sent, 3);
  EXPECT_EQ(device->extraCounters().force_send_errors, 0);
}

// The timeout is measured on the device's clock: a FakeClock moved past it makes the input
// stale without waiting.
TEST(NetworkDevice, AfterTheTimeoutTheForceIsZeroThePedalReleasedAndTheDeviceDisconnected) {
  FakeClock clock(1000 * kMs);
  auto device = openOn(clock);
  ASSERT_NE(device, nullptr);
  Peer peer(device->port());
  UdpStatePacket p = state(1, 4.0);
  p.buttons = kUdpButtonPedal;
  p.velocity_mm_s = {1, 2, 3};
  p.angular_velocity_rad_s = {0.1, 0, 0};
  p.extension_mm = 5;
  p.extension_velocity_mm_s = 6;
  peer.send(p);
  ASSERT_TRUE(waitForDatagrams(*device, 1));
  ASSERT_TRUE(device->read(0.0).pose.pedal);

  clock.advanceNs(50 * kMs);  // exactly the timeout: still fresh
  EXPECT_TRUE(device->connected());
  EXPECT_TRUE(device->read(0.05).pose.pedal);
  device->commandForce({1, 0, 0});
  EXPECT_EQ(device->lastForce(), Eigen::Vector3d(1, 0, 0));
  UdpForcePacket f;
  ASSERT_TRUE(peer.receiveForce(f));
  EXPECT_EQ(f.flags, 0u);

  clock.advanceNs(1);  // past it
  EXPECT_FALSE(device->connected());
  const DeviceState s = device->read(0.051);
  EXPECT_FALSE(s.pose.pedal);
  EXPECT_EQ(s.buttons, 0u);
  EXPECT_EQ(s.velocity_mm_s, Eigen::Vector3d::Zero());
  EXPECT_EQ(s.angular_velocity_rad_s, Eigen::Vector3d::Zero());
  EXPECT_EQ(s.extension_velocity_mm_s, 0.0);
  EXPECT_EQ(s.pose.tip, Eigen::Vector3d(4, 2, 3));  // the pose is held
  EXPECT_EQ(s.pose.extension_mm, 5.0);
  device->commandForce({1, 0, 0});
  EXPECT_EQ(device->lastForce(), Eigen::Vector3d::Zero());
  ASSERT_TRUE(peer.receiveForce(f));
  EXPECT_EQ(f.flags, kUdpFlagStale | kUdpFlagDisconnected);
  EXPECT_EQ(f.force_n, Eigen::Vector3d::Zero());
  EXPECT_EQ(f.ack_sequence, 1u);
  device->read(0.052);  // still stale: the same period
  DeviceCounters c = device->counters();
  EXPECT_EQ(c.stale_periods, 1);
  EXPECT_EQ(c.disconnects, 1);
  EXPECT_EQ(c.reconnects, 0);

  // The peer comes back (restarted, counting from 0): a new stream, not late, not lost.
  peer.send(state(0, 8.0));
  ASSERT_TRUE(waitForDatagrams(*device, 2));
  EXPECT_TRUE(device->connected());
  EXPECT_EQ(device->read(0.06).pose.tip.x(), 8.0);
  device->commandForce({0, 0, 2});
  EXPECT_EQ(device->lastForce(), Eigen::Vector3d(0, 0, 2));
  c = device->counters();
  EXPECT_EQ(c.reconnects, 1);
  EXPECT_EQ(c.packets_received, 2);
  EXPECT_EQ(c.packets_late, 0);
  EXPECT_EQ(c.packets_lost, 0);
  EXPECT_EQ(device->extraCounters().stream_restarts, 1);
}

// A burst of 1,000 packets in batches (as a 1 kHz peer sends in one second) is taken whole.
TEST(NetworkDevice, TakesAThousandPacketsInOrder) {
  FakeClock clock;
  auto device = openOn(clock);
  ASSERT_NE(device, nullptr);
  Peer peer(device->port());
  for (std::uint32_t batch = 0; batch < 20; ++batch) {
    for (std::uint32_t i = 0; i < 50; ++i) peer.send(state(batch * 50 + i, batch * 50 + i));
    ASSERT_TRUE(waitForDatagrams(*device, (batch + 1) * 50));
  }
  const DeviceCounters c = device->counters();
  EXPECT_EQ(c.packets_received, 1000);
  EXPECT_EQ(c.packets_lost + c.packets_late + c.packets_malformed, 0);
  EXPECT_EQ(device->read(0.0).pose.tip.x(), 999.0);
}

// The haptic loop drives the network device as any other: it reads the peer's state and the
// force it commands reaches the peer.
TEST(NetworkDevice, AHapticLoopSendsItsForceToThePeer) {
  FakeClock clock;
  std::string error;
  auto owned = NetworkDevice::open(NetworkDeviceOptions{}, clock, &error);
  ASSERT_NE(owned, nullptr) << error;
  NetworkDevice& device = *owned;
  Peer peer(device.port());
  peer.send(state(1, 0.0));
  ASSERT_TRUE(waitForDatagrams(device, 1));
  HapticLoopOptions options;
  options.safety.ramp_s = 0.0;
  options.realtime_priority = 0;
  HapticLoop loop(std::move(owned), clock, options);
  LocalForceModel m;
  m.f0_n = {0, 0.15, 0};  // below the safety gate's engage threshold, so it engages
  for (int i = 0; i < 10; ++i) {
    m.step = i;
    loop.publishModel(m);
    loop.tick(clock.nowNs());
  }
  UdpForcePacket f;
  for (int i = 0; i < 10; ++i) ASSERT_TRUE(peer.receiveForce(f));
  EXPECT_EQ(f.sequence, 9u);
  EXPECT_EQ(f.ack_sequence, 1u);
  EXPECT_NEAR(f.force_n.y(), 0.15, 1e-12);
}

}  // namespace
}  // namespace hysim::haptics
