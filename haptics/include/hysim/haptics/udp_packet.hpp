#pragma once
// The packets of the UDP device bridge (haptics/README.md, "UDP device bridge"): a bridge
// program next to a vendor SDK sends the hand's state to hysim, hysim answers with the force.
// Both packets have a fixed size and are little-endian on the wire; they are written and read
// byte by byte, so the code is the same on any host and any input bytes are safe to decode.
#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "hysim/haptics/device.hpp"

namespace hysim::haptics {

inline constexpr std::uint16_t kUdpProtocolVersion = 1;
inline constexpr std::uint16_t kUdpStateType = 1;  // peer -> hysim
inline constexpr std::uint16_t kUdpForceType = 2;  // hysim -> peer
inline constexpr std::size_t kUdpStatePacketSize = 144;
inline constexpr std::size_t kUdpForcePacketSize = 48;
inline constexpr double kUdpMaxExtensionMm = 50.0;        // loop extension must lie in [0, this]
inline constexpr double kUdpQuaternionNormTolerance = 1e-3;  // | |q| - 1 | above this: rejected

// State packet buttons.
inline constexpr std::uint32_t kUdpButtonPedal = 1u << 0;  // cut pedal (electrode on)
inline constexpr std::uint32_t kUdpButtonLens = 1u << 1;   // lens switch

// Force packet flags.
inline constexpr std::uint32_t kUdpFlagStale = 1u << 0;         // force zeroed: input is stale
inline constexpr std::uint32_t kUdpFlagDisconnected = 1u << 1;  // hysim counts the device as gone

// The peer's sample of the hand, as on the wire (no normalisation, so a decoded packet encodes
// to the same bytes). Positions in mm, world frame; the quaternion w, x, y, z turns the body
// frame (x, y = up, z = shaft axis, as the columns of ToolPose::rotation) into the world.
struct UdpStatePacket {
  std::uint32_t sequence = 0;
  std::uint32_t buttons = 0;
  double peer_time_s = 0.0;
  Eigen::Vector3d tip_mm{0, 0, 0};
  std::array<double, 4> orientation_wxyz{1, 0, 0, 0};
  Eigen::Vector3d velocity_mm_s{0, 0, 0};
  Eigen::Vector3d angular_velocity_rad_s{0, 0, 0};
  double extension_mm = 0.0;
  double extension_velocity_mm_s = 0.0;
};

struct UdpForcePacket {
  std::uint32_t sequence = 0;        // hysim's own count of force packets
  std::uint32_t ack_sequence = 0;    // the state packet the force was computed from
  std::uint32_t flags = 0;
  Eigen::Vector3d force_n{0, 0, 0};  // world frame
};

// Why a datagram was refused (checked in this order).
enum class UdpPacketError {
  None,
  Size,        // not exactly the packet's size (short, truncated or oversized)
  Magic,       // not "HYSD" / "HYSF"
  Version,     // not kUdpProtocolVersion
  Type,        // not the packet type expected here
  NonFinite,   // a NaN or infinity in any number
  Quaternion,  // orientation not within kUdpQuaternionNormTolerance of unit length
  Extension,   // loop extension outside [0, kUdpMaxExtensionMm]
};
inline constexpr int kUdpPacketErrorCount = 8;

const char* describe(UdpPacketError error);

std::array<std::uint8_t, kUdpStatePacketSize> encodeState(const UdpStatePacket& packet);
std::array<std::uint8_t, kUdpForcePacketSize> encodeForce(const UdpForcePacket& packet);

// Decode any bytes: a well-formed packet fills `out` and gives None; anything else leaves
// `out` alone and gives the first reason it fails. Allocates nothing.
UdpPacketError decodeState(std::span<const std::uint8_t> bytes, UdpStatePacket& out);
UdpPacketError decodeForce(std::span<const std::uint8_t> bytes, UdpForcePacket& out);

// A decoded state as the device's state: the quaternion normalised into a rotation, buttons
// as given, the pedal from bit 0. time_s is left for the caller.
DeviceState deviceStateFromPacket(const UdpStatePacket& packet);
// The packet a peer sends for `state` (the rotation converted to a unit quaternion).
UdpStatePacket statePacketFromDevice(const DeviceState& state, std::uint32_t sequence, double peer_time_s);

}  // namespace hysim::haptics
