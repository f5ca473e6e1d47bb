// Tests of the run recording (crunch/io/recording.h, docs/RECORDING.md): CRC-32, Chunk, a round
// trip of many records, the reader's errors for files that are not (good) recordings, and damage
// in the middle of a file: everything before it delivered, the damage named with file, record
// number and byte offset, nothing after. The writer's no-allocation check is in
// io_ring_alloc_test.cc (own executable: it replaces operator new).
#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "crunch/io/recording.h"
#include "support/temp_dir.h"

using crunch::io::Chunk;
using crunch::io::kMaxChunkBytes;
using crunch::io::kRecordHeaderBytes;
using crunch::io::kRecordingHeaderBytes;
using crunch::io::MarkKind;
using crunch::io::RecordingReader;
using crunch::io::RecordingWriter;
using crunch::io::StreamId;

namespace {

std::vector<std::uint8_t> readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
void writeAll(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

struct Rec {
  StreamId stream;
  std::uint64_t t_ns;
  std::vector<std::uint8_t> bytes;
};

// `n` records of all three streams, sizes 0..kMaxChunkBytes (both ends included).
std::vector<Rec> makeRecords(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<Rec> out;
  for (int i = 0; i < n; ++i) {
    Rec r;
    const int kind = i % 5;
    if (kind == 4) {
      r.stream = StreamId::kMark;
      r.bytes = {static_cast<std::uint8_t>(1 + i % 3)};
    } else {
      r.stream = kind % 2 == 0 ? StreamId::kBridge : StreamId::kCreate;
      std::size_t size = rng() % (kMaxChunkBytes + 1);
      if (i == 1) size = 0;
      if (i == 2) size = kMaxChunkBytes;
      r.bytes.resize(size);
      for (auto& b : r.bytes) b = static_cast<std::uint8_t>(rng());
    }
    r.t_ns = 1'000'000'000ull * 3600 + 500'000ull * static_cast<std::uint64_t>(i) + (rng() % 100);
    out.push_back(std::move(r));
  }
  return out;
}

// Writes `recs` to `path`; returns each record's byte offset in the file.
std::vector<std::uint64_t> writeRecording(const std::string& path, const std::vector<Rec>& recs,
                                          const std::string& meta = "{\"program\":\"test\"}") {
  auto w = RecordingWriter::create(path, meta);
  REQUIRE(w.ok());
  std::vector<std::uint64_t> offsets;
  std::uint64_t at = kRecordingHeaderBytes + meta.size();
  for (const Rec& r : recs) {
    offsets.push_back(at);
    if (r.stream == StreamId::kMark) {
      REQUIRE(w.value()->mark(static_cast<MarkKind>(r.bytes[0]), r.t_ns).ok());
    } else {
      REQUIRE(w.value()->write(r.stream, r.t_ns, r.bytes).ok());
    }
    at += kRecordHeaderBytes + r.bytes.size() + 4;
  }
  REQUIRE(w.value()->close().ok());
  return offsets;
}

// Reads until kEnd or kDamaged; returns what ended it, `got` the records delivered.
RecordingReader::Next readAllRecords(RecordingReader& r, std::vector<Rec>& got) {
  Chunk c;
  for (;;) {
    const RecordingReader::Next n = r.next(c);
    if (n != RecordingReader::Next::kRecord) return n;
    REQUIRE(c.size <= kMaxChunkBytes);
    got.push_back({c.stream, c.t_ns, {c.data().begin(), c.data().end()}});
  }
}

bool same(const Rec& a, const Rec& b) {
  return a.stream == b.stream && a.t_ns == b.t_ns && a.bytes == b.bytes;
}

void put32(std::vector<std::uint8_t>& v, std::size_t at, std::uint32_t x) {
  for (int i = 0; i < 4; ++i) v[at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(x >> (8 * i));
}
void rehashHeader(std::vector<std::uint8_t>& v) {
  put32(v, 28, crunch::io::crc32({v.data(), 28}));
}

std::string openError(const std::string& path) {
  auto r = RecordingReader::open(path);
  REQUIRE_FALSE(r.ok());
  return r.error().message;
}

}  // namespace

using Catch::Matchers::Contains;

TEST_CASE("Recording: crc32 is zlib's CRC-32", "[io][recording]") {
  const std::string s = "123456789";
  const std::span<const std::uint8_t> bytes(reinterpret_cast<const std::uint8_t*>(s.data()), s.size());
  CHECK(crunch::io::crc32(bytes) == 0xCBF43926u);
  CHECK(crunch::io::crc32({}) == 0u);
  // Continuing a CRC over a second piece equals the CRC of the whole.
  CHECK(crunch::io::crc32(bytes.subspan(4), crunch::io::crc32(bytes.subspan(0, 4))) == 0xCBF43926u);
  const std::uint8_t a = 'a';
  CHECK(crunch::io::crc32({&a, 1}) == 0xE8B7BE43u);
}

TEST_CASE("Recording: Chunk::assign copies at most kMaxChunkBytes", "[io][recording]") {
  std::vector<std::uint8_t> big(kMaxChunkBytes + 100);
  for (std::size_t i = 0; i < big.size(); ++i) big[i] = static_cast<std::uint8_t>(i * 7);
  Chunk c;
  CHECK(c.assign(StreamId::kCreate, 42, big) == kMaxChunkBytes);
  CHECK(c.size == kMaxChunkBytes);
  CHECK(c.stream == StreamId::kCreate);
  CHECK(c.t_ns == 42);
  CHECK(std::equal(c.data().begin(), c.data().end(), big.begin()));
  const std::vector<std::uint8_t> small = {1, 2, 3};
  CHECK(c.assign(StreamId::kBridge, 7, small) == 3);
  CHECK(c.size == 3);
  CHECK(std::vector<std::uint8_t>(c.data().begin(), c.data().end()) == small);
  CHECK(c.assign(StreamId::kMark, 8, {}) == 0);
  CHECK(c.data().empty());
}

TEST_CASE("Recording: many records of all three streams round-trip with the metadata",
          "[io][recording]") {
  TempDir dir;
  const std::string path = dir.file("run.crec");
  const std::vector<Rec> recs = makeRecords(600, 11);  // ~1 MB: several writer buffers
  const std::string meta = "{\"devices\":{\"bridge\":\"1d50:6142\"},\"program\":\"crunchhost\","
                           "\"note\":\"\xC3\xA9t\xC3\xA9\"}";
  const std::uint64_t t0 = static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(
          std::chrono::system_clock::now().time_since_epoch()).count());
  auto w = RecordingWriter::create(path, meta);
  REQUIRE(w.ok());
  Chunk chunk;
  for (const Rec& r : recs) {
    if (r.stream == StreamId::kMark) {
      REQUIRE(w.value()->mark(static_cast<MarkKind>(r.bytes[0]), r.t_ns).ok());
    } else {
      chunk.assign(r.stream, r.t_ns, r.bytes);
      REQUIRE(w.value()->write(chunk).ok());  // the Chunk overload
    }
  }
  CHECK(w.value()->records() == recs.size());
  CHECK(w.value()->path() == path);
  REQUIRE(w.value()->close().ok());
  const std::uint64_t written = w.value()->bytesWritten();
  CHECK(written == std::filesystem::file_size(path));

  auto r = RecordingReader::open(path);
  REQUIRE(r.ok());
  CHECK(r.value()->metadata() == meta);
  // The start time is the wall clock at create().
  CHECK(r.value()->startUnixNs() + 1'000'000'000ull >= t0);
  CHECK(r.value()->startUnixNs() <= t0 + 60'000'000'000ull);
  std::vector<Rec> got;
  CHECK(readAllRecords(*r.value(), got) == RecordingReader::Next::kEnd);
  CHECK(r.value()->damage().empty());
  CHECK(r.value()->records() == recs.size());
  REQUIRE(got.size() == recs.size());
  for (std::size_t i = 0; i < recs.size(); ++i) {
    INFO("record " << i);
    CHECK(same(got[i], recs[i]));
  }
  // Marks carry their kind.
  CHECK(got[4].stream == StreamId::kMark);
  CHECK(got[4].bytes.size() == 1);
  // After the end, next() keeps saying so.
  Chunk c;
  CHECK(r.value()->next(c) == RecordingReader::Next::kEnd);
}

TEST_CASE("Recording: a recording with no records ends cleanly", "[io][recording]") {
  TempDir dir;
  const std::string path = dir.file("empty.crec");
  {
    auto w = RecordingWriter::create(path, "");
    REQUIRE(w.ok());
  }  // the destructor closes
  CHECK(std::filesystem::file_size(path) == kRecordingHeaderBytes);
  auto r = RecordingReader::open(path);
  REQUIRE(r.ok());
  CHECK(r.value()->metadata().empty());
  Chunk c;
  CHECK(r.value()->next(c) == RecordingReader::Next::kEnd);
  CHECK(r.value()->records() == 0);
}

TEST_CASE("Recording: flush() makes the records so far readable while the writer stays open",
          "[io][recording]") {
  TempDir dir;
  const std::string path = dir.file("live.crec");
  auto w = RecordingWriter::create(path, "{}");
  REQUIRE(w.ok());
  const std::vector<std::uint8_t> bytes = {1, 2, 3, 4};
  for (int i = 0; i < 3; ++i) REQUIRE(w.value()->write(StreamId::kBridge, i, bytes).ok());
  REQUIRE(w.value()->flush().ok());
  auto r = RecordingReader::open(path);
  REQUIRE(r.ok());
  std::vector<Rec> got;
  CHECK(readAllRecords(*r.value(), got) == RecordingReader::Next::kEnd);
  CHECK(got.size() == 3);
  CHECK(w.value()->close().ok());
}

TEST_CASE("Recording: the reader refuses files that are not good recordings, naming the path",
          "[io][recording]") {
  TempDir dir;
  const std::string good = dir.file("good.crec");
  writeRecording(good, makeRecords(3, 1), "{\"a\":1}");
  const std::vector<std::uint8_t> bytes = readAll(good);
  REQUIRE(RecordingReader::open(good).ok());

  SECTION("missing file") {
    const std::string path = dir.file("nope.crec");
    const std::string e = openError(path);
    CHECK_THAT(e, Contains(path));
    CHECK_THAT(e, Contains("cannot open"));
  }
  SECTION("shorter than the header") {
    const std::string path = dir.file("short.crec");
    writeAll(path, {bytes.begin(), bytes.begin() + 20});
    const std::string e = openError(path);
    CHECK_THAT(e, Contains(path));
    CHECK_THAT(e, Contains("not a recording"));
  }
  SECTION("not a recording: bad magic") {
    const std::string path = dir.file("other.json");
    std::vector<std::uint8_t> v = bytes;
    v[0] = '{';
    rehashHeader(v);  // a valid CRC does not make it a recording
    writeAll(path, v);
    const std::string e = openError(path);
    CHECK_THAT(e, Contains(path));
    CHECK_THAT(e, Contains("not a crunchhost recording"));
  }
  SECTION("damaged header: CRC mismatch") {
    const std::string path = dir.file("hdr.crec");
    std::vector<std::uint8_t> v = bytes;
    v[17] ^= 0x10;  // a bit of the start time
    writeAll(path, v);
    const std::string e = openError(path);
    CHECK_THAT(e, Contains(path));
    CHECK_THAT(e, Contains("header CRC mismatch"));
  }
  SECTION("a newer format version") {
    const std::string path = dir.file("v2.crec");
    std::vector<std::uint8_t> v = bytes;
    v[8] = static_cast<std::uint8_t>(crunch::io::kRecordingVersion + 1);
    v[9] = 0;
    rehashHeader(v);
    writeAll(path, v);
    const std::string e = openError(path);
    CHECK_THAT(e, Contains(path));
    CHECK_THAT(e, Contains("version " + std::to_string(crunch::io::kRecordingVersion + 1)));
  }
  SECTION("a bit flip in the metadata that leaves valid JSON (issue 16)") {
    const std::string path = dir.file("meta_flip.crec");
    std::vector<std::uint8_t> v = bytes;
    v[kRecordingHeaderBytes + 5] ^= 0x02;  // {"a":1} -> {"a":3}: still JSON, another setting
    writeAll(path, v);
    const std::string e = openError(path);
    CHECK_THAT(e, Contains(path));
    CHECK_THAT(e, Contains("metadata CRC mismatch"));
  }
  SECTION("damaged length fields with a valid CRC") {
    const std::string path = dir.file("len.crec");
    std::vector<std::uint8_t> v = bytes;
    put32(v, 12, 2u << 20);  // 2 MiB of metadata claimed
    rehashHeader(v);
    writeAll(path, v);
    const std::string e = openError(path);
    CHECK_THAT(e, Contains(path));
    CHECK_THAT(e, Contains("damaged"));
  }
  SECTION("truncated inside the metadata") {
    const std::string path = dir.file("meta.crec");
    writeAll(path, {bytes.begin(), bytes.begin() + kRecordingHeaderBytes + 3});
    const std::string e = openError(path);
    CHECK_THAT(e, Contains(path));
    CHECK_THAT(e, Contains("metadata"));
    CHECK_THAT(e, Contains("truncated"));
  }
}

TEST_CASE("Recording: damage mid-file delivers the records before it and names where it is",
          "[io][recording]") {
  TempDir dir;
  const std::string good = dir.file("good.crec");
  const std::vector<Rec> recs = makeRecords(10, 5);
  const std::vector<std::uint64_t> off = writeRecording(good, recs);
  const std::vector<std::uint8_t> bytes = readAll(good);
  constexpr std::size_t kBad = 6;  // 0-based index of the damaged record: record 7 in messages
  REQUIRE(recs[kBad].bytes.size() >= 8);  // a payload to cut and flip in
  const std::size_t at = static_cast<std::size_t>(off[kBad]);
  const std::size_t size = recs[kBad].bytes.size();

  std::vector<std::uint8_t> v = bytes;
  std::string what;
  SECTION("truncated in a record header") {
    v.resize(at + 5);
    what = "ends inside a record header";
  }
  SECTION("truncated in a payload") {
    v.resize(at + kRecordHeaderBytes + size / 2);
    what = "ends inside a record";
  }
  SECTION("truncated in the CRC") {
    v.resize(at + kRecordHeaderBytes + size + 2);
    what = "ends inside a record";
  }
  SECTION("a flipped payload byte") {
    v[at + kRecordHeaderBytes + size / 3] ^= 0x01;
    what = "CRC mismatch";
  }
  SECTION("a flipped time-stamp byte") {
    v[at + 7] ^= 0x80;
    what = "CRC mismatch";
  }
  SECTION("a bad stream id") {
    v[at] = 9;
    what = "unknown stream";
  }
  SECTION("a non-zero reserved byte") {
    v[at + 1] = 1;
    what = "unknown stream";
  }
  SECTION("a size larger than a chunk") {
    v[at + 2] = 0xFF;
    v[at + 3] = 0xFF;
    what = "too large";
  }
  const std::string path = dir.file("damaged.crec");
  writeAll(path, v);
  auto r = RecordingReader::open(path);
  REQUIRE(r.ok());
  std::vector<Rec> got;
  CHECK(readAllRecords(*r.value(), got) == RecordingReader::Next::kDamaged);
  REQUIRE(got.size() == kBad);  // exactly the records before the damage
  for (std::size_t i = 0; i < kBad; ++i) CHECK(same(got[i], recs[i]));
  CHECK(r.value()->records() == kBad);
  const std::string& d = r.value()->damage();
  CHECK_THAT(d, Contains(path));
  CHECK_THAT(d, Contains("record " + std::to_string(kBad + 1) + " at byte " + std::to_string(at)));
  CHECK_THAT(d, Contains(what));
  // Nothing after the damage, however often asked.
  Chunk c;
  CHECK(r.value()->next(c) == RecordingReader::Next::kDamaged);
  CHECK(r.value()->next(c) == RecordingReader::Next::kDamaged);
  CHECK(r.value()->damage() == d);
}

TEST_CASE("Recording: a file cut at every byte of its last record replays the others",
          "[io][recording]") {
  TempDir dir;
  const std::string good = dir.file("good.crec");
  std::vector<Rec> recs = makeRecords(4, 9);
  recs[3].stream = StreamId::kCreate;
  recs[3].bytes = {9, 8, 7, 6, 5};
  const std::vector<std::uint64_t> off = writeRecording(good, recs);
  const std::vector<std::uint8_t> bytes = readAll(good);
  for (std::size_t cut = static_cast<std::size_t>(off[3]) + 1; cut < bytes.size(); ++cut) {
    INFO("cut at " << cut);
    const std::string path = dir.file("cut.crec");
    writeAll(path, {bytes.begin(), bytes.begin() + static_cast<long>(cut)});
    auto r = RecordingReader::open(path);
    REQUIRE(r.ok());
    std::vector<Rec> got;
    CHECK(readAllRecords(*r.value(), got) == RecordingReader::Next::kDamaged);
    CHECK(got.size() == 3);
    CHECK_THAT(r.value()->damage(), Contains("record 4 at byte " + std::to_string(off[3])));
    CHECK_THAT(r.value()->damage(), Contains("truncated"));
  }
}

TEST_CASE("Recording: the writer's errors name the file", "[io][recording]") {
  TempDir dir;
  SECTION("a path that cannot be created") {
    const std::string path = dir.file("no/such/dir/run.crec");
    auto w = RecordingWriter::create(path, "{}");
    REQUIRE_FALSE(w.ok());
    CHECK_THAT(w.error().message, Contains(path));
    CHECK_THAT(w.error().message, Contains("cannot create"));
  }
  SECTION("a directory") {
    auto w = RecordingWriter::create(dir.path().string(), "{}");
    REQUIRE_FALSE(w.ok());
    CHECK_THAT(w.error().message, Contains(dir.path().string()));
  }
  SECTION("metadata over 1 MiB") {
    const std::string path = dir.file("big.crec");
    auto w = RecordingWriter::create(path, std::string((1u << 20) + 1, 'x'));
    REQUIRE_FALSE(w.ok());
    CHECK_THAT(w.error().message, Contains(path));
  }
  SECTION("a full device") {
    if (!std::filesystem::exists("/dev/full")) {
      WARN("no /dev/full here: the write-failure case is not checked");
      return;
    }
    auto w = RecordingWriter::create("/dev/full", "{}");
    REQUIRE_FALSE(w.ok());
    CHECK_THAT(w.error().message, Contains("/dev/full"));
    CHECK_THAT(w.error().message, Contains("write failed"));
  }
}

TEST_CASE("Recording: write() and mark() after close() are errors, close() twice is fine",
          "[io][recording]") {
  TempDir dir;
  const std::string path = dir.file("closed.crec");
  auto w = RecordingWriter::create(path, "{}");
  REQUIRE(w.ok());
  const std::vector<std::uint8_t> bytes = {1, 2, 3};
  REQUIRE(w.value()->write(StreamId::kBridge, 1, bytes).ok());
  REQUIRE(w.value()->close().ok());
  const crunch::Status s = w.value()->write(StreamId::kBridge, 2, bytes);
  REQUIRE_FALSE(s.ok());
  CHECK_THAT(s.error().message, Contains(path));
  CHECK_THAT(s.error().message, Contains("after close"));
  CHECK_FALSE(w.value()->mark(MarkKind::kWhiskEnd, 3).ok());
  CHECK(w.value()->close().ok());
  CHECK(w.value()->flush().ok());
  CHECK(w.value()->records() == 1);
  // The file holds the one record written before close().
  auto r = RecordingReader::open(path);
  REQUIRE(r.ok());
  std::vector<Rec> got;
  CHECK(readAllRecords(*r.value(), got) == RecordingReader::Next::kEnd);
  CHECK(got.size() == 1);
}

TEST_CASE("Recording: a version-1 file (no metadata CRC) is still read, and said unprotected",
          "[io][recording]") {
  TempDir dir;
  const std::string path = dir.file("v1.crec");
  const std::vector<Rec> recs = makeRecords(5, 3);
  writeRecording(path, recs, "{\"a\":1}");
  {
    auto now = RecordingReader::open(path);
    REQUIRE(now.ok());
    CHECK(now.value()->formatVersion() == crunch::io::kRecordingVersion);
    CHECK(now.value()->metadataProtected());
  }
  // What version 1 wrote: version 1, bytes 24..27 zero (reserved), the header CRC over them.
  std::vector<std::uint8_t> v = readAll(path);
  v[8] = 1;
  v[9] = 0;
  put32(v, 24, 0);
  rehashHeader(v);
  writeAll(path, v);
  auto old = RecordingReader::open(path);
  REQUIRE(old.ok());
  CHECK(old.value()->formatVersion() == 1);
  CHECK_FALSE(old.value()->metadataProtected());
  CHECK(old.value()->metadata() == "{\"a\":1}");
  std::vector<Rec> got;
  CHECK(readAllRecords(*old.value(), got) == RecordingReader::Next::kEnd);
  CHECK(got.size() == recs.size());
}
