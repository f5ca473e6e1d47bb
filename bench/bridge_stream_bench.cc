// Google Benchmark for the host bridge-stream decoder (crunch/io/bridge_stream.h) against the
// need of 28 boards x 2 kHz = 56,000 frames/s. Results and how to run them: docs/BENCHMARKS.md.
//
//   BM_Memcpy        the baseline: memcpy of the same bytes, in the same chunks, into a buffer
//                    of the stream's size (what merely moving the data costs).
//   BM_Decode        BridgeStreamDecoder::feed() over one second of a clean 28-board stream, in
//                    USB-sized chunks (512 B: one high-speed bulk packet; 16 KiB: a transfer).
//   BM_DecodeDirty   the same with 1 % of frames corrupted by one flipped bit and a burst of
//                    random garbage after every 50th frame (rejections and resynchronisation).
//   BM_BridgeDecode  bridge_decode() alone on the known frame boundaries: the CRC's share.
// Each reports items_per_second = frames/s (the stream's frames, however many were accepted).
#include <benchmark/benchmark.h>

#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

#include "crunch/core/rng.h"
#include "crunch/io/bridge_stream.h"

namespace {

constexpr int kBoards = BRIDGE_MAX_BOARDS;
constexpr int kTicks = 2000;  // one second at 2 kHz
constexpr double kNeedFramesPerSecond = kBoards * 2000.0;

// One second of all 28 boards ticked in turn; `dirty` corrupts as BM_DecodeDirty says.
std::vector<std::uint8_t> makeStream(bool dirty) {
  crunch::Rng rng(11);
  std::vector<std::uint8_t> s;
  s.reserve(static_cast<std::size_t>(kBoards * kTicks) * (BRIDGE_FRAME_LEN + 2));
  int n = 0;
  for (int k = 0; k < kTicks; ++k) {
    for (int b = 0; b < kBoards; ++b, ++n) {
      const bridge_frame_t f{static_cast<std::uint8_t>(b),
                             static_cast<std::uint16_t>(k),
                             static_cast<std::uint32_t>(k),
                             static_cast<std::uint16_t>(rng.below(65536)),
                             static_cast<std::uint16_t>(rng.below(65536)),
                             0};
      std::uint8_t out[BRIDGE_FRAME_LEN];
      bridge_encode(&f, out);
      if (dirty && rng.below(100) == 0) out[rng.below(BRIDGE_FRAME_LEN)] ^= 0x04;
      s.insert(s.end(), out, out + BRIDGE_FRAME_LEN);
      if (dirty && n % 50 == 49)
        for (std::uint32_t g = rng.below(24); g > 0; --g)
          s.push_back(static_cast<std::uint8_t>(rng.below(256)));
    }
  }
  return s;
}

const std::vector<std::uint8_t>& cleanStream() {
  static const std::vector<std::uint8_t> s = makeStream(false);
  return s;
}
const std::vector<std::uint8_t>& dirtyStream() {
  static const std::vector<std::uint8_t> s = makeStream(true);
  return s;
}

void report(benchmark::State& state, const std::vector<std::uint8_t>& s) {
  const auto frames = static_cast<std::int64_t>(kBoards * kTicks);
  state.SetItemsProcessed(state.iterations() * frames);
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(s.size()));
  state.counters["x_need"] = benchmark::Counter(static_cast<double>(frames) / kNeedFramesPerSecond,
                                                benchmark::Counter::kIsIterationInvariantRate);
}

void decode(benchmark::State& state, const std::vector<std::uint8_t>& s) {
  const auto chunk = static_cast<std::size_t>(state.range(0));
  crunch::io::BridgeStreamDecoder dec;
  std::uint64_t sum = 0;
  auto sink = [&](const crunch::io::DecodedFrame& d) { sum += d.frame.alpha; };
  for (auto _ : state) {
    for (std::size_t at = 0; at < s.size(); at += chunk)
      dec.feed(std::span<const std::uint8_t>(s).subspan(at, std::min(chunk, s.size() - at)), sink);
    benchmark::DoNotOptimize(sum);
  }
  state.counters["accepted"] =
      static_cast<double>(dec.counters().frames) / static_cast<double>(state.iterations());
  report(state, s);
}

void BM_Memcpy(benchmark::State& state) {
  const std::vector<std::uint8_t>& s = cleanStream();
  const auto chunk = static_cast<std::size_t>(state.range(0));
  std::vector<std::uint8_t> dst(s.size());
  for (auto _ : state) {
    for (std::size_t at = 0; at < s.size(); at += chunk)
      std::memcpy(dst.data() + at, s.data() + at, std::min(chunk, s.size() - at));
    benchmark::DoNotOptimize(dst.data());
    benchmark::ClobberMemory();
  }
  report(state, s);
}
BENCHMARK(BM_Memcpy)->ArgName("chunk")->Arg(512)->Arg(16384);

void BM_Decode(benchmark::State& state) { decode(state, cleanStream()); }
BENCHMARK(BM_Decode)->ArgName("chunk")->Arg(512)->Arg(16384);

void BM_DecodeDirty(benchmark::State& state) { decode(state, dirtyStream()); }
BENCHMARK(BM_DecodeDirty)->ArgName("chunk")->Arg(512)->Arg(16384);

void BM_BridgeDecode(benchmark::State& state) {
  const std::vector<std::uint8_t>& s = cleanStream();
  std::uint64_t sum = 0;
  for (auto _ : state) {
    for (std::size_t at = 0; at + BRIDGE_FRAME_LEN <= s.size(); at += BRIDGE_FRAME_LEN) {
      bridge_frame_t f;
      if (bridge_decode(s.data() + at, &f) == 0) sum += f.alpha;
    }
    benchmark::DoNotOptimize(sum);
  }
  report(state, s);
}
BENCHMARK(BM_BridgeDecode);

}  // namespace

BENCHMARK_MAIN();
