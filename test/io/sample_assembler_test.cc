// Tests of the SampleAssembler (crunch/io/sample_assembler.h): from per-board frames, interleaved
// as they arrive, to one SampleFrame per 500 us tick, keeping the time base through gaps and
// silent boards. The no-allocation check is in io_ring_alloc_test.cc (own executable).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "crunch/io/sample_assembler.h"

using crunch::io::DecodedFrame;
using crunch::io::SampleAssembler;
namespace signal = crunch::signal;
namespace st = crunch::signal::status;

namespace {

// Board b's frame for tick t: alpha = t + 1 (never 0, unlike a placeholder), beta = b.
DecodedFrame frame(int board, int tick, std::uint32_t lost = 0, std::uint32_t dropped = 0) {
  DecodedFrame d;
  d.frame.board = static_cast<std::uint8_t>(board);
  d.frame.seq = static_cast<std::uint16_t>(tick);
  d.frame.tick = static_cast<std::uint32_t>(tick);
  d.frame.alpha = static_cast<std::uint16_t>(tick + 1);
  d.frame.beta = static_cast<std::uint16_t>(board);
  d.frame.status = 0;
  d.frames_lost = lost;
  d.samples_dropped = dropped;
  return d;
}

struct Collector {
  std::vector<signal::SampleFrame> samples;
  int push(SampleAssembler& a, const DecodedFrame& d) {
    const std::size_t before = samples.size();
    const int n = a.push(d, [&](const signal::SampleFrame& f) { samples.push_back(f); });
    REQUIRE(static_cast<std::size_t>(n) == samples.size() - before);
    return n;
  }
};

bool isPlaceholder(const signal::WhiskerReading& r) {
  return r.alpha == 0 && r.beta == 0 && r.status == st::kTimeout;
}
bool isTick(const signal::WhiskerReading& r, int whisker, int tick) {
  return r.alpha == tick + 1 && r.beta == whisker && r.status == 0;
}

// Checks sample k: whisker w holds tick k's reading, or a placeholder where `missing(w, k)`.
template <typename Missing>
void checkAligned(const std::vector<signal::SampleFrame>& samples, Missing&& missing) {
  for (std::size_t k = 0; k < samples.size(); ++k) {
    for (int w = 0; w < signal::kWhiskers; ++w) {
      const auto& r = samples[k][static_cast<std::size_t>(w)];
      const bool ok = missing(w, static_cast<int>(k)) ? isPlaceholder(r)
                                                      : isTick(r, w, static_cast<int>(k));
      INFO("sample " << k << " whisker " << w << ": alpha " << r.alpha << " beta " << r.beta
                     << " status " << r.status);
      REQUIRE(ok);
    }
  }
}

}  // namespace

TEST_CASE("SampleAssembler: four boards in lockstep give one sample per tick", "[io][assembler]") {
  SampleAssembler a;
  Collector c;
  for (int t = 0; t < 300; ++t) {
    for (int b = 0; b < 4; ++b) {
      const int n = c.push(a, frame(b, t));
      CHECK(n == (b == 3 ? 1 : 0));  // the sample completes with the last whisker's reading
    }
  }
  REQUIRE(c.samples.size() == 300);
  checkAligned(c.samples, [](int, int) { return false; });
  CHECK(a.counters().samples == 300);
  CHECK(a.counters().placeholders == 0);
  CHECK(a.counters().silent_fills == 0);
  for (int w = 0; w < 4; ++w) CHECK(a.queued(w) == 0);
}

TEST_CASE("SampleAssembler: a board's frames go to the whisker the options map it to",
          "[io][assembler]") {
  SampleAssembler::Options o;
  o.board_of_whisker = {7, 2, 11, 0};
  SampleAssembler a(o);
  Collector c;
  for (int t = 0; t < 10; ++t) {
    for (const int b : {0, 2, 7, 11}) c.push(a, frame(b, t));
  }
  REQUIRE(c.samples.size() == 10);
  for (int t = 0; t < 10; ++t) {
    const auto& s = c.samples[static_cast<std::size_t>(t)];
    CHECK(s[0].beta == 7);
    CHECK(s[1].beta == 2);
    CHECK(s[2].beta == 11);
    CHECK(s[3].beta == 0);
    for (const auto& r : s) CHECK(r.alpha == t + 1);
  }
  // Board 1 is no whisker's now: ignored and counted.
  CHECK(c.push(a, frame(1, 10)) == 0);
  CHECK(a.counters().unmapped_frames == 1);
}

