#include "crunch_sim/virtual_whisker_board.h"

#include <algorithm>
#include <cassert>

extern "C" {
#include "whisker/error.h"
#include "whisker/hal.h"
}

namespace crunch::sim {

void Mlx90333Emulator::setReading(std::uint16_t alpha, std::uint16_t beta, std::uint16_t diag) {
  alpha_ = alpha;
  beta_ = beta;
  diag_ = diag;
}

void Mlx90333Emulator::inject(Fault fault, int frames) {
  assert(frames > 0);
  fault_ = fault;
  fault_frames_ = frames;
}

int Mlx90333Emulator::answer(const std::uint8_t* tx, std::uint8_t* rx, std::uint8_t n) {
  if (n != MLX_FRAME_LEN) return 1;
  if (!std::all_of(tx, tx + n, [](std::uint8_t b) { return b == 0xFFu; })) ++protocol_errors_;
  ++answered_;

  const Fault fault = fault_frames_ > 0 ? fault_ : Fault::kNone;
  if (fault_frames_ > 0 && --fault_frames_ == 0) fault_ = Fault::kNone;

  std::array<std::uint8_t, MLX_FRAME_LEN> frame{};
  switch (fault) {
    case Fault::kRepeat:
      if (have_last_) {
        frame = last_;
        break;
      }
      [[fallthrough]];  // nothing to repeat yet: a normal answer
    case Fault::kNone:
    case Fault::kBadStart:
    case Fault::kBadChecksum:
      mlx_encode(alpha_, beta_, diag_, frame.data());
      if (fault == Fault::kBadStart) frame[0] = 0x7Fu;
      if (fault == Fault::kBadChecksum) frame[MLX_FRAME_LEN - 1] ^= 0x01u;
      break;
    case Fault::kSilent:
      frame.fill(0xFFu);
      break;
  }
  // Only a frame the sensor really produced is one it can repeat.
  if (fault == Fault::kNone) {
    last_ = frame;
    have_last_ = true;
  }
  std::copy(frame.begin(), frame.end(), rx);
  return 0;
}

namespace {
int emulatorResponder(void* user, const std::uint8_t* tx, std::uint8_t* rx, std::uint8_t n) {
  return static_cast<Mlx90333Emulator*>(user)->answer(tx, rx, n);
}

// Binds a board's HAL context for the duration of a scope.
class HalBinding {
 public:
  explicit HalBinding(hal_host_t* ctx) { hal_host_bind(ctx); }
  ~HalBinding() { hal_host_bind(nullptr); }
  HalBinding(const HalBinding&) = delete;
  HalBinding& operator=(const HalBinding&) = delete;
};
}  // namespace

VirtualWhiskerBoard::VirtualWhiskerBoard(std::uint8_t board_id) {
  assert(board_id < BRIDGE_MAX_BOARDS);
  hal_host_init(&hal_, link_.data(), kLinkCapacity);
  hal_.spi = emulatorResponder;
  hal_.spi_user = &sensor_;
  HalBinding bind(&hal_);
  [[maybe_unused]] const int rc = board_init(&board_, board_id);
  assert(rc == FW_OK);
  [[maybe_unused]] const int trc = hal_timer_start(SAMPLER_HZ);
  assert(trc == FW_OK);
}

std::span<const std::uint8_t> VirtualWhiskerBoard::tick() {
  HalBinding bind(&hal_);
  sampler_tick(&board_.sampler);  // the timer interrupt
  if (stall_ticks_ > 0) {
    --stall_ticks_;
  } else {
    while (board_poll(&board_) == FW_OK) {
    }
  }
  assert(hal_host_irq_balanced(&hal_));
  const std::uint16_t n = hal_host_link_drain(&hal_, out_.data(), kLinkCapacity);
  return {out_.data(), n};
}

}  // namespace crunch::sim
