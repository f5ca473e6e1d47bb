// BridgeStreamDecoder: real frames from VirtualWhiskerBoard (the firmware core) and hand-built
// ones, fed in every way USB bulk transfers can cut them, with garbage, bit flips, false syncs,
// wraps and losses. Each test asserts what was delivered and the exact counters.
#include "crunch/io/bridge_stream.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdint>
#include <memory>
#include <span>
#include <tuple>
#include <vector>

#include "crunch/core/rng.h"
#include "crunch_sim/virtual_whisker_board.h"

extern "C" {
#include "whisker/error.h"
#include "whisker/ring.h"
#include "whisker/sampler.h"
}

using crunch::io::BridgeStreamCounters;
using crunch::io::BridgeStreamDecoder;
using crunch::io::DecodedFrame;
using crunch::sim::VirtualWhiskerBoard;
using Bytes = std::vector<std::uint8_t>;

namespace {

auto key(const bridge_frame_t& f) {
  return std::make_tuple(f.board, f.seq, f.tick, f.alpha, f.beta, f.status);
}

bool sameFrames(const std::vector<bridge_frame_t>& a, const std::vector<bridge_frame_t>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (key(a[i]) != key(b[i])) return false;
  return true;
}

// Everything a decoder said: the frames, in order, and its counters.
struct Outcome {
  std::vector<bridge_frame_t> frames;
  std::vector<DecodedFrame> decoded;
  BridgeStreamCounters counters;
  std::size_t pending = 0;
};

bool sameCounters(const BridgeStreamCounters& a, const BridgeStreamCounters& b) {
  if (std::tie(a.bytes, a.frames, a.skipped_bytes, a.crc_failures, a.bad_version, a.bad_board) !=
      std::tie(b.bytes, b.frames, b.skipped_bytes, b.crc_failures, b.bad_version, b.bad_board))
    return false;
  for (std::size_t i = 0; i < a.boards.size(); ++i) {
    const auto& x = a.boards[i];
    const auto& y = b.boards[i];
    if (std::tie(x.frames, x.lost_frames, x.dropped_samples, x.unmarked_tick_gaps, x.restarts,
                 x.not_fresh, x.last_seq, x.last_tick) !=
        std::tie(y.frames, y.lost_frames, y.dropped_samples, y.unmarked_tick_gaps, y.restarts,
                 y.not_fresh, y.last_seq, y.last_tick))
      return false;
  }
  return true;
}

// Feeds `bytes` cut at the given ascending offsets (each chunk [cuts[k], cuts[k+1])).
Outcome decodeChunks(const Bytes& bytes, const std::vector<std::size_t>& cuts) {
  BridgeStreamDecoder dec;
  Outcome out;
  std::size_t from = 0;
  auto sink = [&](const DecodedFrame& d) {
    out.frames.push_back(d.frame);
    out.decoded.push_back(d);
  };
  std::size_t delivered = 0;
  for (std::size_t k = 0; k <= cuts.size(); ++k) {
    const std::size_t to = k < cuts.size() ? cuts[k] : bytes.size();
    delivered += dec.feed(std::span<const std::uint8_t>(bytes).subspan(from, to - from), sink);
    from = to;
  }
  REQUIRE(delivered == out.frames.size());
  out.counters = dec.counters();
  out.pending = dec.pending();
  // The accounting invariant of bridge_stream.h.
  const auto& c = out.counters;
  CHECK(c.bytes == bytes.size());
  CHECK(c.bytes == BRIDGE_FRAME_LEN * c.frames + c.skipped_bytes + out.pending);
  return out;
}

Outcome decodeWhole(const Bytes& bytes) { return decodeChunks(bytes, {}); }

Bytes encode(const bridge_frame_t& f) {
  Bytes b(BRIDGE_FRAME_LEN);
  REQUIRE(bridge_encode(&f, b.data()) == FW_OK);
  return b;
}

bridge_frame_t frame(std::uint8_t board, std::uint16_t seq, std::uint32_t tick,
                     std::uint16_t status = 0, std::uint16_t alpha = 0x1234,
                     std::uint16_t beta = 0x4321) {
  return bridge_frame_t{board, seq, tick, alpha, beta, status};
}

void append(Bytes& to, const Bytes& from) { to.insert(to.end(), from.begin(), from.end()); }

Bytes encodeAll(const std::vector<bridge_frame_t>& frames) {
  Bytes out;
  for (const auto& f : frames) append(out, encode(f));
  return out;
}

// A reading that changes every tick, as a real sensor's low bits do (no STALE).
std::uint16_t scriptAlpha(std::uint32_t k) { return static_cast<std::uint16_t>(1000 + 29 * k); }
std::uint16_t scriptBeta(std::uint32_t k) { return static_cast<std::uint16_t>(64000 - 31 * k); }

// `ticks` periods of the given boards ticked in turn: the bytes they sent and the frames those
// bytes are (decoded at the known boundaries, the ground truth).
struct Recorded {
  Bytes bytes;
  std::vector<bridge_frame_t> frames;
  std::vector<std::size_t> starts;  // byte offset of each frame
};

void record(VirtualWhiskerBoard& board, std::uint32_t k, Recorded& rec) {
  board.sensor().setReading(scriptAlpha(k + board.boardId()), scriptBeta(k));
  const auto sent = board.tick();
  REQUIRE(sent.size() % BRIDGE_FRAME_LEN == 0);
  for (std::size_t i = 0; i < sent.size(); i += BRIDGE_FRAME_LEN) {
    bridge_frame_t f{};
    REQUIRE(bridge_decode(sent.data() + i, &f) == FW_OK);
    rec.frames.push_back(f);
    rec.starts.push_back(rec.bytes.size() + i);
  }
  rec.bytes.insert(rec.bytes.end(), sent.begin(), sent.end());
}

Recorded recordBoards(const std::vector<std::uint8_t>& ids, std::uint32_t ticks) {
  std::vector<std::unique_ptr<VirtualWhiskerBoard>> boards;
  for (auto id : ids) boards.push_back(std::make_unique<VirtualWhiskerBoard>(id));
  Recorded rec;
  for (std::uint32_t k = 0; k < ticks; ++k)
    for (auto& b : boards) record(*b, k, rec);
  return rec;
}

}  // namespace

