// The host side of the whisker-board link (paper §2.1): a streaming decoder for the byte stream
// the FPGA bridge delivers over USB bulk transfers, which carries the 18-byte bridge frames of up
// to 28 whisker boards (docs/protocol.md is the definition of the frame and of the
// resynchronisation rule; "Host decoder" there describes this class).
//
// feed() takes the bytes as they arrive, in chunks of any size: a frame may be split across
// chunks, a chunk may hold several frames, and garbage may lie between them. The decoder scans
// for the sync bytes A5 5A and checks the frame with the firmware's own C code (bridge_decode():
// CRC-16 over bytes 2..15, then version and board id), so host and board cannot disagree about
// the format. A frame that fails is dropped and counted, and only its first byte is discarded:
// the scan resumes one byte later, since a real frame may begin inside a rejected one. The
// result — frames delivered and every counter — is the same however the stream is chunked.
//
// Per board, the sequence number and timestamp tell the two kinds of loss apart
// (docs/protocol.md, "Sequence number and timestamp"):
//   - a sequence gap: frames lost after the board (link noise, bridge overflow); the missing
//     frames are counted, across the uint16 wrap;
//   - a timestamp gap with consecutive sequence numbers on a frame marked BRIDGE_ST_DROPPED:
//     samples the board itself dropped (its ring overflowed); the missing samples are counted.
//
// Ownership: the decoder owns all its state (one frame of buffer and the counters); it keeps no
// reference to the bytes given to feed() nor to the sink after feed() returns.
// Thread-safety: none; one reader thread owns a decoder. Counters may be read between feeds.
// Allocation: none, ever. feed() runs on the fixed internal buffer and delivers each frame to
// the caller's sink by reference.
#pragma once

#include <array>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <span>
#include <type_traits>

extern "C" {
#include "whisker/bridge_frame.h"
}

namespace crunch::io {

// One accepted frame with what the decoder learnt about the stream just before it.
struct DecodedFrame {
  bridge_frame_t frame{};             // the fields of a frame that passed bridge_decode()
  std::uint32_t frames_lost = 0;      // this board's frames lost on the link just before it
  std::uint32_t samples_dropped = 0;  // samples the board dropped just before it (DROPPED)
};

// Per-board counters. A board's first frame (or its first after a restart) sets the baseline
// and counts no gap.
struct BoardCounters {
  std::uint64_t frames = 0;              // frames accepted from this board
  std::uint64_t lost_frames = 0;         // frames missing by sequence number (lost after the board)
  std::uint64_t dropped_samples = 0;     // samples missing by timestamp, with consecutive sequence
                                         // numbers, on a frame carrying BRIDGE_ST_DROPPED
  std::uint64_t unmarked_tick_gaps = 0;  // timestamp gaps with consecutive sequence numbers but
                                         // no DROPPED bit: against the protocol, counted only
  std::uint64_t restarts = 0;   // the timestamp did not advance (board reset, or a repeated
                                // frame): tracking restarted from that frame, no loss counted
  std::uint64_t not_fresh = 0;  // frames whose status is not 0 (STALE, NO_DATA, DROPPED, MLX)
  std::uint16_t last_seq = 0;   // of the last accepted frame; valid when frames > 0
  std::uint32_t last_tick = 0;  // timestamp (500 us ticks) of the last accepted frame
};

struct BridgeStreamCounters {
  std::uint64_t bytes = 0;          // bytes given to feed()
  std::uint64_t frames = 0;         // frames accepted and delivered, all boards
  std::uint64_t skipped_bytes = 0;  // bytes discarded while hunting for a frame, including the
                                    // first byte of each rejected frame
  std::uint64_t crc_failures = 0;   // 18 bytes after a sync whose CRC did not match
  std::uint64_t bad_version = 0;    // CRC good, version is not BRIDGE_VERSION
  std::uint64_t bad_board = 0;      // CRC and version good, board id >= BRIDGE_MAX_BOARDS
  std::array<BoardCounters, BRIDGE_MAX_BOARDS> boards{};

  // The boards' lost_frames and dropped_samples, summed.
  std::uint64_t lostFrames() const {
    std::uint64_t n = 0;
    for (const BoardCounters& b : boards) n += b.lost_frames;
    return n;
  }
  std::uint64_t droppedSamples() const {
    std::uint64_t n = 0;
    for (const BoardCounters& b : boards) n += b.dropped_samples;
    return n;
  }
};
// Invariant after every feed(): bytes == BRIDGE_FRAME_LEN * frames + skipped_bytes + pending(),
// and frames == the sum of boards[b].frames.

// A non-owning reference to a callable taking `const DecodedFrame&` (a function_ref): lets
// feed() live in the .cc file without std::function's allocation. Valid while the callable is.
class FrameSink {
 public:
  template <typename F>
  requires(!std::same_as<std::remove_cvref_t<F>, FrameSink> &&
           std::invocable<F&, const DecodedFrame&>)
      FrameSink(F&& f)  // NOLINT(google-explicit-constructor): lambdas convert implicitly
      : object_(const_cast<void*>(static_cast<const void*>(&f))),
        call_([](void* o, const DecodedFrame& d) {
          (*static_cast<std::remove_reference_t<F>*>(o))(d);
        }) {}

  void operator()(const DecodedFrame& d) const { call_(object_, d); }

 private:
  void* object_;
  void (*call_)(void*, const DecodedFrame&);
};

class BridgeStreamDecoder {
 public:
  BridgeStreamDecoder() = default;
  BridgeStreamDecoder(const BridgeStreamDecoder&) = delete;
  BridgeStreamDecoder& operator=(const BridgeStreamDecoder&) = delete;

  // Decodes `bytes`, the next part of the stream, calling `sink` once per accepted frame, in
  // stream order, before returning. Bytes that may begin a frame completed by a later chunk are
  // kept (at most BRIDGE_FRAME_LEN - 1). Returns the number of frames delivered by this call.
  // A corrupt frame is never delivered; it shows only in the counters. The sink may read
  // counters() (they include the frame it is given) but must not call feed() or reset().
  std::size_t feed(std::span<const std::uint8_t> bytes, FrameSink sink);

  const BridgeStreamCounters& counters() const { return counters_; }
  // Bytes held from the last feed() as the possible start of a frame (0..17).
  std::size_t pending() const { return pending_; }

  // Forgets the held bytes and every board's sequence/timestamp baseline (a reopened device);
  // the counters are kept.
  void resync();
  // Forgets everything, counters included.
  void reset();

 private:
  // Decodes 18 bytes starting with the sync; accepts and delivers, or counts the failure.
  bool tryFrame(const std::uint8_t* p, FrameSink& sink);
  // Per-board bookkeeping of an accepted frame; fills the gap fields of `d`.
  void track(DecodedFrame& d);
  // Keeps the tail of a scan shorter than a frame: from its first possible sync on.
  void keepTail(const std::uint8_t* p, std::size_t n);

  std::array<std::uint8_t, BRIDGE_FRAME_LEN> buf_{};
  std::size_t pending_ = 0;
  std::array<bool, BRIDGE_MAX_BOARDS> tracking_{};  // a board's last_seq/last_tick are a baseline
  BridgeStreamCounters counters_{};
};

}  // namespace crunch::io
