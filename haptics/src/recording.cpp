// Recording format: a header, fixed-size records, an end marker (haptics/README.md, "Recordings").
#include "hysim/haptics/recording.hpp"

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "hysim/cutting/input_file.hpp"
#include "hysim/haptics/little_endian.hpp"

namespace hysim::haptics {
namespace {

constexpr char kMagic[9] = "HYSIMREC";
constexpr char kEndMagic[9] = "HYSIMEND";
constexpr int kFixedHeaderBytes = 32;
using le::kFnv64Offset;

// Record layout (offsets in bytes).
constexpr int kTime = 0, kTip = 8, kRotation = 32, kExtension = 104, kVelocity = 112, kAngular = 136,
              kExtensionVelocity = 160, kButtons = 168, kPedal = 172, kFlags = 173, kReserved = 174, kCheck = 176;

void putVector(unsigned char* p, const Eigen::Vector3d& v) {
  for (int i = 0; i < 3; ++i) le::putF64(p + 8 * i, v[i]);
}
Eigen::Vector3d getVector(const unsigned char* p) {
  return {le::getF64(p), le::getF64(p + 8), le::getF64(p + 16)};
}

// Is `state` one a device could have delivered? (Finite, a proper rotation, a sane extension.)
bool plausible(const DeviceState& s, std::string& reason) {
  const ToolPose& p = s.pose;
  if (!std::isfinite(s.time_s) || !p.tip.allFinite() || !p.rotation.allFinite() || !std::isfinite(p.extension_mm) ||
      !s.velocity_mm_s.allFinite() || !s.angular_velocity_rad_s.allFinite() ||
      !std::isfinite(s.extension_velocity_mm_s)) {
    reason = "a number is not finite";
    return false;
  }
  const double off = (p.rotation.transpose() * p.rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (off > 1e-6 || p.rotation.determinant() < 0.0) {
    reason = "the orientation is not a rotation";
    return false;
  }
  if (p.extension_mm < 0.0 || p.extension_mm > kMaxLoopExtensionMm) {
    reason = "loop extension " + std::to_string(p.extension_mm) + " mm is outside [0, 100]";
    return false;
  }
  return true;
}

void putString(std::vector<unsigned char>& out, const std::string& s) {
  unsigned char len[4];
  le::putU32(len, static_cast<std::uint32_t>(s.size()));
  out.insert(out.end(), len, len + 4);
  out.insert(out.end(), s.begin(), s.end());
}

std::vector<unsigned char> encodeHeader(const RecordingHeader& h) {
  std::vector<unsigned char> out(kFixedHeaderBytes);
  std::memcpy(out.data(), kMagic, 8);
  le::putU32(out.data() + 8, kRecordingVersion);
  le::putU32(out.data() + 12, kRecordBytes);
  le::putU64(out.data() + 16, h.scene_hash);
  le::putF64(out.data() + 24, h.dt_s);
  for (const std::string* s : {&h.scene_path, &h.mesh_path, &h.chips_mode, &h.hysim_version, &h.device_name}) {
    putString(out, *s);
  }
  return out;
}

// Reading: a cursor over the whole file that names byte offsets in its errors.
struct Reader {
  const std::vector<unsigned char>& bytes;
  const std::string& path;
  std::size_t at = 0;
  std::string& error;

  bool fail(std::size_t offset, const std::string& what) {
    error = path + ": byte " + std::to_string(offset) + ": " + what;
    return false;
  }
  bool need(std::size_t n, const char* what) {
    if (bytes.size() - at >= n) return true;
    return fail(at, std::string("truncated in ") + what + " (" + std::to_string(bytes.size()) + " bytes in all)");
  }
  bool string(std::string& out, const char* what) {
    if (!need(4, what)) return false;
    const std::uint32_t len = le::getU32(bytes.data() + at);
    if (len > static_cast<std::uint32_t>(kMaxRecordingString)) {
      return fail(at, std::string(what) + " is " + std::to_string(len) + " bytes long (at most 4096)");
    }
    at += 4;
    if (!need(len, what)) return false;
    out.assign(reinterpret_cast<const char*>(bytes.data() + at), len);
    at += len;
    return true;
  }
};

bool readHeader(Reader& r, RecordingHeader& h) {
  if (!r.need(kFixedHeaderBytes, "the header")) return false;
  const unsigned char* p = r.bytes.data();
  if (std::memcmp(p, kMagic, 8) != 0) return r.fail(0, "not a hysim recording (no HYSIMREC marker)");
  if (const std::uint32_t v = le::getU32(p + 8); v != kRecordingVersion) {
    return r.fail(8, "format version " + std::to_string(v) + " (this hysim reads version 1)");
  }
  if (const std::uint32_t n = le::getU32(p + 12); n != static_cast<std::uint32_t>(kRecordBytes)) {
    return r.fail(12, "record size " + std::to_string(n) + " (version 1 records are 180 bytes)");
  }
  h.scene_hash = le::getU64(p + 16);
  h.dt_s = le::getF64(p + 24);
  if (!(h.dt_s > 0.0) || !std::isfinite(h.dt_s)) return r.fail(24, "step dt " + std::to_string(h.dt_s) + " s");
  r.at = kFixedHeaderBytes;
  return r.string(h.scene_path, "the scene path") && r.string(h.mesh_path, "the mesh path") &&
         r.string(h.chips_mode, "the chips mode") && r.string(h.hysim_version, "the hysim version") &&
         r.string(h.device_name, "the device name");
}

bool readRecords(Reader& r, Recording& out) {
  const std::size_t start = r.at;
  const std::size_t body = r.bytes.size() - start;
  if (body < static_cast<std::size_t>(kRecordingEndBytes)) {
    return r.fail(start, "truncated: no end marker after " + std::to_string(body / kRecordBytes) + " whole records");
  }
  const std::size_t end_at = r.bytes.size() - kRecordingEndBytes;
  if (std::memcmp(r.bytes.data() + end_at, kEndMagic, 8) != 0) {
    const std::size_t whole = body / kRecordBytes;
    return r.fail(start + whole * kRecordBytes, "truncated: no end marker after " + std::to_string(whole) +
                                                    " whole records (the session did not finish)");
  }
  if ((end_at - start) % kRecordBytes != 0) {
    return r.fail(start + (end_at - start) / kRecordBytes * kRecordBytes, "partial record before the end marker");
  }
  const std::size_t count = (end_at - start) / kRecordBytes;
  out.states.resize(count);
  std::uint64_t checksum = kFnv64Offset;
  std::string reason;
  for (std::size_t i = 0; i < count; ++i, r.at += kRecordBytes) {
    const unsigned char* p = r.bytes.data() + r.at;
    if (!decodeRecord(p, out.states[i], reason)) return r.fail(r.at, "record " + std::to_string(i) + ": " + reason);
    if (i > 0 && out.states[i].state.time_s < out.states[i - 1].state.time_s) {
      return r.fail(r.at, "record " + std::to_string(i) + ": time goes backwards");
    }
    checksum = le::fnv1a64(checksum, p, kRecordBytes);
  }
  if (const std::uint64_t n = le::getU64(r.bytes.data() + end_at + 8); n != count) {
    return r.fail(end_at + 8, "the end marker counts " + std::to_string(n) + " records, the file holds " +
                                  std::to_string(count));
  }
  if (le::getU64(r.bytes.data() + end_at + 16) != checksum) {
    return r.fail(end_at + 16, "the records' checksum does not match the end marker");
  }
  return true;
}

// Read whole into memory, so bounded: 4 GiB is over six hours of 180-byte records at 1 kHz.
constexpr std::uintmax_t kMaxRecordingFileBytes = std::uintmax_t{4} << 30;

bool readWholeFile(const std::string& path, std::vector<unsigned char>& bytes, std::string& error) {
  if (Status s = checkInputFile(path, kMaxRecordingFileBytes, "recording"); !s.ok()) {
    error = s.error();
    return false;
  }
  std::error_code ec;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    error = path + ": cannot open";
    return false;
  }
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) {
    error = path + ": cannot read its size: " + ec.message();
    return false;
  }
  bytes.resize(size);
  if (size > 0 && !in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size))) {
    error = path + ": read error";
    return false;
  }
  return true;
}

}  // namespace