TEST_CASE("BridgeStream: a virtual-board stream round-trips frame for frame", "[io]") {
  constexpr std::uint32_t kTicks = 500;
  const Recorded rec = recordBoards({0, 5, 27}, kTicks);
  REQUIRE(rec.frames.size() == 3 * kTicks);

  const Outcome out = decodeWhole(rec.bytes);
  CHECK(sameFrames(out.frames, rec.frames));
  const auto& c = out.counters;
  CHECK(c.frames == 3 * kTicks);
  CHECK(c.skipped_bytes == 0);
  CHECK(c.crc_failures == 0);
  CHECK(c.bad_version + c.bad_board == 0);
  CHECK(out.pending == 0);
  for (std::uint8_t id : {0, 5, 27}) {
    const auto& b = c.boards[id];
    CHECK(b.frames == kTicks);
    CHECK(b.lost_frames == 0);
    CHECK(b.dropped_samples == 0);
    CHECK(b.unmarked_tick_gaps == 0);
    CHECK(b.restarts == 0);
    CHECK(b.not_fresh == SAMPLER_POWERUP_TICKS);  // the power-up frames, and only they
    CHECK(b.last_tick == kTicks - 1);
    CHECK(b.last_seq == kTicks - 1);
  }
  CHECK(c.boards[1].frames == 0);
  for (const auto& d : out.decoded) CHECK(d.frames_lost + d.samples_dropped == 0);
}

