// One 500 us sample of the four horizontal whiskers as the bridge delivers it (paper §2.1,
// docs/protocol.md): per whisker the MLX90333's raw 16-bit Alpha and Beta codes and the bridge
// frame's status word. This header fixes the shapes every signal module shares (4 whiskers,
// 8 channels, 2 kHz) and says which samples are measurements.
//
// Which samples are used (docs/SIGNAL.md, "Invalid samples"): status 0 is the only fresh, valid
// measurement. NO_DATA bits (0x003E) carry Alpha = Beta = 0, no measurement at all. STALE,
// DROPPED and the MLX diagnostic bits carry values as measured but flagged: STALE repeats the
// previous frame (not a new measurement), MLX bits say the sensor distrusts its own reading
// (field lost, saturated...), DROPPED says samples *before* this one were lost. By default only
// status 0 is used; DROPPED-only samples may be admitted with an option. A sample that is not
// used is replaced by the last used value ("held") and counted by its kind.
//
// Plain values; thread-safe.
#pragma once

#include <array>
#include <cstdint>

namespace crunch::signal {

inline constexpr int kWhiskers = 4;              // the paper's four horizontal whiskers (§2.2)
inline constexpr int kChannels = 2 * kWhiskers;  // Alpha and Beta per whisker (§2.5)
inline constexpr double kSampleRateHz = 2000.0;  // one sample per 500 us (§2.1)
inline constexpr double kSamplePeriod = 1.0 / kSampleRateHz;  // seconds

// Row of a channel in an 8-channel window: whisker w's Alpha is 2w, its Beta 2w + 1.
constexpr int channelOf(int whisker, int axis) { return 2 * whisker + axis; }

// The bridge frame's status bits (docs/protocol.md; the firmware's bridge_frame.h and
// mlx90333.h define the same values, and a test checks that they agree).
namespace status {
inline constexpr std::uint16_t kStale = 0x0001;
inline constexpr std::uint16_t kBadStart = 0x0002;
inline constexpr std::uint16_t kChecksum = 0x0004;
inline constexpr std::uint16_t kTimeout = 0x0008;
inline constexpr std::uint16_t kBusy = 0x0010;
inline constexpr std::uint16_t kPowerUp = 0x0020;
inline constexpr std::uint16_t kDropped = 0x0040;
inline constexpr std::uint16_t kNoData = 0x003E;   // any of these: Alpha and Beta are 0
inline constexpr std::uint16_t kMlxMask = 0x7F00;  // the sensor's diagnostic bits
}  // namespace status

// One whisker's reading in one sample.
struct WhiskerReading {
  std::uint16_t alpha = 0;   // MLX90333 Alpha, raw code
  std::uint16_t beta = 0;    // MLX90333 Beta, raw code
  std::uint16_t status = 0;  // bridge frame status; 0 = fresh and valid
};

// The four whiskers' readings taken at the same 500 us tick. A tick with no frame from a board
// (a sequence or timestamp gap) should be fed as a reading with status::kDropped or a NO_DATA bit
// so the time base stays at 2 kHz.
using SampleFrame = std::array<WhiskerReading, kWhiskers>;

// What a status word says about its values, the most severe reason first.
enum class SampleKind {
  kFresh,       // status 0
  kNoData,      // a NO_DATA bit: no measurement
  kSensorFlag,  // an MLX diagnostic bit (or a reserved bit): measured, but distrusted
  kStale,       // STALE: the previous frame repeated
  kDropped,     // DROPPED alone: fresh value, earlier samples were lost
};

SampleKind classifyStatus(std::uint16_t status_word);

// Per-whisker counts of samples by kind, and how many were used as measurements or held.
struct SampleCounts {
  std::uint64_t fresh = 0;
  std::uint64_t no_data = 0;
  std::uint64_t sensor_flag = 0;
  std::uint64_t stale = 0;
  std::uint64_t dropped = 0;
  std::uint64_t used = 0;  // fed to the filters as a measurement
  std::uint64_t held = 0;  // replaced by the last used value (or ignored before the first one)

  std::uint64_t total() const { return fresh + no_data + sensor_flag + stale + dropped; }
};

}  // namespace crunch::signal
