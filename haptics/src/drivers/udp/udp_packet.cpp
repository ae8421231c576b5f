#include "hysim/haptics/udp_packet.hpp"

#include "hysim/haptics/little_endian.hpp"

#include <Eigen/Geometry>
#include <bit>
#include <cassert>
#include <cmath>
#include <limits>

namespace hysim::haptics {

// Doubles travel as their IEEE-754 bit pattern; any other double format would need a converter.
static_assert(std::numeric_limits<double>::is_iec559, "the wire format carries IEEE-754 doubles");

namespace {

constexpr std::array<std::uint8_t, 4> kStateMagic{'H', 'Y', 'S', 'D'};
constexpr std::array<std::uint8_t, 4> kForceMagic{'H', 'Y', 'S', 'F'};

// Writes little-endian values at increasing offsets; the caller sizes the buffer exactly.
class Writer {
 public:
  explicit Writer(std::span<std::uint8_t> out) : out_(out) {}
  void bytes(const std::array<std::uint8_t, 4>& b) {
    for (std::uint8_t v : b) out_[at_++] = v;
  }
  void u16(std::uint16_t v) { le::putU16(next(2), v); }
  void u32(std::uint32_t v) { le::putU32(next(4), v); }
  void f64(double v) { le::putF64(next(8), v); }
  void vec3(const Eigen::Vector3d& v) {
    for (int i = 0; i < 3; ++i) f64(v[i]);
  }
  std::size_t offset() const { return at_; }

 private:
  unsigned char* next(std::size_t n) {
    unsigned char* p = out_.data() + at_;
    at_ += n;
    return p;
  }
  std::span<std::uint8_t> out_;
  std::size_t at_ = 0;
};

// Reads little-endian values; the caller has checked the size before the first read.
class Reader {
 public:
  explicit Reader(std::span<const std::uint8_t> in) : in_(in) {}
  bool magic(const std::array<std::uint8_t, 4>& expected) {
    bool same = true;
    for (std::uint8_t v : expected) same = same && in_[at_++] == v;
    return same;
  }
  std::uint16_t u16() { return le::getU16(next(2)); }
  std::uint32_t u32() { return le::getU32(next(4)); }
  double f64() { return le::getF64(next(8)); }
  Eigen::Vector3d vec3() {
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) v[i] = f64();
    return v;
  }
  std::size_t offset() const { return at_; }

 private:
  const unsigned char* next(std::size_t n) {
    const unsigned char* p = in_.data() + at_;
    at_ += n;
    return p;
  }
  std::span<const std::uint8_t> in_;
  std::size_t at_ = 0;
};

// The common header: magic, version, type. Returns the first field that does not match.
UdpPacketError readHeader(Reader& r, const std::array<std::uint8_t, 4>& magic, std::uint16_t type) {
  if (!r.magic(magic)) return UdpPacketError::Magic;
  if (r.u16() != kUdpProtocolVersion) return UdpPacketError::Version;
  if (r.u16() != type) return UdpPacketError::Type;
  return UdpPacketError::None;
}

bool finite(const UdpStatePacket& p) {
  bool ok = std::isfinite(p.peer_time_s) && p.tip_mm.allFinite() && p.velocity_mm_s.allFinite() &&
            p.angular_velocity_rad_s.allFinite() && std::isfinite(p.extension_mm) &&
            std::isfinite(p.extension_velocity_mm_s);
  for (double q : p.orientation_wxyz) ok = ok && std::isfinite(q);
  return ok;
}

double quaternionNorm(const std::array<double, 4>& q) {
  return std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
}

}  // namespace

const char* describe(UdpPacketError error) {
  switch (error) {
    case UdpPacketError::None: return "ok";
    case UdpPacketError::Size: return "wrong size";
    case UdpPacketError::Magic: return "wrong magic";
    case UdpPacketError::Version: return "unsupported version";
    case UdpPacketError::Type: return "unexpected packet type";
    case UdpPacketError::NonFinite: return "non-finite number";
    case UdpPacketError::Quaternion: return "orientation is not a unit quaternion";
    case UdpPacketError::Extension: return "loop extension out of range";
  }
  return "unknown";
}