TEST_CASE("BridgeStream: the outcome is the same at every split point", "[io]") {
  // Four frames with a little garbage, a lone A5 and a false sync between them, so splits land
  // inside syncs, payloads, CRCs and garbage alike.
  Bytes bytes = {0x00, 0xA5};
  append(bytes, encode(frame(1, 10, 100)));
  append(bytes, {0xA5, 0x5A, 0x01});
  append(bytes, encode(frame(2, 7, 70, BRIDGE_ST_STALE, 0x5AA5, 0xA55A)));
  append(bytes, encode(frame(1, 11, 101)));
  append(bytes, {0x5A, 0xA5});
  append(bytes, encode(frame(27, 65535, 4000000000u)));
  append(bytes, {0xA5});

  const Outcome whole = decodeWhole(bytes);
  REQUIRE(whole.frames.size() == 4);
  CHECK(whole.counters.skipped_bytes == 2 + 3 + 2);
  CHECK(whole.pending == 1);  // the trailing A5 may begin a frame

  SECTION("one cut") {
    for (std::size_t k = 0; k <= bytes.size(); ++k) {
      INFO("cut at " << k);
      const Outcome cut = decodeChunks(bytes, {k});
      CHECK(sameFrames(cut.frames, whole.frames));
      CHECK(sameCounters(cut.counters, whole.counters));
      CHECK(cut.pending == whole.pending);
    }
  }
  SECTION("two cuts") {
    for (std::size_t a = 0; a <= bytes.size(); ++a)
      for (std::size_t b = a; b <= bytes.size(); ++b) {
        const Outcome cut = decodeChunks(bytes, {a, b});
        if (!sameFrames(cut.frames, whole.frames) || !sameCounters(cut.counters, whole.counters)) {
          FAIL("cuts at " << a << " and " << b);
        }
      }
  }
  SECTION("byte by byte") {
    std::vector<std::size_t> cuts;
    for (std::size_t k = 1; k < bytes.size(); ++k) cuts.push_back(k);
    const Outcome cut = decodeChunks(bytes, cuts);
    CHECK(sameFrames(cut.frames, whole.frames));
    CHECK(sameCounters(cut.counters, whole.counters));
  }
}

TEST_CASE("BridgeStream: random garbage between frames is skipped, every frame kept", "[io]") {
  const Recorded rec = recordBoards({3, 4}, 400);
  crunch::Rng rng(20261123);
  Bytes bytes;
  std::uint64_t garbage = 0;
  for (std::size_t i = 0; i < rec.frames.size(); ++i) {
    const std::uint32_t n = rng.below(3) == 0 ? rng.below(40) : 0;
    for (std::uint32_t g = 0; g < n; ++g) {
      // Random bytes, rich in sync bytes so that false starts are common.
      const std::uint32_t pick = rng.below(4);
      bytes.push_back(pick == 0   ? std::uint8_t{0xA5}
                      : pick == 1 ? std::uint8_t{0x5A}
                                  : static_cast<std::uint8_t>(rng.below(256)));
    }
    garbage += n;
    bytes.insert(bytes.end(), rec.bytes.begin() + static_cast<std::ptrdiff_t>(rec.starts[i]),
                 rec.bytes.begin() + static_cast<std::ptrdiff_t>(rec.starts[i]) + BRIDGE_FRAME_LEN);
  }
  REQUIRE(garbage > 1000);

  // Random chunk sizes, as bulk transfers arrive.
  std::vector<std::size_t> cuts;
  for (std::size_t at = rng.below(64); at < bytes.size(); at += 1 + rng.below(128))
    cuts.push_back(at);
  const Outcome out = decodeChunks(bytes, cuts);
  CHECK(sameFrames(out.frames, rec.frames));
  CHECK(out.counters.skipped_bytes == garbage);
  CHECK(out.counters.crc_failures > 0);  // the false starts were tried and rejected
  for (std::uint8_t id : {3, 4}) {
    CHECK(out.counters.boards[id].lost_frames == 0);
    CHECK(out.counters.boards[id].frames == 400);
  }
  CHECK(sameCounters(out.counters, decodeWhole(bytes).counters));
}

