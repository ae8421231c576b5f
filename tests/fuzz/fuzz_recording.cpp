// Fuzz target: the .hyrec recording reader. Any bytes must give a recording or an error
// naming the byte. Mutated records seldom keep their checksum, so the input's first record's
// worth of bytes is also decoded as one record with its check put right: that reaches the
// plausibility checks, and a record that decodes must encode and decode again.
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "hysim/haptics/little_endian.hpp"
#include "hysim/haptics/recording.hpp"

using namespace hysim::haptics;

namespace {

void checkOneRecord(const std::uint8_t* data, std::size_t size) {
  constexpr std::size_t kCheck = kRecordBytes - 4;
  if (size < kCheck) return;
  std::array<unsigned char, kRecordBytes> bytes{};
  std::copy(data, data + kCheck, bytes.begin());
  le::putU32(bytes.data() + kCheck, le::fnv1a32(bytes.data(), kCheck));
  RecordedState decoded, again;
  std::string reason;
  if (!decodeRecord(bytes.data(), decoded, reason)) return;
  std::array<unsigned char, kRecordBytes> encoded{};
  encodeRecord(decoded.state, decoded.attached, encoded.data());
  if (!decodeRecord(encoded.data(), again, reason)) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::vector<unsigned char> bytes(data, data + size);
  Recording recording;
  std::string error;
  (void)parseRecording(bytes, "fuzz.hyrec", recording, error);
  checkOneRecord(data, size);
  return 0;
}
