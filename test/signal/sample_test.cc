// Which bridge samples are measurements (docs/protocol.md status bits).
#include "crunch/signal/sample.h"

#include <catch2/catch.hpp>

#include "whisker/bridge_frame.h"
#include "whisker/mlx90333.h"

using namespace crunch;
using namespace crunch::signal;

TEST_CASE("Sample: status bits agree with the firmware's definitions", "[signal]") {
  CHECK(status::kStale == BRIDGE_ST_STALE);
  CHECK(status::kBadStart == BRIDGE_ST_BAD_START);
  CHECK(status::kChecksum == BRIDGE_ST_CHECKSUM);
  CHECK(status::kTimeout == BRIDGE_ST_TIMEOUT);
  CHECK(status::kBusy == BRIDGE_ST_BUSY);
  CHECK(status::kPowerUp == BRIDGE_ST_POWERUP);
  CHECK(status::kDropped == BRIDGE_ST_DROPPED);
  CHECK(status::kNoData == BRIDGE_ST_NO_DATA);
  CHECK(status::kMlxMask == MLX_ST_DIAG_MASK);
}

TEST_CASE("Sample: only status 0 is fresh, NO_DATA outranks flags, flags outrank STALE",
          "[signal]") {
  CHECK(classifyStatus(0) == SampleKind::kFresh);
  for (std::uint16_t bit :
       {status::kBadStart, status::kChecksum, status::kTimeout, status::kBusy, status::kPowerUp}) {
    CHECK(classifyStatus(bit) == SampleKind::kNoData);
    CHECK(classifyStatus(bit | status::kStale | 0x0400) == SampleKind::kNoData);
  }
  for (std::uint16_t bit = 0x0100; bit != 0x8000; bit <<= 1) {
    CHECK(classifyStatus(bit) == SampleKind::kSensorFlag);
    CHECK(classifyStatus(bit | status::kStale | status::kDropped) == SampleKind::kSensorFlag);
  }
  // Reserved bits are not understood, hence not trusted.
  CHECK(classifyStatus(0x0080) == SampleKind::kSensorFlag);
  CHECK(classifyStatus(0x8000) == SampleKind::kSensorFlag);
  CHECK(classifyStatus(status::kStale) == SampleKind::kStale);
  CHECK(classifyStatus(status::kStale | status::kDropped) == SampleKind::kStale);
  CHECK(classifyStatus(status::kDropped) == SampleKind::kDropped);
}
