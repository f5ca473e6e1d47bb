// Google Benchmark for the per-byte data path of `crunchhost --robot` (issue 5, "Speed"): USB
// chunks through the SPSC ring into the bridge decoder, the sample assembler and the signal
// pipeline, as session/robot_session.cc wires them, against the need of 28 boards x 2 kHz =
// 56,000 frames/s; and the latency from the USB chunk that completes a contact episode to the
// episode and to its WhiskEvidence report. Results and how to run them: docs/BENCHMARKS.md.
//
// The stream: 28 VirtualWhiskerBoards (the firmware core, crunch_sim) ticked in turn, 18-byte
// bridge frames. Boards 0..3 are the four whiskers and read synthetic whisker signals (rest,
// then contact bumps, test/signal/synthetic.h); boards 4..27 read rest plus noise, and the
// assembler counts their frames as unmapped, as the robot's does with extra boards.
//
// Throughput (items_per_second = frames/s of the stream, x_need = that / 56,000; real time;
// x_need_proc_cpu: the same from the process's CPU time, see report()):
//   BM_RingMemcpy        baseline, ring alone: a producer thread (the USB event thread) assigns
//                        4096-byte io::Chunks and pushes them into io::SpscRing<io::Chunk>(256);
//                        the benchmark thread drains them and memcpys the bytes out.
//   BM_Decode            baseline, decoder alone: BridgeStreamDecoder::feed() over the same
//                        bytes in 4096-byte pieces, no ring, no thread.
//   BM_RingDecodeAssemble  the ring as in BM_RingMemcpy, then decoder + SampleAssembler.
//   BM_RingFullPipeline  the same, then signal::SignalPipeline (shipped models) on the samples:
//                        the full per-sample cost.
// One iteration is one pass over 4 s of stream (224,000 frames, 985 chunks). When the ring is
// full the producer yields and retries (the app drops instead): `full_waits` counts the retries.
//
// Latency (BM_ContactLatency, one iteration = kEpisodes contact episodes): 1 ms of frames per
// chunk (2 ticks x 28 boards = 1008 bytes), as the bridge's transfers deliver them. Lock-step:
// the producer stamps and pushes a chunk only once the consumer has finished the previous one,
// and waits for it before making the next, so every chunk arrives at an idle consumer as it
// does in real time (1 ms between chunks, microseconds of work each) without taking real time.
// The consumer spins on the ring (yielding); the app's control loop instead wakes from
// CreateBase::poll(0.002), which can add up to 2 ms (docs/BENCHMARKS.md).
//   lat_episode_*  from the chunk's t_ns (stamped just before it is assigned and pushed, as the
//                  USB callback does) to SignalPipeline::push returning the episode
//   lat_report_*   to WhiskEvidence::take having the episode's reports
//   pickup_p50_us  of lat_episode: from the stamp until the consumer starts on the chunk
//   completing_push_p50_us  of lat_episode: the SignalPipeline::push call that completes the
//                  episode (radial and orientation models evaluated)
//   struct_*       the pipeline's structural delay, in stream time: from the first onset to the
//                  completing sample (ContactEpisode::duration_s), and from the start of the
//                  touch in the signal to it. By design (paper §2.5): the window is 2 s.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <span>
#include <string>
#include <thread>
#include <time.h>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/core/rng.h"
#include "crunch/io/bridge_stream.h"
#include "crunch/io/recording.h"
#include "crunch/io/sample_assembler.h"
#include "crunch/io/spsc_ring.h"
#include "crunch/robot/shapelet.h"
#include "crunch/session/whisk_evidence.h"
#include "crunch/signal/models_io.h"
#include "crunch/signal/pipeline.h"
#include "crunch_sim/training.h"
#include "crunch_sim/virtual_whisker_board.h"
#include "signal/synthetic.h"

