// Proves the Create stream parser and SensorTracker never allocate while fed (crunch/io/create_oi.h).
// Its own executable: support/count_allocations.h replaces the global operator new.
#include <catch2/catch.hpp>

#include <array>
#include <vector>

#include "crunch/io/create_oi.h"
#include "support/count_allocations.h"

namespace oi = crunch::io::oi;

TEST_CASE("OI stream parser and tracker: feeding allocates nothing", "[io][create][alloc]") {
  std::vector<std::uint8_t> stream;
  for (int k = 0; k < 200; ++k) {
    oi::SensorFrame f;
    f.set(oi::kBumpsWheelDrops, k % 17 == 0 ? 1 : 0);
    f.set(oi::kDistance, k);
    f.set(oi::kAngle, -k);
    f.set(oi::kOiMode, 2);
    std::array<std::uint8_t, 32> out{};
    const std::size_t n = oi::encodeStreamPacket(oi::kCreateBaseStream, f, true, out);
    stream.insert(stream.end(), out.begin(), out.begin() + static_cast<long>(n));
    stream.insert(stream.end(), {19, 200, 7, 19, 0x13, 0x55});  // garbage with false headers
  }
  oi::StreamParser parser;
  oi::SensorTracker tracker;
  const long long before = g_allocations;
  int packets = 0;
  for (const std::uint8_t b : stream) packets += parser.feed(b);
  tracker.feed(stream);
  const long long after = g_allocations;
  CHECK(after == before);
  CHECK(packets == 200);
  CHECK(tracker.packets() == 200);
}