TEST_CASE("SampleAssembler: the interleaving order of the boards does not matter",
          "[io][assembler]") {
  constexpr int kTicks = 2000;
  for (const unsigned seed : {1u, 2u, 3u, 4u, 5u}) {
    // Each board's frames in tick order, delivered in bursts of random length from a random
    // board, never more than max_lag ahead of the slowest board.
    SampleAssembler a;
    Collector c;
    std::mt19937 rng(seed);
    std::array<int, 4> next{};
    while (*std::min_element(next.begin(), next.end()) < kTicks) {
      const int b = static_cast<int>(rng() % 4);
      const int slowest = *std::min_element(next.begin(), next.end());
      const int room = std::min(kTicks, slowest + 60) - next[static_cast<std::size_t>(b)];
      if (room <= 0) continue;
      const int burst = 1 + static_cast<int>(rng() % static_cast<unsigned>(std::min(room, 24)));
      for (int i = 0; i < burst; ++i) c.push(a, frame(b, next[static_cast<std::size_t>(b)]++));
    }
    INFO("seed " << seed);
    REQUIRE(c.samples.size() == kTicks);
    checkAligned(c.samples, [](int, int) { return false; });
    CHECK(a.counters().silent_fills == 0);
    CHECK(a.counters().placeholders == 0);
  }
}

TEST_CASE("SampleAssembler: a reported gap inserts placeholders so later samples stay aligned",
          "[io][assembler]") {
  SampleAssembler a;
  Collector c;
  // Board 2 loses ticks 50..54: 3 on the link (frames_lost) and 2 dropped by the board
  // (samples_dropped); its tick-55 frame reports both. Board 1 loses tick 120 on the link.
  for (int t = 0; t < 200; ++t) {
    for (int b = 0; b < 4; ++b) {
      if (b == 2 && t >= 50 && t <= 54) continue;
      if (b == 1 && t == 120) continue;
      if (b == 2 && t == 55) {
        c.push(a, frame(b, t, 3, 2));
      } else if (b == 1 && t == 121) {
        c.push(a, frame(b, t, 1, 0));
      } else {
        c.push(a, frame(b, t));
      }
    }
  }
  REQUIRE(c.samples.size() == 200);
  checkAligned(c.samples, [](int w, int k) {
    return (w == 2 && k >= 50 && k <= 54) || (w == 1 && k == 120);
  });
  CHECK(a.counters().placeholders == 6);
  CHECK(a.counters().silent_fills == 0);
}

TEST_CASE("SampleAssembler: a gap longer than max_lag inserts at most max_lag placeholders",
          "[io][assembler]") {
  SampleAssembler::Options o;
  o.max_lag = 8;
  SampleAssembler a(o);
  Collector c;
  c.push(a, frame(0, 0, 1000, 0));
  CHECK(a.counters().placeholders == 8);
  CHECK(a.queued(0) <= 9);
}

TEST_CASE("SampleAssembler: a silent board is filled after max_lag and not filled twice when it "
          "returns with its gap",
          "[io][assembler]") {
  SampleAssembler::Options o;
  o.max_lag = 8;
  SampleAssembler a(o);
  Collector c;
  // Board 3 is silent for ticks 20..99 (80 ticks lost on the link), then returns reporting them.
  constexpr int kTicks = 200;
  for (int t = 0; t < kTicks; ++t) {
    for (int b = 0; b < 4; ++b) {
      if (b == 3 && t >= 20 && t < 100) continue;
      c.push(a, frame(b, t, (b == 3 && t == 100) ? 80 : 0));
    }
    // While board 3 is silent the others are held up by at most max_lag samples.
    CHECK(static_cast<int>(c.samples.size()) >= t + 1 - o.max_lag - 1);
  }
  REQUIRE(c.samples.size() == kTicks);  // no extra samples: no tick was filled twice
  // Board 3's later readings line up with the other boards' same ticks.
  checkAligned(c.samples, [](int w, int k) { return w == 3 && k >= 20 && k < 100; });
  CHECK(a.counters().silent_fills > 0);
  CHECK(a.counters().silent_fills + a.counters().placeholders == 80);
}

TEST_CASE("SampleAssembler: a board that returns while the others are ahead lines up",
          "[io][assembler]") {
  // As above, but board 3 comes back in the middle of a burst of the others: they are a few
  // ticks ahead of it when its gap is reported.
  SampleAssembler::Options o;
  o.max_lag = 16;
  SampleAssembler a(o);
  Collector c;
  for (int t = 0; t < 10; ++t)
    for (int b = 0; b < 4; ++b) c.push(a, frame(b, t));
  for (int t = 10; t < 60; ++t)
    for (int b = 0; b < 3; ++b) c.push(a, frame(b, t));
  CHECK(a.counters().silent_fills > 0);
  // Board 3 lost ticks 10..49; returns with tick 50 while the others are at tick 59.
  c.push(a, frame(3, 50, 40));
  for (int t = 51; t < 60; ++t) c.push(a, frame(3, t));
  for (int t = 60; t < 100; ++t)
    for (int b = 0; b < 4; ++b) c.push(a, frame(b, t));
  REQUIRE(c.samples.size() == 100);
  checkAligned(c.samples, [](int w, int k) { return w == 3 && k >= 10 && k < 50; });
  CHECK(a.counters().silent_fills + a.counters().placeholders == 40);
}