std::array<std::uint8_t, kUdpStatePacketSize> encodeState(const UdpStatePacket& p) {
  std::array<std::uint8_t, kUdpStatePacketSize> out{};
  Writer w(out);
  w.bytes(kStateMagic);
  w.u16(kUdpProtocolVersion);
  w.u16(kUdpStateType);
  w.u32(p.sequence);
  w.u32(p.buttons);
  w.f64(p.peer_time_s);
  w.vec3(p.tip_mm);
  for (double q : p.orientation_wxyz) w.f64(q);
  w.vec3(p.velocity_mm_s);
  w.vec3(p.angular_velocity_rad_s);
  w.f64(p.extension_mm);
  w.f64(p.extension_velocity_mm_s);
  assert(w.offset() == out.size());
  return out;
}

std::array<std::uint8_t, kUdpForcePacketSize> encodeForce(const UdpForcePacket& p) {
  std::array<std::uint8_t, kUdpForcePacketSize> out{};
  Writer w(out);
  w.bytes(kForceMagic);
  w.u16(kUdpProtocolVersion);
  w.u16(kUdpForceType);
  w.u32(p.sequence);
  w.u32(p.ack_sequence);
  w.u32(p.flags);
  w.u32(0);  // reserved: keeps the doubles 8-byte aligned in the datagram
  w.vec3(p.force_n);
  assert(w.offset() == out.size());
  return out;
}

UdpPacketError decodeState(std::span<const std::uint8_t> bytes, UdpStatePacket& out) {
  if (bytes.size() != kUdpStatePacketSize) return UdpPacketError::Size;
  Reader r(bytes);
  if (const UdpPacketError e = readHeader(r, kStateMagic, kUdpStateType); e != UdpPacketError::None) return e;
  UdpStatePacket p;
  p.sequence = r.u32();
  p.buttons = r.u32();
  p.peer_time_s = r.f64();
  p.tip_mm = r.vec3();
  for (double& q : p.orientation_wxyz) q = r.f64();
  p.velocity_mm_s = r.vec3();
  p.angular_velocity_rad_s = r.vec3();
  p.extension_mm = r.f64();
  p.extension_velocity_mm_s = r.f64();
  assert(r.offset() == bytes.size());
  if (!finite(p)) return UdpPacketError::NonFinite;
  if (!(std::abs(quaternionNorm(p.orientation_wxyz) - 1.0) <= kUdpQuaternionNormTolerance)) {
    return UdpPacketError::Quaternion;
  }
  if (!(p.extension_mm >= 0.0 && p.extension_mm <= kUdpMaxExtensionMm)) return UdpPacketError::Extension;
  out = p;
  return UdpPacketError::None;
}

UdpPacketError decodeForce(std::span<const std::uint8_t> bytes, UdpForcePacket& out) {
  if (bytes.size() != kUdpForcePacketSize) return UdpPacketError::Size;
  Reader r(bytes);
  if (const UdpPacketError e = readHeader(r, kForceMagic, kUdpForceType); e != UdpPacketError::None) return e;
  UdpForcePacket p;
  p.sequence = r.u32();
  p.ack_sequence = r.u32();
  p.flags = r.u32();
  r.u32();  // reserved, ignored so later versions may use it
  p.force_n = r.vec3();
  assert(r.offset() == bytes.size());
  if (!p.force_n.allFinite()) return UdpPacketError::NonFinite;
  out = p;
  return UdpPacketError::None;
}

DeviceState deviceStateFromPacket(const UdpStatePacket& p) {
  const auto& q = p.orientation_wxyz;
  DeviceState s;
  s.pose.tip = p.tip_mm;
  s.pose.rotation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
  s.pose.extension_mm = p.extension_mm;
  s.pose.pedal = (p.buttons & kUdpButtonPedal) != 0;
  s.velocity_mm_s = p.velocity_mm_s;
  s.angular_velocity_rad_s = p.angular_velocity_rad_s;
  s.extension_velocity_mm_s = p.extension_velocity_mm_s;
  s.buttons = p.buttons;
  return s;
}

UdpStatePacket statePacketFromDevice(const DeviceState& s, std::uint32_t sequence, double peer_time_s) {
  const Eigen::Quaterniond q = Eigen::Quaterniond(s.pose.rotation).normalized();
  UdpStatePacket p;
  p.sequence = sequence;
  p.buttons = s.buttons | (s.pose.pedal ? kUdpButtonPedal : 0u);
  p.peer_time_s = peer_time_s;
  p.tip_mm = s.pose.tip;
  p.orientation_wxyz = {q.w(), q.x(), q.y(), q.z()};
  p.velocity_mm_s = s.velocity_mm_s;
  p.angular_velocity_rad_s = s.angular_velocity_rad_s;
  p.extension_mm = s.pose.extension_mm;
  p.extension_velocity_mm_s = s.extension_velocity_mm_s;
  return p;
}

}  // namespace hysim::haptics
