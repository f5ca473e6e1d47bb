// Recording of a robot run's raw input, for `crunchhost --replay FILE` (docs/RECORDING.md is the
// format's definition). What a run reads from the world is recorded as it was read, in the order
// the control loop handled it: the USB bridge's byte chunks, the Create's serial bytes, and the
// control loop's marks (where one body whisk ended). Replaying the file through the same decoder,
// OI parser, signal pipeline and mapper gives the same map, bit for bit.
//
// File: a 32-byte header (magic "CRUNCHRC", version, metadata length, start time, the metadata's
// CRC-32 (version 2; 0 in version 1), the header's CRC-32), the metadata (UTF-8 JSON: devices,
// program version, models, settings), then records of
//   u8 stream | u8 0 | u16 size | u64 t_ns | size bytes | u32 CRC-32 of the 12 + size before it
// all little-endian. t_ns is CLOCK_MONOTONIC when the bytes arrived, as the host saw it.
//
// Chunk is also what travels through the SpscRing from the USB thread (spsc_ring.h): one type,
// so the bytes recorded are exactly the bytes decoded.
//
// Errors name the file and say what is wrong and where (byte offset, record number). A reader
// stops at the first damage — a record cut short by the end of the file (a run killed while
// writing) or one whose CRC, stream or size is wrong — and reports it; everything before is
// delivered, nothing after (a damaged size field leaves no trustworthy way to find the next
// record).
//
// Allocation: the writer's buffer is allocated at create(); write() does not allocate. The
// reader allocates at open() only. Thread-safety: none; one thread owns a writer or reader.
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "crunch/core/result.h"

namespace crunch::io {

enum class StreamId : std::uint8_t {
  kBridge = 1,  // bytes of the USB bridge's bulk IN transfers (docs/protocol.md frames)
  kCreate = 2,  // bytes received from the Create's serial port (OI sensor stream)
  kMark = 3,    // a control-loop event; payload[0] is a MarkKind
};

enum class MarkKind : std::uint8_t {
  kWhiskEnd = 1,           // one body whisk ended: its contacts form one group for the mapper
  kBridgeReconnected = 2,  // the USB bridge came back: partial frames and baselines forgotten
  kWhiskStart = 3,         // a body whisk's sweep begins: contacts from here on are its own
};

inline constexpr std::size_t kMaxChunkBytes = 4096;

// A piece of one input stream as it arrived. Fixed size: lives in ring slots without allocation.
struct Chunk {
  StreamId stream = StreamId::kBridge;
  std::uint16_t size = 0;
  std::uint64_t t_ns = 0;
  std::array<std::uint8_t, kMaxChunkBytes> bytes{};

  std::span<const std::uint8_t> data() const { return {bytes.data(), size}; }
  // Copies up to kMaxChunkBytes of `src`; returns how many were copied.
  std::size_t assign(StreamId id, std::uint64_t t, std::span<const std::uint8_t> src);
};

// Version 2 (issue 16) adds the metadata's own CRC-32 at header bytes 24..27, so a bit flip in
// the settings that leaves valid JSON is found; version 1 files are still read, and said to be
// unprotected (RecordingReader::metadataProtected).
inline constexpr std::uint16_t kRecordingVersion = 2;
inline constexpr std::size_t kRecordingHeaderBytes = 32;
inline constexpr std::size_t kRecordHeaderBytes = 12;

// CRC-32 (IEEE 802.3, zlib's): the checksum of the header and of every record.
std::uint32_t crc32(std::span<const std::uint8_t> bytes, std::uint32_t crc = 0);

// CLOCK_MONOTONIC in nanoseconds.
std::uint64_t monotonicNs();

class RecordingWriter {
 public:
  // Creates (truncates) `path` and writes the header with `metadata_json`. Errors name the path.
  static Result<std::unique_ptr<RecordingWriter>> create(const std::string& path,
                                                         const std::string& metadata_json);
  ~RecordingWriter();
  RecordingWriter(const RecordingWriter&) = delete;
  RecordingWriter& operator=(const RecordingWriter&) = delete;

  // Appends one record (buffered). size <= kMaxChunkBytes (asserted). An Error names the file.
  Status write(StreamId stream, std::uint64_t t_ns, std::span<const std::uint8_t> bytes);
  Status write(const Chunk& chunk) { return write(chunk.stream, chunk.t_ns, chunk.data()); }
  Status mark(MarkKind kind, std::uint64_t t_ns);
  // Writes the buffer out and fsyncs: what is written survives a crash after this returns.
  Status flush();
  // flush() and close; later calls do nothing.
  Status close();

  const std::string& path() const { return path_; }
  std::uint64_t records() const { return records_; }
  std::uint64_t bytesWritten() const { return bytes_; }

 private:
  RecordingWriter(std::string path, int fd);
  Status writeOut();
  std::string path_;
  int fd_ = -1;
  std::vector<std::uint8_t> buffer_;  // reserved at create(); flushed when it would overflow
  std::uint64_t records_ = 0;
  std::uint64_t bytes_ = 0;
};

class RecordingReader {
 public:
  enum class Next {
    kRecord,     // `out` holds the next record
    kEnd,        // the file ended cleanly after the last record
    kDamaged,    // damage at damage(); nothing more is read
  };

  // Opens and checks the header (magic, version, header CRC, metadata length) and, from version
  // 2, the metadata's CRC. Errors name the path and what is wrong: not a recording, a newer
  // version, a damaged header, damaged metadata.
  static Result<std::unique_ptr<RecordingReader>> open(const std::string& path);
  ~RecordingReader();
  RecordingReader(const RecordingReader&) = delete;
  RecordingReader& operator=(const RecordingReader&) = delete;

  Next next(Chunk& out);

  const std::string& metadata() const { return metadata_; }
  std::uint16_t formatVersion() const { return version_; }
  // Whether the metadata carries its own CRC (version 2 on); a version-1 file's metadata could
  // be damaged without the reader knowing.
  bool metadataProtected() const { return version_ >= 2; }
  std::uint64_t startUnixNs() const { return start_unix_ns_; }
  std::uint64_t records() const { return records_; }
  // What the damage is and where ("recording F: record 1234 at byte 56789: CRC mismatch"),
  // empty unless next() returned kDamaged.
  const std::string& damage() const { return damage_; }

 private:
  RecordingReader(std::string path, std::FILE* file);
  Next fail(const std::string& why);
  std::string path_;
  std::FILE* file_ = nullptr;
  std::string metadata_;
  std::uint16_t version_ = 0;
  std::uint64_t start_unix_ns_ = 0;
  std::uint64_t offset_ = 0;
  std::uint64_t records_ = 0;
  std::string damage_;
  bool done_ = false;
};

}  // namespace crunch::io