TEST_CASE("BridgeStream: every single bit flip in a frame is caught, its neighbours kept", "[io]") {
  // Payloads without A5 so that the rescan of the rejected frame finds nothing inside it.
  const std::vector<bridge_frame_t> frames = {frame(9, 1, 1), frame(9, 2, 2), frame(9, 3, 3)};
  const Bytes clean = encodeAll(frames);
  for (std::size_t bit = 0; bit < 8 * BRIDGE_FRAME_LEN; ++bit) {
    INFO("bit " << bit);
    Bytes bytes = clean;
    const std::size_t byte = BRIDGE_FRAME_LEN + bit / 8;
    bytes[byte] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    const Outcome out = decodeWhole(bytes);
    REQUIRE(out.frames.size() == 2);
    CHECK(key(out.frames[0]) == key(frames[0]));
    CHECK(key(out.frames[1]) == key(frames[2]));
    CHECK(out.counters.skipped_bytes == BRIDGE_FRAME_LEN);  // the corrupt frame, nothing else
    // A flip in the sync hides the frame; anywhere else the CRC rejects it (CRC-16 catches every
    // single-bit error), before the version and board are even looked at.
    CHECK(out.counters.crc_failures == (bit / 8 < 2 ? 0u : 1u));
    CHECK(out.counters.bad_version + out.counters.bad_board == 0);
    // The gap the lost frame leaves is seen as a lost frame.
    CHECK(out.counters.boards[9].lost_frames == 1);
    CHECK(out.decoded[1].frames_lost == 1);
  }
}

TEST_CASE("BridgeStream: a good CRC with a bad version or board id is rejected and counted",
          "[io]") {
  Bytes bad_version = encode(frame(4, 1, 1));
  bad_version[3] = BRIDGE_VERSION + 1;
  Bytes bad_board = encode(frame(4, 1, 1));
  bad_board[2] = BRIDGE_MAX_BOARDS;
  for (Bytes* b : {&bad_version, &bad_board}) {
    const std::uint16_t crc = bridge_crc16(b->data() + 2, 14);
    (*b)[16] = static_cast<std::uint8_t>(crc & 0xFF);
    (*b)[17] = static_cast<std::uint8_t>(crc >> 8);
  }
  Bytes bytes = bad_version;
  append(bytes, encode(frame(4, 2, 2)));
  append(bytes, bad_board);
  const Outcome out = decodeWhole(bytes);
  REQUIRE(out.frames.size() == 1);
  CHECK(out.frames[0].seq == 2);
  CHECK(out.counters.bad_version == 1);
  CHECK(out.counters.bad_board == 1);
  CHECK(out.counters.crc_failures == 0);
  CHECK(out.counters.skipped_bytes == 2 * BRIDGE_FRAME_LEN);
}

TEST_CASE("BridgeStream: a false sync inside a payload costs one byte, not the real frame",
          "[io]") {
  // Alpha 0x5AA5 is sent A5 5A at bytes 10-11: a sync pattern inside the payload.
  const std::vector<bridge_frame_t> frames = {frame(6, 1, 1, 0, 0x5AA5), frame(6, 2, 2, 0, 0x5AA5),
                                              frame(6, 3, 3, 0, 0x5AA5)};
  const Bytes clean = encodeAll(frames);
  REQUIRE(clean[10] == 0xA5);
  REQUIRE(clean[11] == 0x5A);

  SECTION("read from the start, the decoder steps over whole frames and never sees it") {
    const Outcome out = decodeWhole(clean);
    CHECK(sameFrames(out.frames, frames));
    CHECK(out.counters.crc_failures == 0);
  }
  SECTION("joining mid-frame at the false sync, the next real frame is still found") {
    // The stream starts at byte 10 of the first frame: "A5 5A" then 6 more bytes, and the
    // decoder's 18 bytes from there run 10 bytes into the second frame.
    const Bytes bytes(clean.begin() + 10, clean.end());
    for (std::size_t k = 0; k <= bytes.size(); ++k) {
      INFO("cut at " << k);
      const Outcome out = decodeChunks(bytes, {k});
      CHECK(sameFrames(out.frames, {frames[1], frames[2]}));
      CHECK(out.counters.crc_failures == 1);
      CHECK(out.counters.skipped_bytes == 8);  // the tail of the first frame only
    }
  }
}