void encodeRecord(const DeviceState& s, bool attached, unsigned char* b) {
  le::putF64(b + kTime, s.time_s);
  putVector(b + kTip, s.pose.tip);
  for (int i = 0; i < 9; ++i) le::putF64(b + kRotation + 8 * i, s.pose.rotation.data()[i]);
  le::putF64(b + kExtension, s.pose.extension_mm);
  putVector(b + kVelocity, s.velocity_mm_s);
  putVector(b + kAngular, s.angular_velocity_rad_s);
  le::putF64(b + kExtensionVelocity, s.extension_velocity_mm_s);
  le::putU32(b + kButtons, s.buttons);
  b[kPedal] = s.pose.pedal ? 1 : 0;
  b[kFlags] = attached ? 1 : 0;
  le::putU16(b + kReserved, 0);
  le::putU32(b + kCheck, le::fnv1a32(b, kCheck));
}

bool decodeRecord(const unsigned char* b, RecordedState& out, std::string& reason) {
  if (le::getU32(b + kCheck) != le::fnv1a32(b, kCheck)) {
    reason = "damaged (its check does not match)";
    return false;
  }
  if (b[kPedal] > 1 || b[kFlags] > 1 || le::getU16(b + kReserved) != 0) {
    reason = "pedal, flags or reserved bytes hold values version 1 never writes";
    return false;
  }
  DeviceState& s = out.state;
  s.time_s = le::getF64(b + kTime);
  s.pose.tip = getVector(b + kTip);
  for (int i = 0; i < 9; ++i) s.pose.rotation.data()[i] = le::getF64(b + kRotation + 8 * i);
  s.pose.extension_mm = le::getF64(b + kExtension);
  s.velocity_mm_s = getVector(b + kVelocity);
  s.angular_velocity_rad_s = getVector(b + kAngular);
  s.extension_velocity_mm_s = le::getF64(b + kExtensionVelocity);
  s.buttons = le::getU32(b + kButtons);
  s.pose.pedal = b[kPedal] == 1;
  out.attached = b[kFlags] == 1;
  return plausible(s, reason);
}

