#include "hysim/haptics/udp_device.hpp"

#include <arpa/inet.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <span>
#include <utility>

#include "thread_setup.hpp"

namespace hysim::haptics {

namespace {

// Room for any datagram we would take plus a margin; with MSG_TRUNC recvfrom reports the real
// length, so a bigger datagram is seen as oversized rather than silently cut.
constexpr std::size_t kReceiveBufferSize = 2048;

// Single-writer counter: each counter has one writing thread, so a load and a store suffice.
void bump(std::atomic<long>& counter, long by = 1) {
  counter.store(counter.load(std::memory_order_relaxed) + by, std::memory_order_relaxed);
}

void setError(std::string* error, std::string message) {
  if (error) *error = std::move(message);
}

}  // namespace

DeviceInfo networkDeviceDefaultInfo() {
  DeviceInfo info;
  info.name = "udp bridge";
  info.num_buttons = 2;  // cut pedal, lens switch
  return info;
}

NetworkDevice::NetworkDevice(const NetworkDeviceOptions& options, Clock& clock, std::unique_ptr<Clock> owned_clock)
    : options_(options),
      owned_clock_(std::move(owned_clock)),
      clock_(clock),
      stale_timeout_ns_(std::llround(options.stale_timeout_s * 1e9)) {}

std::unique_ptr<NetworkDevice> NetworkDevice::open(const NetworkDeviceOptions& options, std::string* error) {
  auto clock = std::make_unique<SteadyClock>();
  Clock& ref = *clock;
  std::unique_ptr<NetworkDevice> device(new NetworkDevice(options, ref, std::move(clock)));
  if (!device->bindSocket(error)) return nullptr;
  device->thread_ = std::thread(&NetworkDevice::receiverMain, device.get());
  return device;
}

std::unique_ptr<NetworkDevice> NetworkDevice::open(const NetworkDeviceOptions& options, Clock& clock,
                                                   std::string* error) {
  std::unique_ptr<NetworkDevice> device(new NetworkDevice(options, clock, nullptr));
  if (!device->bindSocket(error)) return nullptr;
  device->thread_ = std::thread(&NetworkDevice::receiverMain, device.get());
  return device;
}

NetworkDevice::~NetworkDevice() {
  stop();
  if (fd_ >= 0) ::close(fd_);
}

void NetworkDevice::stop() {
  stop_request_.store(true);
  if (thread_.joinable()) thread_.join();
}

bool NetworkDevice::bindSocket(std::string* error) {
  if (!(options_.stale_timeout_s > 0.0) || !std::isfinite(options_.stale_timeout_s)) {
    setError(error, "udp device: the stale timeout must be a positive number of seconds");
    return false;
  }
  if (options_.poll_timeout_ms < 1 || options_.poll_timeout_ms > 1000) {
    setError(error, "udp device: the poll timeout must lie in [1, 1000] ms");
    return false;
  }
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(options_.port);
  if (::inet_pton(AF_INET, options_.bind_address.c_str(), &address.sin_addr) != 1) {
    setError(error, "udp device: '" + options_.bind_address + "' is not an IPv4 address");
    return false;
  }
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) {
    setError(error, std::string("udp device: socket: ") + std::strerror(errno));
    return false;
  }
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) != 0) {
    setError(error, "udp device: cannot bind " + options_.bind_address + ":" + std::to_string(options_.port) +
                        ": " + std::strerror(errno));
    return false;
  }
  socklen_t length = sizeof(address);
  if (::getsockname(fd_, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
    setError(error, std::string("udp device: getsockname: ") + std::strerror(errno));
    return false;
  }
  port_ = ntohs(address.sin_port);
  return true;
}

void NetworkDevice::receiverMain() {
  detail::nameThisThread("hysim-udp");
  std::array<std::uint8_t, kReceiveBufferSize> buffer{};
  while (!stop_request_.load(std::memory_order_relaxed)) {
    pollfd waiting{fd_, POLLIN, 0};
    // A short wait, so stop() is answered within poll_timeout_ms.
    if (::poll(&waiting, 1, options_.poll_timeout_ms) > 0) receiveAll(buffer.data(), buffer.size());
  }
}

// Takes every datagram queued now, so a burst is classified in arrival order.
void NetworkDevice::receiveAll(std::uint8_t* buffer, std::size_t capacity) {
  while (!stop_request_.load(std::memory_order_relaxed)) {
    sockaddr_in from{};
    socklen_t from_length = sizeof(from);
    const ssize_t n = ::recvfrom(fd_, buffer, capacity, MSG_DONTWAIT | MSG_TRUNC,
                                 reinterpret_cast<sockaddr*>(&from), &from_length);
    if (n < 0) {
      if (errno == EINTR) continue;
      return;  // drained (EAGAIN), or an error the next poll reports again
    }
    UdpStatePacket packet;
    const std::size_t size = static_cast<std::size_t>(n);
    const UdpPacketError reason =
        size > capacity ? UdpPacketError::Size : decodeState(std::span<const std::uint8_t>(buffer, size), packet);
    if (reason != UdpPacketError::None) {
      bump(malformed_);
      bump(rejected_[static_cast<std::size_t>(reason)]);
      continue;
    }
    take(packet, from);
  }
}