TEST_CASE("BridgeStream: sequence numbers wrap from 0xFFFF to 0 without a loss", "[io]") {
  SECTION("a virtual board past 65536 frames") {
    VirtualWhiskerBoard board(12);
    BridgeStreamDecoder dec;
    std::uint64_t delivered = 0;
    bool wrapped = false;
    std::uint16_t prev = 0;
    auto sink = [&](const DecodedFrame& d) {
      if (delivered > 0 && d.frame.seq == 0 && prev == 0xFFFF) wrapped = true;
      prev = d.frame.seq;
      ++delivered;
    };
    constexpr std::uint32_t kTicks = 65536 + 100;
    for (std::uint32_t k = 0; k < kTicks; ++k) {
      board.sensor().setReading(scriptAlpha(k), scriptBeta(k));
      dec.feed(board.tick(), sink);
    }
    CHECK(wrapped);
    CHECK(delivered == kTicks);
    const auto& b = dec.counters().boards[12];
    CHECK(b.frames == kTicks);
    CHECK(b.lost_frames == 0);
    CHECK(b.restarts == 0);
    CHECK(b.last_seq == static_cast<std::uint16_t>(kTicks - 1));
  }
  SECTION("frames lost across the wrap are counted") {
    const Outcome out = decodeWhole(encodeAll(
        {frame(2, 0xFFFD, 1000), frame(2, 0xFFFE, 1001), frame(2, 1, 1004), frame(2, 2, 1005)}));
    REQUIRE(out.frames.size() == 4);
    CHECK(out.counters.boards[2].lost_frames == 2);  // 0xFFFF and 0
    CHECK(out.decoded[2].frames_lost == 2);
    CHECK(out.counters.boards[2].restarts == 0);
  }
  SECTION("more than 65535 lost frames: the timestamp tells how many times it wrapped") {
    const std::uint32_t lost = 70000;  // 35 s of link outage
    const Outcome out = decodeWhole(
        encodeAll({frame(2, 100, 5000),
                   frame(2, static_cast<std::uint16_t>(100 + lost + 1), 5000 + lost + 1)}));
    CHECK(out.counters.boards[2].lost_frames == lost);
    CHECK(out.decoded[1].frames_lost == lost);
  }
}

TEST_CASE("BridgeStream: frames lost on the link are counted per board", "[io]") {
  const Recorded rec = recordBoards({1, 2}, 200);
  // Remove board 1's frames 50, 51, 52 and 120, and board 2's frame 80 (frames alternate 1, 2).
  const std::vector<std::size_t> removed = {2 * 50, 2 * 51, 2 * 52, 2 * 120, 2 * 80 + 1};
  Bytes bytes;
  std::vector<bridge_frame_t> kept;
  for (std::size_t i = 0; i < rec.frames.size(); ++i) {
    if (std::find(removed.begin(), removed.end(), i) != removed.end()) continue;
    kept.push_back(rec.frames[i]);
    bytes.insert(bytes.end(), rec.bytes.begin() + static_cast<std::ptrdiff_t>(rec.starts[i]),
                 rec.bytes.begin() + static_cast<std::ptrdiff_t>(rec.starts[i]) + BRIDGE_FRAME_LEN);
  }
  const Outcome out = decodeWhole(bytes);
  CHECK(sameFrames(out.frames, kept));
  CHECK(out.counters.boards[1].lost_frames == 4);
  CHECK(out.counters.boards[2].lost_frames == 1);
  CHECK(out.counters.boards[1].dropped_samples == 0);  // not the board's loss
  CHECK(out.counters.boards[1].unmarked_tick_gaps == 0);
  // The frame after each hole says how many are missing right before it.
  std::vector<std::tuple<std::uint8_t, std::uint16_t, std::uint32_t>> holes;
  for (const auto& d : out.decoded)
    if (d.frames_lost > 0) holes.emplace_back(d.frame.board, d.frame.seq, d.frames_lost);
  CHECK(holes == decltype(holes){{1, 53, 3}, {2, 81, 1}, {1, 121, 1}});
}

