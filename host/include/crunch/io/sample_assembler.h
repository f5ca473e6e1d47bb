// From the boards' frames to the signal pipeline's samples (paper §2.1): the bridge delivers each
// whisker board's frames separately, interleaved as they arrive; the signal pipeline wants one
// SampleFrame (signal/sample.h) per 500 us tick with all four whiskers. The assembler keeps one
// short queue per whisker and emits a sample as soon as every whisker has a reading.
//
// Keeping the 2 kHz time base through losses (signal/sample.h: "a tick with no frame from a
// board should be fed as a reading with a NO_DATA bit"):
//   - a frame the decoder reports after a gap (DecodedFrame::frames_lost + samples_dropped) is
//     preceded in its whisker's queue by that many placeholder readings, status kTimeout (a
//     NO_DATA bit: no measurement), at most max_lag of them;
//   - a whisker whose board has gone silent while the others keep streaming is filled with
//     placeholders once another whisker's queue is max_lag readings ahead, so the others are
//     never held up by more than max_lag samples (32 ms at the default); when that board's
//     frames return, its gap is filled only for the ticks not filled already.
// Frames from boards that are not mapped to a whisker are ignored and counted.
//
// Allocation: none (fixed queues). Thread-safety: none; the consumer thread owns it.
#pragma once

#include <array>
#include <cstdint>

#include "crunch/io/bridge_stream.h"
#include "crunch/signal/sample.h"

namespace crunch::io {

class SampleAssembler {
 public:
  static constexpr int kQueue = 128;  // readings per whisker queue
  struct Options {
    // The board id of whisker w (bridge frame `board` field); the default is board w.
    std::array<std::uint8_t, signal::kWhiskers> board_of_whisker{0, 1, 2, 3};
    int max_lag = 64;  // samples, 1 .. kQueue - 1
  };
  struct Counters {
    std::uint64_t samples = 0;           // SampleFrames emitted
    std::uint64_t placeholders = 0;      // readings inserted for missing frames (gaps)
    std::uint64_t silent_fills = 0;      // readings inserted for a board that fell behind
    std::uint64_t unmapped_frames = 0;   // frames of boards that are no whisker's
  };

  SampleAssembler() : SampleAssembler(Options{}) {}
  explicit SampleAssembler(const Options& options);

  // Adds one decoded frame; calls sink(const signal::SampleFrame&) for every sample completed,
  // in time order. Returns how many.
  template <typename Sink>
  int push(const DecodedFrame& d, Sink&& sink) {
    const int w = whiskerOf(d.frame.board);
    if (w < 0) {
      ++counters_.unmapped_frames;
      return 0;
    }
    // Ticks already filled while the board was silent are not filled twice.
    std::uint64_t gap = std::uint64_t{d.frames_lost} + d.samples_dropped;
    const auto wi = static_cast<std::size_t>(w);
    gap = gap > debt_[wi] ? gap - debt_[wi] : 0;
    debt_[wi] = 0;
    int n = 0;
    // Emits after every reading queued, placeholders included, so no queue ever holds more than
    // max_lag + 1 readings (queuing a whole gap first could overrun kQueue and lose a reading).
    auto emit = [&] {
      while (ready()) {
        sink(static_cast<const signal::SampleFrame&>(pop()));
        ++n;
      }
    };
    for (std::uint64_t i = 0; i < gap && i < static_cast<std::uint64_t>(options_.max_lag); ++i) {
      enqueue(w, placeholder());
      ++counters_.placeholders;
      emit();
    }
    enqueue(w, signal::WhiskerReading{d.frame.alpha, d.frame.beta, d.frame.status});
    emit();
    return n;
  }

  // Forgets queued readings (a reconnected bridge); counters are kept.
  void reset();
  const Counters& counters() const { return counters_; }
  // Readings queued for whisker w.
  int queued(int w) const { return count_[static_cast<std::size_t>(w)]; }

 private:
  static signal::WhiskerReading placeholder() { return {0, 0, signal::status::kTimeout}; }
  int whiskerOf(std::uint8_t board) const;
  void enqueue(int w, const signal::WhiskerReading& r);
  // Every whisker has a reading, or one is max_lag ahead (the empty ones are filled).
  bool ready();
  const signal::SampleFrame& pop();

  Options options_;
  std::array<std::array<signal::WhiskerReading, kQueue>, signal::kWhiskers> queue_{};
  std::array<int, signal::kWhiskers> head_{};
  std::array<int, signal::kWhiskers> count_{};
  std::array<std::uint64_t, signal::kWhiskers> debt_{};  // silent fills not yet matched by a gap
  signal::SampleFrame out_{};
  Counters counters_;
};

}  // namespace crunch::io
