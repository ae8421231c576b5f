// hysim-udp-peer: the reference peer of the UDP device bridge (haptics/README.md). It replays a
// scene's scripted tool path as state packets at a fixed rate, as a bridge next to a vendor
// SDK would send the hand's state, reads the force packets hysim sends back and prints a
// summary. A bridge for real hardware replaces the script with the SDK's samples and renders
// the force it receives.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>

#include "hysim/engine/scene.hpp"
#include "hysim/haptics/clock.hpp"
#include "hysim/haptics/device.hpp"
#include "hysim/haptics/udp_packet.hpp"
#include "tool_common.hpp"

using namespace hysim;

namespace {

struct PeerArgs {
  std::string scene;
  int port = 0;
  std::string host = "127.0.0.1";
  double rate_hz = 1000.0;
  double seconds = -1.0;  // < 0: the scripted path's duration
  double start_delay_s = 0.0;
};

struct PeerSummary {
  long sent = 0;
  long send_errors = 0;
  long late_ticks = 0;  // the sender woke more than one period after its deadline
  long forces = 0;
  long forces_malformed = 0;
  long forces_stale = 0;  // flagged: hysim zeroed the force because our input was stale
  std::uint32_t last_ack = 0;
  double max_force_n = 0.0;
  double elapsed_s = 0.0;
};

int fail(const std::string& message) {
  std::cerr << "hysim-udp-peer: " << message << "\n";
  return 2;
}

// A UDP socket (bound by the system on the first send) and the address of hysim's device.
bool openSocket(const PeerArgs& args, int& fd, sockaddr_in& to, std::string& error) {
  to = sockaddr_in{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<std::uint16_t>(args.port));
  if (::inet_pton(AF_INET, args.host.c_str(), &to.sin_addr) != 1) {
    error = "--host '" + args.host + "' is not an IPv4 address";
    return false;
  }
  fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    error = std::string("socket: ") + std::strerror(errno);
    return false;
  }
  return true;
}

// Takes every force packet waiting now, without blocking.
void drainForces(int fd, PeerSummary& summary) {
  std::uint8_t buffer[512];
  for (;;) {
    const ssize_t n = ::recv(fd, buffer, sizeof(buffer), MSG_DONTWAIT | MSG_TRUNC);
    if (n < 0) {
      if (errno == EINTR) continue;
      return;
    }
    haptics::UdpForcePacket force;
    const std::size_t size = static_cast<std::size_t>(n);
    if (size > sizeof(buffer) || haptics::decodeForce(std::span<const std::uint8_t>(buffer, size), force) !=
                                     haptics::UdpPacketError::None) {
      ++summary.forces_malformed;
      continue;
    }
    ++summary.forces;
    summary.last_ack = force.ack_sequence;
    if (force.flags & haptics::kUdpFlagStale) ++summary.forces_stale;
    summary.max_force_n = std::max(summary.max_force_n, force.force_n.norm());
  }
}

// Sends the path's state at t_k = k / rate on absolute deadlines, so the rate never drifts.
PeerSummary replay(const PeerArgs& args, const haptics::Trajectory& path, int fd, const sockaddr_in& to) {
  haptics::ScriptedDevice script(path);
  haptics::SteadyClock clock;
  const std::int64_t period_ns = std::llround(1e9 / args.rate_hz);
  const double seconds = args.seconds >= 0.0 ? args.seconds : path.duration();
  const long ticks = static_cast<long>(std::floor(seconds * args.rate_hz)) + 1;
  const std::int64_t start_ns = clock.nowNs() + std::llround(args.start_delay_s * 1e9);
  PeerSummary summary;
  for (long k = 0; k < ticks; ++k) {
    const std::int64_t deadline_ns = start_ns + k * period_ns;
    clock.sleepUntilNs(deadline_ns);
    if (clock.nowNs() - deadline_ns > period_ns) ++summary.late_ticks;
    const double t = static_cast<double>(k) / args.rate_hz;
    const auto packet = haptics::statePacketFromDevice(script.read(t), static_cast<std::uint32_t>(k), t);
    const auto bytes = haptics::encodeState(packet);
    const ssize_t n = ::sendto(fd, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof(to));
    ++(n == static_cast<ssize_t>(bytes.size()) ? summary.sent : summary.send_errors);
    drainForces(fd, summary);
  }
  // The answers to the last packets are still on their way: wait for them a little.
  clock.sleepUntilNs(clock.nowNs() + 100'000'000);
  drainForces(fd, summary);
  summary.elapsed_s = 1e-9 * static_cast<double>(clock.nowNs() - start_ns);
  return summary;
}

void printSummary(const PeerArgs& args, const PeerSummary& s) {
  std::printf("hysim-udp-peer: sent %ld state packets to %s:%d at %.0f Hz in %.3f s (send errors %ld, late ticks %ld)\n",
              s.sent, args.host.c_str(), args.port, args.rate_hz, s.elapsed_s, s.send_errors, s.late_ticks);
  std::printf("hysim-udp-peer: force packets received %ld (malformed %ld, zeroed as stale %ld), last ack %u, max force %.4f N\n",
              s.forces, s.forces_malformed, s.forces_stale, s.last_ack, s.max_force_n);
}

}  // namespace

int main(int argc, char** argv) {
  PeerArgs args;
  args.scene = tools::defaultScenePath();
  CLI::App app{"hysim-udp-peer: replays a scene's scripted tool path to hysim's UDP device (reference bridge peer)"};
  app.add_option("scene", args.scene, "scene file (default: scenes/default.yaml)");
  app.add_option("--port", args.port, "hysim's UDP device port")->required()->check(CLI::Range(1, 65535));
  app.add_option("--host", args.host, "hysim's IPv4 address")->capture_default_str();
  app.add_option("--rate", args.rate_hz, "state packets per second")->capture_default_str()->check(tools::finiteRange(1.0, 10000.0));
  app.add_option("--seconds", args.seconds, "how long to send (default: the path's duration)")->check(tools::finiteRange(0.0, 86400.0));
  app.add_option("--start-delay-s", args.start_delay_s, "wait this long before the first packet")
      ->capture_default_str()
      ->check(tools::finiteRange(0.0, 3600.0));
  CLI11_PARSE(app, argc, argv);

  auto scene = engine::loadScene(args.scene);
  if (!scene.ok()) return fail(scene.error());
  if (scene->tool_path.empty()) return fail("scene '" + args.scene + "' has no tool_path to replay");
  const haptics::Trajectory path(scene->tool_path);
  if (args.seconds < 0.0 && path.duration() <= 0.0) {
    return fail("the tool path of '" + args.scene + "' lasts 0 s; give --seconds");
  }
  int fd = -1;
  sockaddr_in to{};
  std::string error;
  if (!openSocket(args, fd, to, error)) return fail(error);
  const PeerSummary summary = replay(args, path, fd, to);
  ::close(fd);
  printSummary(args, summary);
  return summary.sent > 0 ? 0 : 1;
}
