#include "crunch_sim/virtual_whisker_board.h"

#include <catch2/catch.hpp>
#include <cstdint>
#include <vector>

extern "C" {
#include "whisker/error.h"
}

using crunch::sim::Mlx90333Emulator;
using crunch::sim::VirtualWhiskerBoard;
using Fault = Mlx90333Emulator::Fault;

namespace {

// Decodes every frame a tick produced; the board only ever sends whole, valid frames.
std::vector<bridge_frame_t> decodeAll(std::span<const std::uint8_t> bytes) {
  REQUIRE(bytes.size() % BRIDGE_FRAME_LEN == 0);
  std::vector<bridge_frame_t> frames;
  for (std::size_t i = 0; i < bytes.size(); i += BRIDGE_FRAME_LEN) {
    bridge_frame_t f{};
    REQUIRE(bridge_decode(bytes.data() + i, &f) == FW_OK);
    frames.push_back(f);
  }
  return frames;
}

// One tick that must give exactly one frame.
bridge_frame_t tickOne(VirtualWhiskerBoard& board) {
  const auto frames = decodeAll(board.tick());
  REQUIRE(frames.size() == 1);
  return frames[0];
}

// A deflection script: a slow sweep over most of the 16-bit range whose low bits change every
// tick, as a real sensor's do (so no two consecutive readings are equal).
std::uint16_t scriptAlpha(std::uint32_t k) { return static_cast<std::uint16_t>(1000 + 29 * k); }
std::uint16_t scriptBeta(std::uint32_t k) { return static_cast<std::uint16_t>(64000 - 31 * k); }

// Runs through the power-up window, checking it, and leaves the board in RUN.
void powerUp(VirtualWhiskerBoard& board) {
  for (std::uint32_t k = 0; k < SAMPLER_POWERUP_TICKS; ++k) {
    board.sensor().setReading(scriptAlpha(k), scriptBeta(k));
    const bridge_frame_t f = tickOne(board);
    CHECK(f.status == BRIDGE_ST_POWERUP);
    CHECK(f.alpha == 0);
    CHECK(f.beta == 0);
    CHECK(f.tick == k);
  }
}

}  // namespace

TEST_CASE("VirtualWhiskerBoard: scripted deflections round-trip exactly through the bridge frame",
          "[sim][firmware]") {
  VirtualWhiskerBoard board(7);
  powerUp(board);
  constexpr std::uint32_t kTicks = 2000;  // one second at 2 kHz
  std::uint32_t mismatches = 0;
  for (std::uint32_t k = SAMPLER_POWERUP_TICKS; k < SAMPLER_POWERUP_TICKS + kTicks; ++k) {
    board.sensor().setReading(scriptAlpha(k), scriptBeta(k));
    const bridge_frame_t f = tickOne(board);
    CHECK(f.board == 7);
    CHECK(f.seq == k);
    CHECK(f.tick == k);
    if (f.status != 0 || f.alpha != scriptAlpha(k) || f.beta != scriptBeta(k)) ++mismatches;
  }
  CHECK(mismatches == 0);
  CHECK(board.counters().ok == kTicks);
  CHECK(board.sensor().answered() == kTicks);
  CHECK(board.sensor().protocolErrors() == 0);  // the firmware clocks out 0xFF
  CHECK(board.framesSent() == SAMPLER_POWERUP_TICKS + kTicks);
}

