#pragma once
// Recordings: per simulation step, exactly the device state the simulation consumed, so that
// feeding the same states back into the same scene reproduces the run to the last bit. The
// format (little-endian, fixed-size records, each with its own check) is documented in
// haptics/README.md.
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "hysim/haptics/device.hpp"

namespace hysim::haptics {

inline constexpr std::uint32_t kRecordingVersion = 1;
inline constexpr int kRecordBytes = 180;      // one DeviceState with flags and check
inline constexpr int kRecordingEndBytes = 24;  // end marker, record count, checksum
inline constexpr int kMaxRecordingString = 4096;

struct RecordingHeader {
  std::uint64_t scene_hash = 0;  // content hash of the scene and the files it loads
  double dt_s = 0.0;             // the scene's step
  std::string scene_path;        // as given to the run
  std::string mesh_path;         // a run's --mesh override; empty: the scene's
  std::string chips_mode;        // a run's --chips override; empty: the scene's
  std::string hysim_version;
  std::string device_name;
};

// One consumed device state. `attached`: the simulation took a new device at this record
// (Simulation::setDevice), which resets the tool's coupling; replay must do the same.
struct RecordedState {
  DeviceState state;
  bool attached = false;
};

struct Recording {
  RecordingHeader header;
  std::vector<RecordedState> states;  // the first one is the device's state before step 1
};

// Writes a recording while a session runs. The file is written as PATH.tmp and renamed to
// PATH by finish(), so an older recording of the same name is never half-overwritten and a
// session that dies leaves a .tmp without an end marker (read as truncated, never as a
// shorter whole session). append() does not allocate: it encodes into a fixed buffer and
// writes through a stdio buffer.
class RecordingWriter {
 public:
  RecordingWriter() = default;
  ~RecordingWriter();  // a writer never finished removes nothing and renames nothing
  RecordingWriter(const RecordingWriter&) = delete;
  RecordingWriter& operator=(const RecordingWriter&) = delete;

  // Opens PATH.tmp and writes the header; false with `error` set when it cannot.
  bool open(const std::string& path, const RecordingHeader& header, std::string& error);
  bool isOpen() const { return file_ != nullptr; }
  void append(const DeviceState& state, bool attached);
  // Writes the end marker, flushes to disk, renames PATH.tmp to PATH. A state that no replay
  // could take (not finite, not a rotation; a device's fault) fails it, naming the record,
  // and leaves PATH.tmp.
  bool finish(std::string& error);
  // Closes and removes PATH.tmp (a run that failed before it began).
  void discard();
  std::uint64_t records() const { return records_; }
  const std::string& path() const { return path_; }

 private:
  std::FILE* file_ = nullptr;
  std::string path_;
  std::uint64_t records_ = 0;
  std::uint64_t checksum_ = 0;  // FNV-1a 64 over every record's bytes
  bool write_failed_ = false;
  std::string first_bad_;  // the first implausible record and why
  std::vector<char> stdio_buffer_;
};

// Reads a whole recording. Errors name the file and the byte offset: a bad header field, a
// record that fails its check or holds an impossible state, a truncated file (no end marker,
// or a partial record), trailing bytes, a record count or checksum that disagrees.
bool readRecording(const std::string& path, Recording& out, std::string& error);
// The same over a file's bytes already in memory (fuzzing, tests); `path` names them in messages.
bool parseRecording(const std::vector<unsigned char>& bytes, const std::string& path, Recording& out,
                    std::string& error);

// The bytes of one record and back (exposed for tests). decodeRecord returns false with a
// reason when the record's check fails or its state is impossible.
void encodeRecord(const DeviceState& state, bool attached, unsigned char* bytes);
bool decodeRecord(const unsigned char* bytes, RecordedState& out, std::string& reason);

}  // namespace hysim::haptics
