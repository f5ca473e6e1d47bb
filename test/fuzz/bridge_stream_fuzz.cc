// libFuzzer target for the host bridge-stream decoder (crunch/io/bridge_stream.h). Input layout:
//   byte 0      mode: bit 0 set = "repair": every A5 5A with 16 more bytes after it gets the
//               correct CRC written into it, so the fuzzer can reach valid frames (and the
//               per-board sequence/timestamp tracking) without having to guess CRCs;
//   bytes 1..4  seed of the chunking (chunk sizes 1..600, as bulk transfers arrive);
//   the rest    the byte stream.
// Properties checked, beyond "no crash, no sanitizer report":
//   - every delivered frame is a frame bridge_decode() accepts (re-encoded, it decodes to
//     itself), with a board id < 28;
//   - the delivered frames are exactly those of a plain reference implementation of the rule in
//     docs/protocol.md run over the whole stream at once (so chunking changes nothing);
//   - the counters add up: bytes = 18 * frames + skipped + pending, frames = the sum over
//     boards, the return values of feed() sum to frames, not_fresh <= frames, last_seq and
//     last_tick are those of each board's last delivered frame;
//   - feeding the same stream as one chunk gives identical counters.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <span>
#include <vector>

#include "crunch/core/rng.h"
#include "crunch/io/bridge_stream.h"

extern "C" {
#include "whisker/error.h"
}

namespace {

using crunch::io::BridgeStreamCounters;
using crunch::io::BridgeStreamDecoder;
using crunch::io::DecodedFrame;

void check(bool ok) {
  if (!ok) std::abort();
}

bool sameFrame(const bridge_frame_t& a, const bridge_frame_t& b) {
  return a.board == b.board && a.seq == b.seq && a.tick == b.tick && a.alpha == b.alpha &&
         a.beta == b.beta && a.status == b.status;
}

// docs/protocol.md's resynchronisation rule, read straight off the page, on the whole stream.
std::vector<bridge_frame_t> reference(const std::vector<std::uint8_t>& s) {
  std::vector<bridge_frame_t> out;
  std::size_t i = 0;
  while (s.size() - i >= BRIDGE_FRAME_LEN) {
    bridge_frame_t f{};
    if (s[i] == BRIDGE_SYNC0 && s[i + 1] == BRIDGE_SYNC1 && bridge_decode(&s[i], &f) == FW_OK) {
      out.push_back(f);
      i += BRIDGE_FRAME_LEN;
    } else {
      ++i;
    }
  }
  return out;
}

bool sameCounters(const BridgeStreamCounters& a, const BridgeStreamCounters& b) {
  if (a.bytes != b.bytes || a.frames != b.frames || a.skipped_bytes != b.skipped_bytes ||
      a.crc_failures != b.crc_failures || a.bad_version != b.bad_version ||
      a.bad_board != b.bad_board)
    return false;
  for (std::size_t i = 0; i < a.boards.size(); ++i) {
    const auto& x = a.boards[i];
    const auto& y = b.boards[i];
    if (x.frames != y.frames || x.lost_frames != y.lost_frames ||
        x.dropped_samples != y.dropped_samples || x.unmarked_tick_gaps != y.unmarked_tick_gaps ||
        x.restarts != y.restarts || x.not_fresh != y.not_fresh || x.last_seq != y.last_seq ||
        x.last_tick != y.last_tick)
      return false;
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 5) return 0;
  const bool repair = (data[0] & 1u) != 0;
  std::uint32_t seed = 0;
  std::memcpy(&seed, data + 1, sizeof seed);
  std::vector<std::uint8_t> stream(data + 5, data + size);
  if (repair) {
    for (std::size_t i = 0; i + BRIDGE_FRAME_LEN <= stream.size(); ++i) {
      if (stream[i] != BRIDGE_SYNC0 || stream[i + 1] != BRIDGE_SYNC1) continue;
      const std::uint16_t crc = bridge_crc16(&stream[i + 2], 14);
      stream[i + 16] = static_cast<std::uint8_t>(crc & 0xFFu);
      stream[i + 17] = static_cast<std::uint8_t>(crc >> 8);
    }
  }

  BridgeStreamDecoder dec;
  std::vector<bridge_frame_t> got;
  auto sink = [&](const DecodedFrame& d) {
    std::uint8_t bytes[BRIDGE_FRAME_LEN];
    bridge_frame_t again{};
    check(bridge_encode(&d.frame, bytes) == FW_OK);  // board < 28
    check(bridge_decode(bytes, &again) == FW_OK && sameFrame(again, d.frame));
    got.push_back(d.frame);
  };

  crunch::Rng rng(seed);
  std::size_t at = 0, returned = 0;
  while (at < stream.size()) {
    const std::size_t n = std::min<std::size_t>(1 + rng.below(600), stream.size() - at);
    returned += dec.feed(std::span<const std::uint8_t>(stream).subspan(at, n), sink);
    at += n;
    const BridgeStreamCounters& c = dec.counters();
    check(c.bytes == at);
    check(c.bytes == BRIDGE_FRAME_LEN * c.frames + c.skipped_bytes + dec.pending());
    check(dec.pending() < BRIDGE_FRAME_LEN);
  }

  const BridgeStreamCounters& c = dec.counters();
  check(returned == got.size() && c.frames == got.size());
  const std::vector<bridge_frame_t> ref = reference(stream);
  check(ref.size() == got.size());
  for (std::size_t i = 0; i < ref.size(); ++i) check(sameFrame(ref[i], got[i]));

  std::uint64_t sum = 0;
  for (std::size_t b = 0; b < c.boards.size(); ++b) {
    const auto& bc = c.boards[b];
    sum += bc.frames;
    check(bc.not_fresh <= bc.frames);
    check(bc.restarts + (bc.frames > 0 ? 1u : 0u) <= bc.frames);
    if (bc.frames == 0) continue;
    for (auto it = got.rbegin(); it != got.rend(); ++it) {
      if (it->board != b) continue;
      check(it->seq == bc.last_seq && it->tick == bc.last_tick);
      break;
    }
  }
  check(sum == c.frames);

  BridgeStreamDecoder whole;
  whole.feed(stream, [](const DecodedFrame&) {});
  check(sameCounters(whole.counters(), c));
  return 0;
}