namespace {

using namespace crunch;
namespace syn = crunch::signal::testing;

constexpr int kBoards = BRIDGE_MAX_BOARDS;
constexpr double kNeedFramesPerSecond = kBoards * 2000.0;
constexpr std::size_t kRingSlots = 256;  // as host/app/robot_mode.cc
constexpr double kNoiseCodes = 3.0;      // sensor noise, LSB (keeps frames from going STALE)

// The 28 boards. tick() appends one 500 us period of all of them, board 0 first.
class BoardBank {
 public:
  explicit BoardBank(std::uint64_t seed) : rng_(seed) {
    for (int b = 0; b < kBoards; ++b)
      boards_.push_back(std::make_unique<sim::VirtualWhiskerBoard>(static_cast<std::uint8_t>(b)));
  }
  void tick(const signal::SampleFrame& whiskers, std::vector<std::uint8_t>& out) {
    for (int b = 0; b < kBoards; ++b) {
      sim::VirtualWhiskerBoard& board = *boards_[static_cast<std::size_t>(b)];
      if (b < signal::kWhiskers) {
        const signal::WhiskerReading& r = whiskers[static_cast<std::size_t>(b)];
        board.sensor().setReading(r.alpha, r.beta);
      } else {
        board.sensor().setReading(syn::code(0.0, kNoiseCodes, rng_),
                                  syn::code(0.0, kNoiseCodes, rng_));
      }
      const auto sent = board.tick();
      out.insert(out.end(), sent.begin(), sent.end());
    }
  }

 private:
  std::vector<std::unique_ptr<sim::VirtualWhiskerBoard>> boards_;
  Rng rng_;
};

// The whiskers' signal: 1.5 s at rest (the detectors calibrate), then `contacts` segments of
// `segment_s`, each a contact of 1-4 whiskers with peak deflections in the models' f1 range.
// touch_start[i] is the sample index where contact i's first bump begins.
struct WhiskerSignal {
  std::vector<signal::SampleFrame> frames;
  std::vector<std::uint64_t> touch_start;
};

WhiskerSignal makeSignal(int contacts, double segment_s, std::uint64_t seed) {
  Rng rng(seed);
  WhiskerSignal s;
  s.frames = syn::quiet(syn::kCalibrationSeconds, kNoiseCodes, rng);
  constexpr double kLead = 0.1;
  for (int i = 0; i < contacts; ++i) {
    syn::Touches t{};
    const int first = static_cast<int>(rng.below(signal::kWhiskers));
    const int count = 1 + static_cast<int>(rng.below(signal::kWhiskers));
    double min_delay = 1.0;
    for (int k = 0; k < count; ++k) {
      auto& touch = t[static_cast<std::size_t>((first + k) % signal::kWhiskers)];
      touch.amplitude = 0.2 + 0.2 * rng.uniform();  // rad: f1 0.2..0.4, r 0.10..0.13 m
      touch.beta_share = 0.1 + 0.4 * rng.uniform();
      touch.delay = k == 0 ? 0.0 : 0.1 * rng.uniform();
      min_delay = std::min(min_delay, touch.delay);
    }
    s.touch_start.push_back(s.frames.size() +
                            static_cast<std::uint64_t>((kLead + min_delay) * signal::kSampleRateHz));
    syn::append(s.frames, syn::contactFrames(t, segment_s, kNoiseCodes, rng, kLead));
  }
  return s;
}

// The throughput stream: 4 s (one contact) of all 28 boards.
const std::vector<std::uint8_t>& throughputStream() {
  static const std::vector<std::uint8_t> bytes = [] {
    const WhiskerSignal sig = makeSignal(1, 2.5, 7);
    BoardBank bank(8);
    std::vector<std::uint8_t> out;
    out.reserve(sig.frames.size() * kBoards * BRIDGE_FRAME_LEN);
    for (const signal::SampleFrame& f : sig.frames) bank.tick(f, out);
    return out;
  }();
  return bytes;
}
std::int64_t streamFrames() {
  return static_cast<std::int64_t>(throughputStream().size() / BRIDGE_FRAME_LEN);
}

signal::PipelineOptions pipelineOptions() { return sim::physicsRigOptions().pipeline; }

const signal::SignalModels& shippedModels() {
  static const signal::SignalModels models = [] {
    auto m = signal::loadModels(CRUNCH_SOURCE_DIR "/models/sim_models.json");
    if (!m) {
      std::fprintf(stderr, "robot_io_bench: %s\n", m.error().message.c_str());
      std::abort();
    }
    return std::move(m).value();
  }();
  return models;
}

signal::SignalPipeline makePipeline() {
  auto p = signal::SignalPipeline::create(pipelineOptions());
  if (!p) {
    std::fprintf(stderr, "robot_io_bench: %s\n", p.error().message.c_str());
    std::abort();
  }
  if (auto st = p.value().setModels(shippedModels()); !st) {
    std::fprintf(stderr, "robot_io_bench: %s\n", st.error().message.c_str());
    std::abort();
  }
  return std::move(p).value();
}

// The USB event thread for the throughput benchmarks: on each startPass() it pushes the whole
// stream once in 4096-byte chunks, as UsbBridge's on_chunk does (robot_mode.cc), retrying
// (yield) when the ring is full.
class ChunkProducer {
 public:
  ChunkProducer(io::SpscRing<io::Chunk>& ring, std::span<const std::uint8_t> stream)
      : ring_(ring), stream_(stream), thread_([this] { run(); }) {}
  ~ChunkProducer() {
    stop_.store(true);
    requested_.fetch_add(1);
    requested_.notify_one();
    thread_.join();
  }
  ChunkProducer(const ChunkProducer&) = delete;
  ChunkProducer& operator=(const ChunkProducer&) = delete;