TEST_CASE("BridgeStream: samples the board dropped (DROPPED) are counted, not as lost frames",
          "[io]") {
  VirtualWhiskerBoard board(8);
  Recorded rec;
  std::uint32_t k = 0;
  for (; k < SAMPLER_POWERUP_TICKS + 10; ++k) record(board, k, rec);
  board.stallMainLoop(RING_CAPACITY + 8);  // the ring overflows: the board drops samples
  for (std::uint32_t s = 0; s < RING_CAPACITY + 20; ++s, ++k) record(board, k, rec);
  REQUIRE(board.ringDropped() > 0);

  const Outcome out = decodeWhole(rec.bytes);
  CHECK(sameFrames(out.frames, rec.frames));
  const auto& b = out.counters.boards[8];
  CHECK(b.dropped_samples == board.ringDropped());
  CHECK(b.lost_frames == 0);
  CHECK(b.unmarked_tick_gaps == 0);
  int marked = 0;
  for (const auto& d : out.decoded) {
    if (d.samples_dropped == 0) continue;
    ++marked;
    CHECK((d.frame.status & BRIDGE_ST_DROPPED) != 0);
    CHECK(d.samples_dropped == board.ringDropped());
  }
  CHECK(marked == 1);
  CHECK(b.not_fresh == SAMPLER_POWERUP_TICKS + 1);  // power-up, and the DROPPED frame
}

TEST_CASE("BridgeStream: a timestamp gap without DROPPED, and a board restart, are told apart",
          "[io]") {
  const Outcome out = decodeWhole(encodeAll({frame(5, 40, 400), frame(5, 41, 405),  // no DROPPED
                                             frame(5, 0, 0), frame(5, 1, 1),        // a reset
                                             frame(5, 1, 1)}));                     // a repeat
  REQUIRE(out.frames.size() == 5);
  const auto& b = out.counters.boards[5];
  CHECK(b.unmarked_tick_gaps == 1);
  CHECK(b.dropped_samples == 0);
  CHECK(b.restarts == 2);
  CHECK(b.lost_frames == 0);
  CHECK(b.last_tick == 1);
}

TEST_CASE("BridgeStream: resync() forgets held bytes and baselines, keeps the counters", "[io]") {
  BridgeStreamDecoder dec;
  std::vector<DecodedFrame> got;
  auto sink = [&](const DecodedFrame& d) { got.push_back(d); };
  const Bytes a = encode(frame(3, 10, 10));
  dec.feed(a, sink);
  dec.feed(std::span<const std::uint8_t>(a).first(9), sink);  // half a frame, then the device
  CHECK(dec.pending() == 9);                                  // is reopened
  dec.resync();
  CHECK(dec.pending() == 0);
  dec.feed(encode(frame(3, 500, 900)), sink);  // would be 489 lost frames without the resync
  REQUIRE(got.size() == 2);
  CHECK(got[1].frames_lost == 0);
  CHECK(dec.counters().boards[3].lost_frames == 0);
  CHECK(dec.counters().boards[3].frames == 2);
  dec.reset();
  CHECK(dec.counters().frames == 0);
  CHECK(dec.counters().bytes == 0);
}
