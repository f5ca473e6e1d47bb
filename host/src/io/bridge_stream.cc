#include "crunch/io/bridge_stream.h"

#include <algorithm>
#include <cstring>

extern "C" {
#include "whisker/error.h"
}

namespace crunch::io {

namespace {
constexpr std::size_t kLen = BRIDGE_FRAME_LEN;
constexpr std::uint8_t kSync0 = BRIDGE_SYNC0;
constexpr std::uint8_t kSync1 = BRIDGE_SYNC1;
constexpr std::size_t kVersionOffset = 3;  // docs/protocol.md, "The frame"
}  // namespace

std::size_t BridgeStreamDecoder::feed(std::span<const std::uint8_t> bytes, FrameSink sink) {
  const std::uint8_t* p = bytes.data();
  const std::size_t n = bytes.size();
  const std::uint64_t frames_before = counters_.frames;
  counters_.bytes += n;
  std::size_t i = 0;

  // 1. Complete the frame held from earlier chunks. Its bytes live only in buf_, so a rejected
  //    frame is rescanned from there.
  while (pending_ > 0 && i < n) {
    if (pending_ == 1 && p[i] != kSync1) {
      // The held A5 is not followed by 5A: drop it and scan p[i] afresh below.
      ++counters_.skipped_bytes;
      pending_ = 0;
      break;
    }
    const std::size_t take = std::min(kLen - pending_, n - i);
    std::memcpy(buf_.data() + pending_, p + i, take);
    pending_ += take;
    i += take;
    if (pending_ < kLen) break;  // the chunk ended first
    pending_ = 0;
    if (!tryFrame(buf_.data(), sink)) {
      // Discard the A5 only; a real frame may start in the other 17 bytes.
      ++counters_.skipped_bytes;
      std::array<std::uint8_t, kLen - 1> rest{};
      std::memcpy(rest.data(), buf_.data() + 1, rest.size());
      keepTail(rest.data(), rest.size());
    }
  }
  if (pending_ > 0) return static_cast<std::size_t>(counters_.frames - frames_before);

  // 2. Frames read in place from the chunk while a whole one may still fit.
  while (n - i >= kLen) {
    if (p[i] == kSync0 && p[i + 1] == kSync1 && tryFrame(p + i, sink)) {
      i += kLen;
      continue;
    }
    // Not a frame here: skip this byte, then jump to the next A5 that leaves room for a frame.
    ++counters_.skipped_bytes;
    ++i;
    const std::size_t room = n - i >= kLen ? n - i - kLen + 1 : 0;
    const void* next = room > 0 ? std::memchr(p + i, kSync0, room) : nullptr;
    const std::size_t to =
        next != nullptr ? static_cast<std::size_t>(static_cast<const std::uint8_t*>(next) - p)
                        : i + room;
    counters_.skipped_bytes += to - i;
    i = to;
  }

  // 3. Fewer than 18 bytes left: keep them from the first possible sync on.
  if (i < n) keepTail(p + i, n - i);
  return static_cast<std::size_t>(counters_.frames - frames_before);
}

bool BridgeStreamDecoder::tryFrame(const std::uint8_t* p, FrameSink& sink) {
  DecodedFrame d;
  const int rc = bridge_decode(p, &d.frame);
  if (rc != FW_OK) {
    // The callers checked the sync, so the failure is the CRC or the header.
    if (rc == FW_ECRC) {
      ++counters_.crc_failures;
    } else if (p[kVersionOffset] != BRIDGE_VERSION) {
      ++counters_.bad_version;
    } else {
      ++counters_.bad_board;
    }
    return false;
  }
  track(d);
  ++counters_.frames;
  sink(d);  // after the counters, so the sink sees them including this frame
  return true;
}

void BridgeStreamDecoder::track(DecodedFrame& d) {
  const bridge_frame_t& f = d.frame;
  BoardCounters& b = counters_.boards[f.board];
  ++b.frames;
  if (f.status != 0u) ++b.not_fresh;

  if (tracking_[f.board]) {
    // Modular differences: both fields wrap (uint16 sequence, uint32 timestamp).
    const auto dt = static_cast<std::int32_t>(f.tick - b.last_tick);
    const auto ds = static_cast<std::uint16_t>(f.seq - b.last_seq);
    std::uint64_t lost = static_cast<std::uint16_t>(ds - 1u);
    const std::uint64_t max_lost = dt > 0 ? static_cast<std::uint64_t>(dt) - 1u : 0u;
    if (dt <= 0 || lost > max_lost) {
      // Time stood still or went back (a reset, a repeated frame), or more frames are missing
      // than ticks passed: the two fields disagree. Start again from this frame.
      ++b.restarts;
    } else {
      // More than 65535 lost frames alias modulo 2^16. Every frame takes at least one tick, and
      // the board normally drops nothing, so take the largest count the timestamp allows.
      lost += ((max_lost - lost) >> 16) << 16;
      if (lost > 0) {
        b.lost_frames += lost;
        d.frames_lost = static_cast<std::uint32_t>(lost);
      } else if (max_lost > 0) {
        // Consecutive sequence numbers, a timestamp gap: samples lost inside the board.
        if ((f.status & BRIDGE_ST_DROPPED) != 0u) {
          b.dropped_samples += max_lost;
          d.samples_dropped = static_cast<std::uint32_t>(max_lost);
        } else {
          ++b.unmarked_tick_gaps;
        }
      }
    }
  }
  b.last_seq = f.seq;
  b.last_tick = f.tick;
  tracking_[f.board] = true;
}

void BridgeStreamDecoder::keepTail(const std::uint8_t* p, std::size_t n) {
  // A possible start: A5 followed by 5A, or an A5 as the very last byte.
  std::size_t j = 0;
  while (j < n && !(p[j] == kSync0 && (j + 1 == n || p[j + 1] == kSync1))) ++j;
  counters_.skipped_bytes += j;
  pending_ = n - j;
  std::memcpy(buf_.data(), p + j, pending_);
}

void BridgeStreamDecoder::resync() {
  pending_ = 0;
  tracking_.fill(false);
}

void BridgeStreamDecoder::reset() {
  resync();
  counters_ = BridgeStreamCounters{};
}

}  // namespace crunch::io