TEST_CASE("SampleAssembler: a gap of max_lag on the only streaming board keeps the alignment",
          "[io][assembler]") {
  // Boards 1..3 fall silent (frames lost) while board 0 streams on, max_lag readings queued
  // ahead of them; then board 0 itself loses exactly max_lag frames. Every tick still gets one
  // sample, and when boards 1..3 return reporting their gaps, all four line up.
  SampleAssembler a;  // default max_lag 64, kQueue 128
  const int lag = 64;
  Collector c;
  for (int t = 0; t < 10; ++t)
    for (int b = 0; b < 4; ++b) c.push(a, frame(b, t));
  for (int t = 10; t < 100; ++t) c.push(a, frame(0, t));
  CHECK(a.queued(0) == lag);
  c.push(a, frame(0, 100 + lag, lag));  // ticks 100 .. 100 + lag - 1 lost
  const int back = 100 + lag + 1;
  c.push(a, frame(0, back));
  for (int b = 1; b < 4; ++b) c.push(a, frame(b, back, static_cast<std::uint32_t>(back - 10)));
  for (int t = back + 1; t < back + 100; ++t)
    for (int b = 0; b < 4; ++b) c.push(a, frame(b, t));
  REQUIRE(c.samples.size() == static_cast<std::size_t>(back + 100));
  checkAligned(c.samples, [&](int w, int k) {
    return (w > 0 && k >= 10 && k < back) || (w == 0 && k >= 100 && k < 100 + lag);
  });
}

TEST_CASE("SampleAssembler: frames of unmapped boards are ignored and counted",
          "[io][assembler]") {
  SampleAssembler a;
  Collector c;
  for (int t = 0; t < 5; ++t) {
    for (int b = 0; b < 4; ++b) c.push(a, frame(b, t));
    CHECK(c.push(a, frame(4 + t, t)) == 0);
    CHECK(c.push(a, frame(27, t, 50)) == 0);  // its gap inserts nothing anywhere
  }
  CHECK(c.samples.size() == 5);
  CHECK(a.counters().unmapped_frames == 10);
  CHECK(a.counters().placeholders == 0);
  for (int w = 0; w < 4; ++w) CHECK(a.queued(w) == 0);
}

TEST_CASE("SampleAssembler: reset() forgets queued readings and keeps the counters",
          "[io][assembler]") {
  SampleAssembler::Options o;
  o.max_lag = 8;
  SampleAssembler a(o);
  Collector c;
  for (int t = 0; t < 5; ++t)
    for (int b = 0; b < 4; ++b) c.push(a, frame(b, t));
  // Boards 0 and 1 get ahead; board 2 silent long enough to be filled (debt), then the bridge
  // reconnects.
  for (int t = 5; t < 20; ++t)
    for (const int b : {0, 1, 3}) c.push(a, frame(b, t));
  const auto before = a.counters();
  CHECK(before.silent_fills > 0);
  CHECK(a.queued(0) > 0);
  a.reset();
  for (int w = 0; w < 4; ++w) CHECK(a.queued(w) == 0);
  CHECK(a.counters().samples == before.samples);
  CHECK(a.counters().silent_fills == before.silent_fills);
  // After the reset the boards restart in lockstep (their first frames set new baselines and
  // report no gap): one sample per tick, from the new frames only, nothing left over.
  Collector after;
  for (int t = 0; t < 30; ++t)
    for (int b = 0; b < 4; ++b) after.push(a, frame(b, t));
  REQUIRE(after.samples.size() == 30);
  checkAligned(after.samples, [](int, int) { return false; });
}

TEST_CASE("SampleAssembler: after reset() a gap is filled in full (no debt carried over)",
          "[io][assembler]") {
  SampleAssembler::Options o;
  o.max_lag = 8;
  SampleAssembler a(o);
  Collector c;
  // Board 2 silent for a while: filled, so it owes a debt of silent fills.
  for (int t = 0; t < 30; ++t)
    for (const int b : {0, 1, 3}) c.push(a, frame(b, t));
  REQUIRE(a.counters().silent_fills > 0);
  a.reset();
  Collector after;
  for (int t = 0; t < 20; ++t) {
    for (int b = 0; b < 4; ++b) {
      if (b == 2 && t >= 5 && t < 8) continue;
      after.push(a, frame(b, t, (b == 2 && t == 8) ? 3 : 0));
    }
  }
  REQUIRE(after.samples.size() == 20);
  checkAligned(after.samples, [](int w, int k) { return w == 2 && k >= 5 && k < 8; });
}