TEST_CASE("VirtualWhiskerBoard: each sensor fault reaches the frame's status and a counter",
          "[sim][firmware]") {
  struct Case {
    const char* name;
    Fault fault;
    std::uint16_t diag;
    std::uint16_t status;
    std::uint16_t sampler_counters_t::*counter;
  };
  const std::vector<Case> cases = {
      {"bad start byte", Fault::kBadStart, 0, BRIDGE_ST_BAD_START, &sampler_counters_t::bad_start},
      {"bad checksum", Fault::kBadChecksum, 0, BRIDGE_ST_CHECKSUM, &sampler_counters_t::checksum},
      {"silent bus (all 0xFF)", Fault::kSilent, 0, BRIDGE_ST_CHECKSUM,
       &sampler_counters_t::checksum},
      {"repeated sample", Fault::kRepeat, 0, BRIDGE_ST_STALE, &sampler_counters_t::stale},
  };
  for (const Case& c : cases) {
    SECTION(c.name) {
      VirtualWhiskerBoard board(3);
      powerUp(board);
      std::uint32_t k = SAMPLER_POWERUP_TICKS;
      board.sensor().setReading(scriptAlpha(k), scriptBeta(k));
      CHECK(tickOne(board).status == 0);
      ++k;
      board.sensor().setReading(scriptAlpha(k), scriptBeta(k));
      board.sensor().inject(c.fault, 3);
      for (int i = 0; i < 3; ++i, ++k) {
        const bridge_frame_t f = tickOne(board);
        CHECK(f.status == c.status);  // never 0: no fault looks fresh
        if ((c.status & BRIDGE_ST_NO_DATA) != 0) {
          CHECK(f.alpha == 0);
          CHECK(f.beta == 0);
        }
      }
      CHECK(board.counters().*c.counter == 3);
      // The sensor recovers; so does the stream, with the scripted values.
      board.sensor().setReading(scriptAlpha(k), scriptBeta(k));
      const bridge_frame_t f = tickOne(board);
      CHECK(f.status == 0);
      CHECK(f.alpha == scriptAlpha(k));
      CHECK(f.beta == scriptBeta(k));
    }
  }

  SECTION("each diagnostic bit") {
    VirtualWhiskerBoard board(4);
    powerUp(board);
    std::uint32_t k = SAMPLER_POWERUP_TICKS;
    for (int bit = 0; bit < 16; ++bit, ++k) {
      const auto diag = static_cast<std::uint16_t>(1u << bit);
      const std::uint16_t expected = mlx_diag_status(diag);
      board.sensor().setReading(scriptAlpha(k), scriptBeta(k), diag);
      const bridge_frame_t f = tickOne(board);
      CAPTURE(bit);
      CHECK(f.status == expected);
      // Diagnostic samples carry the values the sensor sent, flagged.
      CHECK(f.alpha == scriptAlpha(k));
      CHECK(f.beta == scriptBeta(k));
    }
    // Bits 0..7 are the datasheet's eight diagnostic flags; all of them reach the status.
    std::uint16_t seen = 0;
    for (int bit = 0; bit < 8; ++bit) {
      const std::uint16_t st = mlx_diag_status(static_cast<std::uint16_t>(1u << bit));
      CHECK(st != 0);
      seen = static_cast<std::uint16_t>(seen | st);
    }
    CHECK(seen == MLX_ST_DIAG_MASK);
    CHECK(board.counters().diag == 8);
  }
}

TEST_CASE("VirtualWhiskerBoard: bus faults give BUSY and TIMEOUT, never a fresh sample",
          "[sim][firmware]") {
  VirtualWhiskerBoard board(0);
  powerUp(board);
  std::uint32_t k = SAMPLER_POWERUP_TICKS;
  auto next = [&]() {
    board.sensor().setReading(scriptAlpha(k), scriptBeta(k));
    ++k;
    return tickOne(board);
  };
  CHECK(next().status == 0);

  SECTION("stuck bus: two BUSY ticks, then the transfer is aborted as TIMEOUT") {
    board.setSpiBusyPolls(-1);
    CHECK(next().status == 0);  // collects the transfer started before the bus stuck
    CHECK(next().status == BRIDGE_ST_BUSY);
    CHECK(next().status == BRIDGE_ST_BUSY);
    CHECK(next().status == BRIDGE_ST_TIMEOUT);
    CHECK(board.counters().timeout == 1);
    board.setSpiBusyPolls(0);
    // The transfer restarted after the abort is still stuck (the knob is read at its start).
    CHECK(next().status == BRIDGE_ST_BUSY);
    CHECK(next().status == BRIDGE_ST_BUSY);
    CHECK(next().status == BRIDGE_ST_TIMEOUT);
    const bridge_frame_t f = next();
    CHECK(f.status == 0);
    CHECK(f.alpha == scriptAlpha(k - 1));
  }
  SECTION("refused start: BUSY and counted") {
    board.setSpiRefuse(true);
    CHECK(next().status == 0);
    CHECK(next().status == BRIDGE_ST_BUSY);
    CHECK(next().status == BRIDGE_ST_BUSY);
    CHECK(board.counters().spi_error == 3);  // each of the three ticks tried to start one
    board.setSpiRefuse(false);
    CHECK(next().status == BRIDGE_ST_BUSY);  // nothing was in flight to collect
    const bridge_frame_t f = next();
    CHECK(f.status == 0);
    CHECK(f.beta == scriptBeta(k - 1));
  }
}

