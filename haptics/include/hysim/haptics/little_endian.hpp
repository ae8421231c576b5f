#pragma once
// Byte-by-byte little-endian encoding for the files and packets hysim exchanges (recordings,
// the UDP device bridge): the bytes are the same on any host, and reading never depends on
// alignment or casts.
#include <bit>
#include <cstddef>
#include <cstdint>

namespace hysim::haptics::le {

inline void putU16(unsigned char* p, std::uint16_t v) {
  p[0] = static_cast<unsigned char>(v);
  p[1] = static_cast<unsigned char>(v >> 8);
}
inline void putU32(unsigned char* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<unsigned char>(v >> (8 * i));
}
inline void putU64(unsigned char* p, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<unsigned char>(v >> (8 * i));
}
inline void putF64(unsigned char* p, double v) { putU64(p, std::bit_cast<std::uint64_t>(v)); }

inline std::uint16_t getU16(const unsigned char* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
inline std::uint32_t getU32(const unsigned char* p) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(p[i]) << (8 * i);
  return v;
}
inline std::uint64_t getU64(const unsigned char* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(p[i]) << (8 * i);
  return v;
}
inline double getF64(const unsigned char* p) { return std::bit_cast<double>(getU64(p)); }

// FNV-1a, 64 bits, continuing from `h` (start with kFnv64Offset): content hashes and checksums.
inline constexpr std::uint64_t kFnv64Offset = 14695981039346656037ull;
inline std::uint64_t fnv1a64(std::uint64_t h, const unsigned char* p, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
  return h;
}

// FNV-1a, 32 bits: a cheap check that a record was not damaged (not a cryptographic hash).
inline std::uint32_t fnv1a32(const unsigned char* p, std::size_t n) {
  std::uint32_t h = 2166136261u;
  for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 16777619u;
  return h;
}

}  // namespace hysim::haptics::le
