// Fuzz target: the UDP bridge's packet decoders. Any datagram must decode or be refused; a
// packet that decodes must encode to bytes that decode and encode to themselves again (the
// wire format normalises nothing; only the reserved word may differ from the input).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "hysim/haptics/udp_packet.hpp"

using namespace hysim::haptics;

namespace {

template <class Packet, class Decode, class Encode>
void checkRoundTrip(std::span<const std::uint8_t> bytes, Decode decode, Encode encode) {
  Packet packet;
  if (decode(bytes, packet) != UdpPacketError::None) return;
  const auto once = encode(packet);
  Packet again;
  if (decode(std::span<const std::uint8_t>(once), again) != UdpPacketError::None) std::abort();
  if (encode(again) != once) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  checkRoundTrip<UdpStatePacket>(bytes, decodeState, encodeState);
  checkRoundTrip<UdpForcePacket>(bytes, decodeForce, encodeForce);
  if (UdpStatePacket state; decodeState(bytes, state) == UdpPacketError::None) (void)deviceStateFromPacket(state);
  return 0;
}
