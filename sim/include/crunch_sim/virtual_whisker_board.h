// A whisker board in software (paper §2.1): the real firmware core (firmware/core, the sampler
// state machine, ring and bridge framing) built with the host HAL (firmware/hal/host), reading an
// emulated MLX90333 over the HAL's fake SPI bus and writing the same 18-byte bridge frames the
// dsPIC33 sends (docs/protocol.md). The simulator's physics path drives whiskers through it; the
// host decoder reads its output exactly as it reads the FPGA bridge's.
//
// Timing: tick() is one 500 us period of the 2 kHz timer. It runs the sampler's ISR step once,
// which collects the transfer started at the previous tick — the emulator answers at that
// moment, so the reading set before tick() is the one the frame stamped with this tick carries —
// and then the board's main loop until the ring is empty or the link refuses. The first
// SAMPLER_POWERUP_TICKS frames are BRIDGE_ST_POWERUP (the sensor's ~16 ms start-up).
//
// A real sensor's low bits never hold still; the emulator answers exactly what it is given, so
// two identical readings in a row come out BRIDGE_ST_STALE, as the firmware would report a
// sensor that has not refreshed. The Hall model in front of it supplies the noise.
//
// Thread-safety: none. The host HAL acts on one bound context at a time (hal_host.h); tick()
// binds this board's context and unbinds it before returning, so any number of boards may be
// ticked in turn from one thread, but not from several threads at once.
// Ownership: non-copyable and non-movable (the HAL context points into the object).
// Allocation: none after construction; tick() returns a view into the board's own buffer.
#pragma once

#include <array>
#include <cstdint>
#include <span>

extern "C" {
#include "hal_host.h"
#include "whisker/board.h"
#include "whisker/bridge_frame.h"
#include "whisker/mlx90333.h"
}

namespace crunch::sim {

// The MLX90333 in Alpha/Beta mode as the bus sees it: each 8-byte transfer is answered with
// mlx_encode(alpha, beta, diag), or with a fault the test or simulator injected.
class Mlx90333Emulator {
 public:
  enum class Fault : std::uint8_t {
    kNone,
    kBadStart,     // start byte is not 0xFF
    kBadChecksum,  // checksum byte off by one
    kRepeat,       // the previous answer again, byte for byte (a sensor that did not refresh)
    kSilent,       // MISO left floating high: every byte 0xFF
  };

  // The reading the next answers carry. diag is the raw diagnostic word (mlx90333.h).
  void setReading(std::uint16_t alpha, std::uint16_t beta, std::uint16_t diag = 0);
  // The next `frames` answers carry `fault` (then kNone again). frames > 0.
  void inject(Fault fault, int frames = 1);

  // The SPI responder (hal_host_spi_fn): fills rx[0..n-1]. Returns non-zero, leaving the HAL to
  // read an idle bus, when n is not an MLX frame; counts a transfer whose tx bytes are not all
  // 0xFF (the master must clock 0xFF) in protocolErrors() but answers it.
  int answer(const std::uint8_t* tx, std::uint8_t* rx, std::uint8_t n);

  std::uint32_t answered() const { return answered_; }
  std::uint32_t protocolErrors() const { return protocol_errors_; }

 private:
  std::uint16_t alpha_ = 0, beta_ = 0, diag_ = 0;
  Fault fault_ = Fault::kNone;
  int fault_frames_ = 0;
  std::array<std::uint8_t, MLX_FRAME_LEN> last_{};
  bool have_last_ = false;
  std::uint32_t answered_ = 0;
  std::uint32_t protocol_errors_ = 0;
};

class VirtualWhiskerBoard {
 public:
  // Power-up: the board's firmware is initialised (board_init) with `board_id`, and the timer is
  // started at SAMPLER_HZ. Asserts board_id < BRIDGE_MAX_BOARDS.
  explicit VirtualWhiskerBoard(std::uint8_t board_id);
  ~VirtualWhiskerBoard() = default;
  VirtualWhiskerBoard(const VirtualWhiskerBoard&) = delete;
  VirtualWhiskerBoard& operator=(const VirtualWhiskerBoard&) = delete;

  Mlx90333Emulator& sensor() { return sensor_; }
  const Mlx90333Emulator& sensor() const { return sensor_; }

  // Bus faults, held until changed (hal_host.h's knobs):
  // the SPI peripheral refuses to start a transfer;
  void setSpiRefuse(bool refuse) { hal_.spi_refuse = refuse ? 1u : 0u; }
  // each transfer reports busy this many polls (one poll per tick); < 0: the bus is stuck;
  void setSpiBusyPolls(std::int16_t polls) { hal_.spi_busy_polls = polls; }
  // the UART link to the bridge takes nothing (frames wait in the ring, which then overflows);
  void setLinkRefuse(bool refuse) { hal_.link_refuse = refuse ? 1u : 0u; }
  // the main loop does not run for the next `ticks` ticks (the ISR still does).
  void stallMainLoop(int ticks) { stall_ticks_ = ticks; }

  // One 500 us timer period (see the top of this file). Returns the bridge bytes the board sent
  // during it, whole 18-byte frames; the view is valid until the next tick().
  std::span<const std::uint8_t> tick();

  std::uint8_t boardId() const { return board_.board_id; }
  std::uint32_t ticks() const { return board_.sampler.tick; }
  const sampler_counters_t& counters() const { return board_.sampler.counters; }
  std::uint16_t ringDropped() const { return board_.ring.dropped; }
  std::uint32_t framesSent() const { return board_.frames_sent; }

 private:
  // Frames the link holds between drains; one tick sends at most a ring's worth after a stall.
  static constexpr std::uint16_t kLinkCapacity = BRIDGE_FRAME_LEN * (RING_CAPACITY + 1);

  Mlx90333Emulator sensor_;
  hal_host_t hal_{};
  board_t board_{};
  int stall_ticks_ = 0;
  std::array<std::uint8_t, kLinkCapacity> link_{};
  std::array<std::uint8_t, kLinkCapacity> out_{};
};

}  // namespace crunch::sim
