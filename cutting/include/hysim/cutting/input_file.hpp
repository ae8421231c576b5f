#pragma once
// Input files are checked before anything reads them: a device (/dev/zero), a FIFO or a
// directory given where a file was expected would be read forever or fail late, and a file
// far larger than any real input would exhaust memory. Every loader (MSH/VTK meshes, cut
// surfaces, scenes and the other YAML files) goes through checkInputFile or readInputFile.
// Header only, standard library only: the loaders of every module share it.
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>

#include "hysim/cutting/result.hpp"

namespace hysim {

// Largest mesh file read (MSH, VTK, and the surface files assimp reads): 1 GiB.
inline constexpr std::uintmax_t kMaxMeshFileBytes = std::uintmax_t{1} << 30;
// Largest scene or other YAML file read (pad scripts, device filters, gamepad mappings): 16 MiB.
inline constexpr std::uintmax_t kMaxYamlFileBytes = std::uintmax_t{16} << 20;

// "16 MiB", "1 GiB", or a byte count.
inline std::string byteSizeText(std::uintmax_t bytes) {
  if (bytes >= (std::uintmax_t{1} << 30) && bytes % (std::uintmax_t{1} << 30) == 0) {
    return std::to_string(bytes >> 30) + " GiB";
  }
  if (bytes >= (std::uintmax_t{1} << 20) && bytes % (std::uintmax_t{1} << 20) == 0) {
    return std::to_string(bytes >> 20) + " MiB";
  }
  return std::to_string(bytes) + " bytes";
}

// Ok when `path` names a regular file (symbolic links followed) of at most `max_bytes`;
// otherwise an error naming the path. `what` names the kind of file in the message ("mesh").
inline Status checkInputFile(const std::string& path, std::uintmax_t max_bytes, const std::string& what) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status)) {
    const std::string why = ec ? ec.message() : std::string(std::strerror(ENOENT));
    return Error{"cannot open '" + path + "': " + why};
  }
  if (fs::is_directory(status)) return Error{"cannot read '" + path + "': " + std::strerror(EISDIR)};
  if (!fs::is_regular_file(status)) {
    return Error{"cannot read '" + path + "': not a regular file (a device, FIFO or socket), refused as a " + what +
                 " file"};
  }
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) return Error{"cannot read '" + path + "': " + ec.message()};
  if (size > max_bytes) {
    return Error{"cannot read '" + path + "': " + std::to_string(size) + " bytes, more than the " +
                 byteSizeText(max_bytes) + " limit for a " + what + " file"};
  }
  return Status::Ok();
}

// The whole file, after checkInputFile. The read stops at the limit too, in case the file
// grows between the check and the read.
inline Result<std::string> readInputFile(const std::string& path, std::uintmax_t max_bytes, const std::string& what) {
  if (Status s = checkInputFile(path, max_bytes, what); !s) return Error{s.error()};
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (!file) return Error{"cannot open '" + path + "': " + std::strerror(errno)};
  std::string text;
  char buffer[1 << 16];
  std::size_t got = 0;
  while (text.size() <= max_bytes && (got = std::fread(buffer, 1, sizeof buffer, file)) > 0) text.append(buffer, got);
  const bool failed = std::ferror(file) != 0;
  const int read_errno = errno;
  std::fclose(file);
  if (failed) return Error{"cannot read '" + path + "': " + std::strerror(read_errno)};
  if (text.size() > max_bytes) {
    return Error{"cannot read '" + path + "': it grew past the " + byteSizeText(max_bytes) + " limit for a " + what +
                 " file while being read"};
  }
  return text;
}

// Offset of the first byte of `text` that is not part of well-formed UTF-8 (Unicode table
// 3-7: no overlong forms, no surrogates, nothing past U+10FFFF), or npos. Strings that reach
// a JSON report must pass: the JSON writer refuses anything else.
inline std::size_t firstInvalidUtf8(std::string_view text) {
  std::size_t i = 0;
  const std::size_t n = text.size();
  while (i < n) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x80) {
      ++i;
      continue;
    }
    int length = 0;
    unsigned char lo = 0x80, hi = 0xBF;  // range of the second byte
    if (c >= 0xC2 && c <= 0xDF) {
      length = 2;
    } else if (c >= 0xE0 && c <= 0xEF) {
      length = 3;
      if (c == 0xE0) lo = 0xA0;
      if (c == 0xED) hi = 0x9F;
    } else if (c >= 0xF0 && c <= 0xF4) {
      length = 4;
      if (c == 0xF0) lo = 0x90;
      if (c == 0xF4) hi = 0x8F;
    } else {
      return i;
    }
    if (i + 1 >= n) return i;
    const auto second = static_cast<unsigned char>(text[i + 1]);
    if (second < lo || second > hi) return i;
    for (int k = 2; k < length; ++k) {
      if (i + static_cast<std::size_t>(k) >= n) return i;
      const auto next = static_cast<unsigned char>(text[i + static_cast<std::size_t>(k)]);
      if (next < 0x80 || next > 0xBF) return i;
    }
    i += static_cast<std::size_t>(length);
  }
  return std::string_view::npos;
}

}  // namespace hysim
