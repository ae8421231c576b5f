#pragma once
// A haptic device on the other end of a local UDP socket: a small bridge program next to a
// vendor SDK (OpenHaptics, Force Dimension, libnifalcon) sends the hand's state packets
// (udp_packet.hpp) at up to 1 kHz and receives the force back. A receiver thread
// ("hysim-udp") decodes and hands the newest state to read() through a lock-free mailbox;
// lost, late, reordered, malformed and oversized datagrams are counted and dropped. When no
// state has arrived for the stale timeout the device counts as disconnected: velocities zero,
// buttons and pedal released (the electrode goes off when the hand is gone), the pose held,
// and every force zero.
#include <Eigen/Core>
#include <netinet/in.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "hysim/haptics/clock.hpp"
#include "hysim/haptics/device.hpp"
#include "hysim/haptics/latest_value.hpp"
#include "hysim/haptics/udp_packet.hpp"

namespace hysim::haptics {

DeviceInfo networkDeviceDefaultInfo();

struct NetworkDeviceOptions {
  std::string bind_address = "127.0.0.1";  // IPv4; a local bridge needs no other interface
  std::uint16_t port = 0;                   // 0: the system picks one (see NetworkDevice::port)
  double stale_timeout_s = 0.05;            // no state packet for longer: disconnected, zero force
  int poll_timeout_ms = 10;                 // the receiver's wait; bounds how long stop() takes
  DeviceInfo info = networkDeviceDefaultInfo();
};

// Counts beyond DeviceCounters, for tests and diagnostics.
struct NetworkDeviceExtraCounters {
  long forces_sent = 0;
  long force_send_errors = 0;  // sendto failed (buffer full, peer's address unreachable)
  long stream_restarts = 0;    // a state packet after a silence began a new sequence
  std::array<long, kUdpPacketErrorCount> rejected_by_reason{};  // index: UdpPacketError
};

class NetworkDevice final : public Device {
 public:
  // Binds the socket and starts the receiver thread; nullptr (and a message in *error) when
  // the address is not IPv4 or the port cannot be bound. The clock must outlive the device.
  static std::unique_ptr<NetworkDevice> open(const NetworkDeviceOptions& options, Clock& clock,
                                             std::string* error = nullptr);
  // The same on the monotonic clock, owned by the device.
  static std::unique_ptr<NetworkDevice> open(const NetworkDeviceOptions& options, std::string* error = nullptr);
  ~NetworkDevice() override;
  NetworkDevice(const NetworkDevice&) = delete;
  NetworkDevice& operator=(const NetworkDevice&) = delete;

  const DeviceInfo& info() const override { return options_.info; }
  // One thread (the haptic loop) calls read() and commandForce(); both never block and
  // allocate nothing.
  DeviceState read(double time_s) override;
  // Clamped with safeForce; zero while the input is stale. Sent to the address the last
  // state packet read() took came from (nothing is sent before the first one).
  void commandForce(const Eigen::Vector3d& force_n) override;
  const Eigen::Vector3d& lastForce() const override { return last_force_; }
  bool connected() const override;  // any thread: a state packet arrived within the timeout
  DeviceCounters counters() const override;
  NetworkDeviceExtraCounters extraCounters() const;

  std::uint16_t port() const { return port_; }  // the bound port
  void stop();  // joins the receiver thread (the destructor calls it); idempotent

 private:
  // What the receiver thread hands to read(): the decoded state, its sequence number, when it
  // arrived (on the device's clock) and where from.
  struct Sample {
    DeviceState state;
    std::uint32_t sequence = 0;
    std::int64_t received_ns = 0;
    sockaddr_in from{};
  };

  NetworkDevice(const NetworkDeviceOptions& options, Clock& clock, std::unique_ptr<Clock> owned_clock);
  bool bindSocket(std::string* error);
  void receiverMain();
  void receiveAll(std::uint8_t* buffer, std::size_t capacity);
  void take(const UdpStatePacket& packet, const sockaddr_in& from);
  bool fresh(std::int64_t now_ns) const;

  NetworkDeviceOptions options_;
  std::unique_ptr<Clock> owned_clock_;
  Clock& clock_;
  std::int64_t stale_timeout_ns_;
  int fd_ = -1;
  std::uint16_t port_ = 0;
  LatestValue<Sample> samples_;

  // Receiver thread only.
  bool have_sequence_ = false;
  std::uint32_t newest_sequence_ = 0;
  std::int64_t newest_received_ns_ = 0;

  // Haptic thread only (read / commandForce).
  Sample current_;
  bool have_sample_ = false;
  bool was_connected_ = false;
  bool ever_connected_ = false;
  std::uint32_t force_sequence_ = 0;
  Eigen::Vector3d last_force_{0, 0, 0};

  // Shared.
  std::atomic<bool> stop_request_{false};
  std::atomic<bool> any_received_{false};
  std::atomic<std::int64_t> last_received_ns_{0};
  std::atomic<long> received_{0};
  std::atomic<long> lost_{0};
  std::atomic<long> late_{0};
  std::atomic<long> malformed_{0};
  std::atomic<long> stale_periods_{0};
  std::atomic<long> disconnects_{0};
  std::atomic<long> reconnects_{0};
  std::atomic<long> forces_sent_{0};
  std::atomic<long> force_send_errors_{0};
  std::atomic<long> stream_restarts_{0};
  std::array<std::atomic<long>, kUdpPacketErrorCount> rejected_{};
  std::thread thread_;
};

}  // namespace hysim::haptics