RecordingWriter::~RecordingWriter() {
  if (file_ != nullptr) std::fclose(file_);
}

bool RecordingWriter::open(const std::string& path, const RecordingHeader& header, std::string& error) {
  if (file_ != nullptr) {
    error = "recording '" + path_ + "' is still open";
    return false;
  }
  for (const std::string* s : {&header.scene_path, &header.mesh_path, &header.chips_mode, &header.hysim_version,
                               &header.device_name}) {
    if (s->size() > static_cast<std::size_t>(kMaxRecordingString)) {
      error = path + ": a header string is longer than 4096 bytes";
      return false;
    }
  }
  // A folder cannot take the file: said now, not at the rename after the whole run.
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec) || path.empty() || path.back() == '/') {
    error = "cannot record into '" + path + "': it names a folder, not a file";
    return false;
  }
  path_ = path;
  const std::string tmp = path + ".tmp";
  file_ = std::fopen(tmp.c_str(), "wb");
  if (file_ == nullptr) {
    error = "cannot write '" + tmp + "': " + std::strerror(errno);
    return false;
  }
  stdio_buffer_.resize(1 << 20);  // about 5,800 records between writes
  std::setvbuf(file_, stdio_buffer_.data(), _IOFBF, stdio_buffer_.size());
  const std::vector<unsigned char> bytes = encodeHeader(header);
  write_failed_ = std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size();
  records_ = 0;
  checksum_ = kFnv64Offset;
  first_bad_.clear();
  return true;
}

void RecordingWriter::append(const DeviceState& state, bool attached) {
  if (file_ == nullptr) return;
  if (first_bad_.empty() && !plausible(state, first_bad_)) {
    first_bad_ = "record " + std::to_string(records_) + ": " + first_bad_;
  }
  std::array<unsigned char, kRecordBytes> bytes;
  encodeRecord(state, attached, bytes.data());
  checksum_ = le::fnv1a64(checksum_, bytes.data(), bytes.size());
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size()) write_failed_ = true;
  ++records_;
}

bool RecordingWriter::finish(std::string& error) {
  if (file_ == nullptr) {
    error = "recording '" + path_ + "' is not open";
    return false;
  }
  std::array<unsigned char, kRecordingEndBytes> end;
  std::memcpy(end.data(), kEndMagic, 8);
  le::putU64(end.data() + 8, records_);
  le::putU64(end.data() + 16, checksum_);
  if (std::fwrite(end.data(), 1, end.size(), file_) != end.size()) write_failed_ = true;
  const bool synced = std::fflush(file_) == 0 && fsync(fileno(file_)) == 0;  // on disk before the rename
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  const std::string tmp = path_ + ".tmp";
  if (write_failed_ || !synced || !closed) {
    error = "cannot write '" + tmp + "' (disk full?)";
    return false;
  }
  if (!first_bad_.empty()) {  // kept as .tmp: a replay could not take it
    error = tmp + ": " + first_bad_ + " (the device delivered a state no replay can take)";
    return false;
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path_, ec);
  if (ec) {
    error = "cannot move '" + tmp + "' to '" + path_ + "': " + ec.message();
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);  // nothing half-done is left behind
    return false;
  }
  return true;
}

void RecordingWriter::discard() {
  if (file_ == nullptr) return;
  std::fclose(file_);
  file_ = nullptr;
  std::error_code ec;
  std::filesystem::remove(path_ + ".tmp", ec);
}

bool readRecording(const std::string& path, Recording& out, std::string& error) {
  std::vector<unsigned char> bytes;
  if (!readWholeFile(path, bytes, error)) return false;
  return parseRecording(bytes, path, out, error);
}

bool parseRecording(const std::vector<unsigned char>& bytes, const std::string& path, Recording& out,
                    std::string& error) {
  Reader r{bytes, path, 0, error};
  return readHeader(r, out.header) && readRecords(r, out);
}

}  // namespace hysim::haptics