  void startPass() {
    requested_.fetch_add(1);
    requested_.notify_one();
  }
  std::size_t chunksPerPass() const {
    return (stream_.size() + io::kMaxChunkBytes - 1) / io::kMaxChunkBytes;
  }

 private:
  void run() {
    io::Chunk chunk;  // the staging slot, as the USB thread's thread_local one
    std::uint64_t done = 0;
    while (true) {
      requested_.wait(done);
      if (stop_.load()) return;
      ++done;
      std::span<const std::uint8_t> bytes = stream_;
      while (!bytes.empty()) {
        const std::size_t n = chunk.assign(io::StreamId::kBridge, io::monotonicNs(), bytes);
        while (!ring_.tryPush(chunk)) std::this_thread::yield();
        bytes = bytes.subspan(n);
      }
    }
  }

  io::SpscRing<io::Chunk>& ring_;
  std::span<const std::uint8_t> stream_;
  std::atomic<std::uint64_t> requested_{0};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// CPU time of the whole process (producer and consumer threads), seconds.
double processCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// `cpu_s`: the process CPU time the timed loop took. Its x_need (`x_need_proc_cpu`) is the
// cost of the path on one core whatever else runs on the machine, when the benchmark is
// pinned to one core (taskset -c 0): then a waiting thread yields to the other instead of
// spinning beside it.
void report(benchmark::State& state, const io::SpscRing<io::Chunk>* ring, double cpu_s) {
  const std::int64_t frames = streamFrames();
  state.counters["x_need_proc_cpu"] = static_cast<double>(frames) *
                                      static_cast<double>(state.iterations()) /
                                      (cpu_s * kNeedFramesPerSecond);
  state.SetItemsProcessed(state.iterations() * frames);
  state.SetBytesProcessed(state.iterations() *
                          static_cast<std::int64_t>(throughputStream().size()));
  state.counters["x_need"] = benchmark::Counter(static_cast<double>(frames) / kNeedFramesPerSecond,
                                                benchmark::Counter::kIsIterationInvariantRate);
  if (ring != nullptr) {
    state.counters["full_waits"] =
        static_cast<double>(ring->dropped()) / static_cast<double>(state.iterations());
  }
}

// Runs one pass per iteration through the ring, handing each chunk to `consume`.
template <typename Consume>
void throughRing(benchmark::State& state, Consume&& consume) {
  io::SpscRing<io::Chunk> ring(kRingSlots);
  ChunkProducer producer(ring, throughputStream());
  const std::size_t chunks = producer.chunksPerPass();
  const double cpu0 = processCpuSeconds();
  for (auto _ : state) {
    producer.startPass();
    std::size_t got = 0;
    while (got < chunks) {
      const std::size_t n = ring.drain(consume);
      if (n == 0) std::this_thread::yield();
      got += n;
    }
  }
  report(state, &ring, processCpuSeconds() - cpu0);
}

void BM_RingMemcpy(benchmark::State& state) {
  std::vector<std::uint8_t> dst(throughputStream().size());
  std::size_t at = 0;
  throughRing(state, [&](const io::Chunk& c) {
    if (at + c.size > dst.size()) at = 0;
    std::memcpy(dst.data() + at, c.bytes.data(), c.size);
    at += c.size;
    benchmark::ClobberMemory();
  });
  benchmark::DoNotOptimize(dst.data());
}
BENCHMARK(BM_RingMemcpy)->UseRealTime();

void BM_Decode(benchmark::State& state) {
  const std::vector<std::uint8_t>& s = throughputStream();
  io::BridgeStreamDecoder dec;
  std::uint64_t sum = 0;
  auto sink = [&](const io::DecodedFrame& d) { sum += d.frame.alpha; };
  const double cpu0 = processCpuSeconds();
  for (auto _ : state) {
    for (std::size_t at = 0; at < s.size(); at += io::kMaxChunkBytes)
      dec.feed(std::span<const std::uint8_t>(s).subspan(
                   at, std::min(io::kMaxChunkBytes, s.size() - at)),
               sink);
    benchmark::DoNotOptimize(sum);
  }
  state.counters["accepted"] =
      static_cast<double>(dec.counters().frames) / static_cast<double>(state.iterations());
  report(state, nullptr, processCpuSeconds() - cpu0);
}
BENCHMARK(BM_Decode)->UseRealTime();

void BM_RingDecodeAssemble(benchmark::State& state) {
  io::BridgeStreamDecoder dec;
  io::SampleAssembler assembler;
  std::uint64_t sum = 0;
  auto onSample = [&](const signal::SampleFrame& f) { sum += f[0].alpha; };
  throughRing(state, [&](const io::Chunk& c) {
    dec.feed(c.data(), [&](const io::DecodedFrame& d) { assembler.push(d, onSample); });
  });
  benchmark::DoNotOptimize(sum);
  const auto it = static_cast<double>(state.iterations());
  state.counters["samples"] = static_cast<double>(assembler.counters().samples) / it;
  state.counters["unmapped"] = static_cast<double>(assembler.counters().unmapped_frames) / it;
  state.counters["crc_fail"] = static_cast<double>(dec.counters().crc_failures);
}
BENCHMARK(BM_RingDecodeAssemble)->UseRealTime();

void BM_RingFullPipeline(benchmark::State& state) {
  io::BridgeStreamDecoder dec;
  io::SampleAssembler assembler;
  signal::SignalPipeline pipeline = makePipeline();
  std::uint64_t episodes = 0;
  auto onSample = [&](const signal::SampleFrame& f) {
    if (pipeline.push(f) != nullptr) ++episodes;
  };
  throughRing(state, [&](const io::Chunk& c) {
    dec.feed(c.data(), [&](const io::DecodedFrame& d) { assembler.push(d, onSample); });
  });
  const auto it = static_cast<double>(state.iterations());
  state.counters["samples"] = static_cast<double>(pipeline.counts().samples) / it;
  state.counters["episodes"] = static_cast<double>(episodes) / it;
}
BENCHMARK(BM_RingFullPipeline)->UseRealTime();

// ---- Latency ------------------------------------------------------------------------------

constexpr int kEpisodes = 100;
constexpr double kSegmentS = 3.0;  // one contact per 3 s: the episode ends ~2.15 s after onset
constexpr int kTicksPerChunk = 2;  // 1 ms of frames per USB chunk

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(p * static_cast<double>(v.size() - 1) + 0.5);
  return v[std::min(i, v.size() - 1)];
}

void BM_ContactLatency(benchmark::State& state) {
  const WhiskerSignal sig = makeSignal(kEpisodes, kSegmentS, 21);
  const std::size_t ticks = sig.frames.size() - sig.frames.size() % kTicksPerChunk;
  const std::size_t total_chunks = ticks / kTicksPerChunk;

  std::vector<double> lat_episode, lat_report, struct_onset, struct_touch, pickup, completing;
  pickup.reserve(2 * kEpisodes);
  completing.reserve(2 * kEpisodes);
  lat_episode.reserve(2 * kEpisodes);
  lat_report.reserve(2 * kEpisodes);
  struct_onset.reserve(2 * kEpisodes);
  struct_touch.reserve(2 * kEpisodes);
  int reports = 0;
  std::uint64_t max_queue = 0;

  for (auto _ : state) {
    io::SpscRing<io::Chunk> ring(kRingSlots);
    io::BridgeStreamDecoder dec;
    io::SampleAssembler assembler;
    signal::SignalPipeline pipeline = makePipeline();
    WhiskEvidence evidence(defaultWhiskerArray(), WhiskerBeam{});
    std::vector<ContactReport> out_reports;
    std::vector<FreeRay> out_rays;
    out_reports.reserve(16);
    out_rays.reserve(16);
    evidence.begin();
    std::atomic<std::uint64_t> consumed{0};

    // The USB event thread: makes chunk k, waits until chunk k-1 is handled, stamps and pushes.
    std::thread producer([&] {
      BoardBank bank(22);
      std::vector<std::uint8_t> bytes;
      bytes.reserve(kTicksPerChunk * kBoards * BRIDGE_FRAME_LEN + 64);
      io::Chunk chunk;
      for (std::size_t k = 0; k < total_chunks; ++k) {
        bytes.clear();
        for (int t = 0; t < kTicksPerChunk; ++t)
          bank.tick(sig.frames[k * kTicksPerChunk + static_cast<std::size_t>(t)], bytes);
        chunk.assign(io::StreamId::kBridge, io::monotonicNs(), bytes);
        while (!ring.tryPush(chunk)) std::this_thread::yield();  // never full in lock-step
        while (consumed.load(std::memory_order_acquire) <= k) std::this_thread::yield();
      }
    });

    // The control loop: drains the ring as robot_session.cc handles a bridge chunk.
    std::uint64_t chunk_t = 0, chunk_picked = 0;
    std::size_t next_touch = 0;
    auto onSample = [&](const signal::SampleFrame& f) {
      const std::uint64_t t0 = io::monotonicNs();
      const signal::ContactEpisode* ep = pipeline.push(f);
      if (ep == nullptr) return;
      const std::uint64_t t1 = io::monotonicNs();
      pickup.push_back(static_cast<double>(chunk_picked - chunk_t) * 1e-3);
      completing.push_back(static_cast<double>(t1 - t0) * 1e-3);
      evidence.take(*ep, [](std::uint64_t) { return Pose2{}; });
      const std::uint64_t t2 = io::monotonicNs();
      lat_episode.push_back(static_cast<double>(t1 - chunk_t) * 1e-3);
      lat_report.push_back(static_cast<double>(t2 - chunk_t) * 1e-3);
      struct_onset.push_back(ep->duration_s);
      // The completing sample is pipeline sample counts().samples - 1 = its stream tick.
      const std::uint64_t end_sample = pipeline.counts().samples - 1;
      while (next_touch + 1 < sig.touch_start.size() &&
             sig.touch_start[next_touch + 1] <= ep->start_sample)
        ++next_touch;
      if (next_touch < sig.touch_start.size() && sig.touch_start[next_touch] <= end_sample) {
        struct_touch.push_back(static_cast<double>(end_sample - sig.touch_start[next_touch]) /
                               signal::kSampleRateHz);
      }
      out_reports.clear();
      out_rays.clear();
      evidence.end(out_reports, out_rays);
      reports += static_cast<int>(out_reports.size());
      evidence.begin();
    };
    auto onFrame = [&](const io::DecodedFrame& d) { assembler.push(d, onSample); };
    std::uint64_t got = 0;
    while (got < total_chunks) {
      max_queue = std::max<std::uint64_t>(max_queue, ring.size());
      const std::size_t n = ring.drain([&](const io::Chunk& c) {
        chunk_picked = io::monotonicNs();
        chunk_t = c.t_ns;
        dec.feed(c.data(), onFrame);
        consumed.store(++got, std::memory_order_release);
      });
      if (n == 0) std::this_thread::yield();
    }
    producer.join();
  }

  const double n = static_cast<double>(lat_episode.size());
  const double it = static_cast<double>(state.iterations());
  state.counters["episodes"] = n / it;
  state.counters["reports"] = static_cast<double>(reports) / it;
  state.counters["lat_episode_p50_us"] = percentile(lat_episode, 0.5);
  state.counters["lat_episode_p99_us"] = percentile(lat_episode, 0.99);
  state.counters["lat_episode_max_us"] = percentile(lat_episode, 1.0);
  state.counters["lat_report_p50_us"] = percentile(lat_report, 0.5);
  state.counters["lat_report_p99_us"] = percentile(lat_report, 0.99);
  state.counters["lat_report_max_us"] = percentile(lat_report, 1.0);
  state.counters["pickup_p50_us"] = percentile(pickup, 0.5);
  state.counters["completing_push_p50_us"] = percentile(completing, 0.5);
  state.counters["struct_onset_p50_s"] = percentile(struct_onset, 0.5);
  state.counters["struct_onset_max_s"] = percentile(struct_onset, 1.0);
  state.counters["struct_touch_p50_s"] = percentile(struct_touch, 0.5);
  state.counters["struct_touch_max_s"] = percentile(struct_touch, 1.0);
  state.counters["max_queue"] = static_cast<double>(max_queue);
}
BENCHMARK(BM_ContactLatency)->Iterations(1)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
