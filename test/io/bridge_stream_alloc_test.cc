// Counts heap allocations to prove BridgeStreamDecoder::feed() never allocates, whatever the
// stream holds (ARCHITECTURE.md §3). Its own executable: it replaces the global operator new.
#include <catch2/catch.hpp>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <vector>

#include "crunch/core/rng.h"
#include "crunch/io/bridge_stream.h"
#include "support/count_allocations.h"



TEST_CASE("BridgeStream: feed() performs no heap allocation, on good or corrupt streams", "[io]") {
  // Frames of every board with sequence gaps, DROPPED gaps, resets, corrupt bytes and garbage.
  crunch::Rng rng(5);
  std::vector<std::uint8_t> bytes;
  std::uint16_t seq[BRIDGE_MAX_BOARDS] = {};
  std::uint32_t tick[BRIDGE_MAX_BOARDS] = {};
  for (int i = 0; i < 20000; ++i) {
    const auto b = static_cast<std::uint8_t>(rng.below(BRIDGE_MAX_BOARDS));
    const std::uint32_t skip = rng.below(8) == 0 ? rng.below(5) : 0;
    seq[b] = static_cast<std::uint16_t>(seq[b] + 1 + skip);
    tick[b] += 1 + skip + (rng.below(16) == 0 ? rng.below(4) : 0);
    const bridge_frame_t f{b,
                           seq[b],
                           tick[b],
                           static_cast<std::uint16_t>(rng.below(65536)),
                           static_cast<std::uint16_t>(rng.below(65536)),
                           static_cast<std::uint16_t>(rng.below(4) == 0 ? BRIDGE_ST_DROPPED : 0)};
    std::uint8_t out[BRIDGE_FRAME_LEN];
    REQUIRE(bridge_encode(&f, out) == 0);
    if (rng.below(10) == 0) out[rng.below(BRIDGE_FRAME_LEN)] ^= 0x10;
    bytes.insert(bytes.end(), out, out + BRIDGE_FRAME_LEN);
    for (std::uint32_t g = rng.below(6) == 0 ? rng.below(20) : 0; g > 0; --g)
      bytes.push_back(rng.below(3) == 0 ? 0xA5 : static_cast<std::uint8_t>(rng.below(256)));
  }
  std::vector<std::size_t> cuts;
  for (std::size_t at = 0; at < bytes.size(); at += 1 + rng.below(600)) cuts.push_back(at);
  cuts.push_back(bytes.size());

  crunch::io::BridgeStreamDecoder dec;
  std::uint64_t seen = 0;
  auto sink = [&](const crunch::io::DecodedFrame& d) { seen += d.frame.seq; };
  const long long before = g_allocations;
  for (std::size_t k = 0; k + 1 < cuts.size(); ++k)
    dec.feed(std::span<const std::uint8_t>(bytes).subspan(cuts[k], cuts[k + 1] - cuts[k]), sink);
  const long long during = g_allocations - before;
  CHECK(dec.counters().frames > 15000);
  CHECK(dec.counters().crc_failures > 1000);
  CHECK(seen > 0);
  CHECK(during == 0);
}