TEST_CASE("VirtualWhiskerBoard: a stalled main loop or link loses samples visibly, not silently",
          "[sim][firmware]") {
  VirtualWhiskerBoard board(27);
  powerUp(board);
  std::uint32_t k = SAMPLER_POWERUP_TICKS;
  constexpr int kStall = RING_CAPACITY + 8;

  SECTION("main loop stall") { board.stallMainLoop(kStall); }
  SECTION("link refuses") { board.setLinkRefuse(true); }

  std::vector<bridge_frame_t> frames;
  for (int i = 0; i < kStall; ++i, ++k) {
    board.sensor().setReading(scriptAlpha(k), scriptBeta(k));
    for (const auto& f : decodeAll(board.tick())) frames.push_back(f);
  }
  CHECK(frames.size() <= 1);  // at most the one frame the link took before it stopped
  board.setLinkRefuse(false);
  board.sensor().setReading(scriptAlpha(k), scriptBeta(k));
  for (const auto& f : decodeAll(board.tick())) frames.push_back(f);
  ++k;

  // Everything the ring kept comes out at once, in order, sequence numbers unbroken.
  REQUIRE(frames.size() >= RING_CAPACITY);
  const std::uint32_t lost = k - SAMPLER_POWERUP_TICKS - static_cast<std::uint32_t>(frames.size());
  CHECK(lost > 0);
  CHECK(board.ringDropped() == lost);
  int gaps = 0;
  std::uint32_t prev_tick = SAMPLER_POWERUP_TICKS - 1;  // the last power-up frame
  for (std::size_t i = 0; i < frames.size(); ++i) {
    CHECK(frames[i].seq == SAMPLER_POWERUP_TICKS + i);
    const bool gap = frames[i].tick != prev_tick + 1;
    // The first frame after the gap, and only it, says so; the timestamps' gap is the loss.
    CHECK(((frames[i].status & BRIDGE_ST_DROPPED) != 0) == gap);
    if (gap) {
      CHECK(frames[i].tick - prev_tick - 1 == lost);
      ++gaps;
    }
    // Values survive: samples are dropped whole, never mixed.
    CHECK(frames[i].alpha == scriptAlpha(frames[i].tick));
    prev_tick = frames[i].tick;
  }
  CHECK(gaps == 1);
}

TEST_CASE("VirtualWhiskerBoard: boards ticked in turn keep separate firmware state",
          "[sim][firmware]") {
  VirtualWhiskerBoard a(1), b(2);
  for (std::uint32_t k = 0; k < SAMPLER_POWERUP_TICKS + 100; ++k) {
    a.sensor().setReading(scriptAlpha(k), scriptBeta(k));
    b.sensor().setReading(scriptBeta(k), scriptAlpha(k));
    if (k == SAMPLER_POWERUP_TICKS + 50) b.sensor().inject(Fault::kBadChecksum);
    const bridge_frame_t fa = tickOne(a);
    const bridge_frame_t fb = tickOne(b);
    CHECK(fa.board == 1);
    CHECK(fb.board == 2);
    if (k < SAMPLER_POWERUP_TICKS) continue;
    CHECK(fa.status == 0);
    CHECK(fa.alpha == scriptAlpha(k));
    if (k == SAMPLER_POWERUP_TICKS + 50) {
      CHECK(fb.status == BRIDGE_ST_CHECKSUM);
    } else {
      CHECK(fb.status == 0);
      CHECK(fb.alpha == scriptBeta(k));
    }
  }
  CHECK(a.counters().checksum == 0);
  CHECK(b.counters().checksum == 1);
  CHECK(hal_host_bound() == nullptr);  // tick() leaves no context bound
}