// Orders a well-formed packet against the newest one taken (serial-number arithmetic, so the
// u32 wrap is a step of one) and publishes it when it is newer.
void NetworkDevice::take(const UdpStatePacket& packet, const sockaddr_in& from) {
  const std::int64_t now_ns = clock_.nowNs();
  // After a silence longer than the timeout the peer may have restarted with a new count:
  // its next packet starts the stream again instead of being dropped as late.
  const bool restart = have_sequence_ && now_ns - newest_received_ns_ > stale_timeout_ns_;
  if (have_sequence_ && !restart) {
    const auto ahead = static_cast<std::int32_t>(packet.sequence - newest_sequence_);
    if (ahead <= 0) {
      bump(late_);
      return;
    }
    if (ahead > 1) bump(lost_, ahead - 1);
  }
  if (restart) bump(stream_restarts_);
  have_sequence_ = true;
  newest_sequence_ = packet.sequence;
  newest_received_ns_ = now_ns;

  Sample sample;
  sample.state = deviceStateFromPacket(packet);
  sample.sequence = packet.sequence;
  sample.received_ns = now_ns;
  sample.from = from;
  samples_.publish(sample);
  last_received_ns_.store(now_ns, std::memory_order_release);
  any_received_.store(true, std::memory_order_release);
  bump(received_);
}

bool NetworkDevice::fresh(std::int64_t now_ns) const {
  return have_sample_ && now_ns - current_.received_ns <= stale_timeout_ns_;
}

DeviceState NetworkDevice::read(double time_s) {
  if (samples_.read(current_)) have_sample_ = true;
  const bool is_fresh = fresh(clock_.nowNs());
  if (is_fresh && !was_connected_) {
    if (ever_connected_) bump(reconnects_);
    ever_connected_ = true;
  } else if (!is_fresh && was_connected_) {
    bump(stale_periods_);
    bump(disconnects_);
  }
  was_connected_ = is_fresh;

  DeviceState state = current_.state;
  state.time_s = time_s;
  if (!is_fresh) {
    // The hand is gone: hold the pose, but nothing moves and the electrode is off.
    state.velocity_mm_s.setZero();
    state.angular_velocity_rad_s.setZero();
    state.extension_velocity_mm_s = 0.0;
    state.buttons = 0;
    state.pose.pedal = false;
  }
  return state;
}

void NetworkDevice::commandForce(const Eigen::Vector3d& force_n) {
  const bool is_fresh = fresh(clock_.nowNs());
  last_force_ = is_fresh ? safeForce(force_n, options_.info.max_force_n) : Eigen::Vector3d::Zero();
  if (!have_sample_) return;  // nobody to send to yet

  UdpForcePacket packet;
  packet.sequence = force_sequence_++;
  packet.ack_sequence = current_.sequence;
  packet.flags = is_fresh ? 0u : (kUdpFlagStale | kUdpFlagDisconnected);
  packet.force_n = last_force_;
  const auto bytes = encodeForce(packet);
  const ssize_t sent = ::sendto(fd_, bytes.data(), bytes.size(), MSG_DONTWAIT | MSG_NOSIGNAL,
                                reinterpret_cast<const sockaddr*>(&current_.from), sizeof(current_.from));
  bump(sent == static_cast<ssize_t>(bytes.size()) ? forces_sent_ : force_send_errors_);
}

bool NetworkDevice::connected() const {
  if (!any_received_.load(std::memory_order_acquire)) return false;
  return clock_.nowNs() - last_received_ns_.load(std::memory_order_acquire) <= stale_timeout_ns_;
}

DeviceCounters NetworkDevice::counters() const {
  DeviceCounters c;
  c.packets_received = received_.load(std::memory_order_relaxed);
  c.packets_lost = lost_.load(std::memory_order_relaxed);
  c.packets_late = late_.load(std::memory_order_relaxed);
  c.packets_malformed = malformed_.load(std::memory_order_relaxed);
  c.stale_periods = stale_periods_.load(std::memory_order_relaxed);
  c.disconnects = disconnects_.load(std::memory_order_relaxed);
  c.reconnects = reconnects_.load(std::memory_order_relaxed);
  return c;
}

NetworkDeviceExtraCounters NetworkDevice::extraCounters() const {
  NetworkDeviceExtraCounters c;
  c.forces_sent = forces_sent_.load(std::memory_order_relaxed);
  c.force_send_errors = force_send_errors_.load(std::memory_order_relaxed);
  c.stream_restarts = stream_restarts_.load(std::memory_order_relaxed);
  for (std::size_t i = 0; i < rejected_.size(); ++i) c.rejected_by_reason[i] = rejected_[i].load(std::memory_order_relaxed);
  return c;
}

}  // namespace hysim::haptics
