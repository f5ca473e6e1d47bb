// Proves the data paths of issue 5 allocate nothing after set-up: the SpscRing (tryPush, tryPop,
// drain), the SampleAssembler (push), the RecordingWriter (write, mark, and the buffer flushes
// in between, after create()) and the RecordingReader (next() on a good file, after open()).
// Its own executable: support/count_allocations.h replaces the global operator new.
#include <catch2/catch.hpp>

#include <cstdint>
#include <memory>
#include <vector>

#include "crunch/io/recording.h"
#include "crunch/io/sample_assembler.h"
#include "crunch/io/spsc_ring.h"
#include "support/count_allocations.h"
#include "support/temp_dir.h"

using namespace crunch::io;

TEST_CASE("SpscRing: tryPush, tryPop and drain allocate nothing", "[io][ring][alloc]") {
  auto ring = std::make_unique<SpscRing<Chunk>>(16);  // the slots: allocated here, once
  Chunk in, out;
  const std::vector<std::uint8_t> bytes(300, 0xAB);
  in.assign(StreamId::kBridge, 1, bytes);
  std::uint64_t sum = 0;
  const long long before = g_allocations;
  for (int round = 0; round < 1000; ++round) {
    for (int i = 0; i < 20; ++i) ring->tryPush(in);  // 4 of them refused: full
    for (int i = 0; i < 5; ++i) ring->tryPop(out);
    ring->drain([&](const Chunk& c) { sum += c.size; });
  }
  const long long after = g_allocations;
  CHECK(after == before);
  CHECK(ring->dropped() == 4000);
  CHECK(sum == 11000u * 300u);
}

TEST_CASE("SampleAssembler: push allocates nothing, gaps and silent boards included",
          "[io][assembler][alloc]") {
  SampleAssembler a;
  int samples = 0;
  auto sink = [&](const crunch::signal::SampleFrame&) { ++samples; };
  const long long before = g_allocations;
  for (int t = 0; t < 5000; ++t) {
    for (int b = 0; b < 5; ++b) {  // board 4 is unmapped
      if (b == 2 && t % 1000 > 900) continue;  // board 2 silent for 99 ticks at a time
      DecodedFrame d;
      d.frame.board = static_cast<std::uint8_t>(b);
      d.frame.alpha = static_cast<std::uint16_t>(t);
      d.frames_lost = (b == 2 && t % 1000 == 0 && t > 0) ? 99 : 0;
      a.push(d, sink);
    }
  }
  const long long after = g_allocations;
  CHECK(after == before);
  CHECK(samples + a.queued(0) == 5000);  // board 2 is silent at the end: the rest queued
  CHECK(a.counters().silent_fills > 0);
}

TEST_CASE("RecordingWriter: write and mark allocate nothing after create",
          "[io][recording][alloc]") {
  TempDir dir;
  auto w = RecordingWriter::create(dir.file("run.crec"), "{\"a\":1}");
  REQUIRE(w.ok());
  RecordingWriter& writer = *w.value();
  Chunk c;
  const std::vector<std::uint8_t> bytes(kMaxChunkBytes, 0x5A);
  c.assign(StreamId::kBridge, 5, bytes);
  const long long before = g_allocations;
  bool ok = true;
  for (int i = 0; i < 200; ++i) {  // ~800 KB: the 256 KB buffer is written out several times
    ok = ok && writer.write(c).ok();
    ok = ok && writer.write(StreamId::kCreate, 7, {bytes.data(), 13}).ok();
    ok = ok && writer.mark(MarkKind::kWhiskEnd, 9).ok();
  }
  const long long after = g_allocations;
  CHECK(ok);
  CHECK(after == before);
  REQUIRE(writer.close().ok());
  CHECK(writer.records() == 600);
}

TEST_CASE("RecordingReader: next() allocates nothing after open", "[io][recording][alloc]") {
  TempDir dir;
  const std::string path = dir.file("run.crec");
  {
    auto w = RecordingWriter::create(path, "{}");
    REQUIRE(w.ok());
    const std::vector<std::uint8_t> bytes(1000, 1);
    for (int i = 0; i < 300; ++i) REQUIRE(w.value()->write(StreamId::kBridge, i, bytes).ok());
  }
  auto r = RecordingReader::open(path);
  REQUIRE(r.ok());
  auto chunk = std::make_unique<Chunk>();
  int records = 0;
  const long long before = g_allocations;
  RecordingReader::Next n;
  while ((n = r.value()->next(*chunk)) == RecordingReader::Next::kRecord) ++records;
  const long long after = g_allocations;
  CHECK(after == before);
  CHECK(n == RecordingReader::Next::kEnd);
  CHECK(records == 300);
}
