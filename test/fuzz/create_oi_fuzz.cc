// libFuzzer target for the Create stream parser and SensorTracker (crunch/io/create_oi.h).
// Byte 0 picks the options (bit 0: checksum includes the header; bit 1: expected length 10)
// and bit 2 a "repair" mode that writes the right checksum after every 19 whose layout is
// complete, so the fuzzer reaches valid packets. Checks beyond "no crash":
//   - bytes == packet_bytes + skipped_bytes + pending() after every byte, pending() < 258;
//   - every delivered packet re-encodes (same ids, same values) to a valid packet;
//   - a SensorTracker fed the same stream in chunks (sizes from the input) gives the same
//     packet count, counters and odometry.
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "crunch/io/create_oi.h"

namespace oi = crunch::io::oi;

namespace {
void check(bool ok) {
  if (!ok) std::abort();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  const std::uint8_t mode = data[0];
  oi::StreamParserOptions options{(mode & 1u) != 0, static_cast<std::uint8_t>((mode & 2u) ? 10 : 0)};
  std::vector<std::uint8_t> s(data + 1, data + size);
  if ((mode & 4u) != 0) {
    for (std::size_t i = 0; i + 2 < s.size(); ++i) {
      if (s[i] != 19) continue;
      const std::size_t end = i + 2 + s[i + 1];
      if (s[i + 1] == 0 || end >= s.size()) continue;
      unsigned sum = 0;
      for (std::size_t k = options.checksum_includes_header ? i : i + 1; k < end; ++k) sum += s[k];
      s[end] = static_cast<std::uint8_t>((256u - (sum & 0xFFu)) & 0xFFu);
    }
  }
  oi::StreamParser parser(options);
  std::uint64_t delivered = 0;
  const auto verify = [&] {
    ++delivered;
    const oi::SensorFrame& f = parser.frame();
    std::vector<std::uint8_t> ids;
    for (std::uint8_t id = oi::kFirstPacketId; id <= oi::kLastPacketId; ++id) {
      if (f.has(id)) ids.push_back(id);
    }
    check(!ids.empty());
    std::uint8_t out[600];
    const std::size_t n = oi::encodeStreamPacket(ids, f, options.checksum_includes_header, out);
    // Duplicate ids in a packet collapse in SensorFrame, so only validity is checked here.
    check(n >= 5);
    oi::StreamParser again(oi::StreamParserOptions{options.checksum_includes_header, 0});
    bool ok = false;
    for (std::size_t i = 0; i < n; ++i) ok = again.feed(out[i]);
    check(ok);
  };
  for (const std::uint8_t b : s) {
    if (parser.feed(b)) {
      verify();
      while (parser.drainHeld()) verify();
    }
    const auto& c = parser.counters();
    check(c.bytes == c.packet_bytes + c.skipped_bytes + parser.pending());
    check(parser.pending() < 258);
  }
  oi::SensorTracker tracker(options);
  std::size_t i = 0, k = 0;
  while (i < s.size()) {
    const std::size_t n = std::min<std::size_t>(1 + data[k++ % size] % 64, s.size() - i);
    tracker.feed({s.data() + i, n});
    i += n;
  }
  check(tracker.packets() == delivered);
  check(tracker.counters().stream.skipped_bytes == parser.counters().skipped_bytes);
  check(tracker.counters().stream.checksum_failures == parser.counters().checksum_failures);
  oi::SensorTracker whole(options);
  whole.feed(s);
  check(whole.odometry().x == tracker.odometry().x && whole.odometry().y == tracker.odometry().y &&
        whole.odometry().theta == tracker.odometry().theta);
  return 0;
}
