// libFuzzer target for the recording reader (crunch/io/recording.h, docs/RECORDING.md): the input
// is written to a temporary file as it is and read with RecordingReader until kEnd or kDamaged.
// Byte 0 of the input, if bit 0 is set, selects a "repair" mode that rewrites the metadata's
// CRC (bytes 24..27, format version 2, when the metadata length fits the input) and the file
// header's CRC (bytes 28..31) so the fuzzer gets past open() and into the records without
// guessing them.
// Checks, beyond "no crash, no sanitizer report":
//   - open() either succeeds or gives an error naming the file;
//   - no record is larger than kMaxChunkBytes, and its stream is 1..3;
//   - the records delivered plus their framing never go past the end of the file;
//   - kDamaged comes with a damage() naming the file and the record number that follows the
//     last one delivered; kEnd with no damage; after either, next() keeps returning it.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "crunch/io/recording.h"
#include "fuzz_check.h"

using crunch::io::Chunk;
using crunch::io::RecordingReader;

namespace {

using fuzz::check;

// One scratch file per process, removed at exit (a plain array: it outlives every destructor).
char g_path[64] = {};
void removeTemp() { std::remove(g_path); }
const char* tempPath() {
  if (g_path[0] == 0) {
    std::snprintf(g_path, sizeof g_path, "/tmp/crunch_recording_fuzz_%d.crec", static_cast<int>(::getpid()));
    std::atexit(removeTemp);
  }
  return g_path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::uint8_t> file(data, data + size);
  if (size >= crunch::io::kRecordingHeaderBytes && (data[0] & 1u) != 0) {
    // Repair mode: keep the real magic if the input starts with it, and correct CRCs.
    const std::size_t meta = static_cast<std::size_t>(file[12]) | (std::size_t{file[13]} << 8) |
                             (std::size_t{file[14]} << 16) | (std::size_t{file[15]} << 24);
    if (meta <= size - crunch::io::kRecordingHeaderBytes) {
      const std::uint32_t mcrc =
          crunch::io::crc32({file.data() + crunch::io::kRecordingHeaderBytes, meta});
      for (int i = 0; i < 4; ++i) file[24 + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(mcrc >> (8 * i));
    }
    const std::uint32_t crc = crunch::io::crc32({file.data(), 28});
    for (int i = 0; i < 4; ++i) file[28 + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(crc >> (8 * i));
  }
  const std::string path = tempPath();
  {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    check(f != nullptr);
    check(file.empty() || std::fwrite(file.data(), 1, file.size(), f) == file.size());
    check(std::fclose(f) == 0);
  }

  auto opened = RecordingReader::open(path);
  if (!opened.ok()) {
    check(opened.error().message.find(path) != std::string::npos);
    return 0;
  }
  RecordingReader& r = *opened.value();
  check(r.metadata().size() + crunch::io::kRecordingHeaderBytes <= file.size());

  static Chunk chunk;  // 4 KiB; reused
  std::uint64_t consumed = crunch::io::kRecordingHeaderBytes + r.metadata().size();
  std::uint64_t records = 0;
  RecordingReader::Next n;
  while ((n = r.next(chunk)) == RecordingReader::Next::kRecord) {
    check(chunk.size <= crunch::io::kMaxChunkBytes);
    const auto s = static_cast<std::uint8_t>(chunk.stream);
    check(s >= 1 && s <= 3);
    consumed += crunch::io::kRecordHeaderBytes + chunk.size + 4;
    check(consumed <= file.size());
    ++records;
    check(r.records() == records);
  }
  if (n == RecordingReader::Next::kEnd) {
    check(r.damage().empty());
    check(consumed == file.size());  // a clean end is the end of the file
  } else {
    check(n == RecordingReader::Next::kDamaged);
    check(r.damage().find(path) != std::string::npos);
    check(r.damage().find("record " + std::to_string(records + 1) + " at byte " +
                          std::to_string(consumed)) != std::string::npos);
  }
  check(r.next(chunk) == n);
  check(r.next(chunk) == n);
  return 0;
}
