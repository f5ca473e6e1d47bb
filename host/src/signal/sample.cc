#include "crunch/signal/sample.h"

namespace crunch::signal {

SampleKind classifyStatus(std::uint16_t status_word) {
  if (status_word == 0) return SampleKind::kFresh;
  if (status_word & status::kNoData) return SampleKind::kNoData;
  // Reserved bits (7, 15) are 0 by the protocol; a set one means a frame we do not understand,
  // so it is distrusted like a sensor flag rather than taken as a measurement.
  const std::uint16_t known = status::kStale | status::kNoData | status::kDropped;
  if (status_word & static_cast<std::uint16_t>(~known)) return SampleKind::kSensorFlag;
  if (status_word & status::kStale) return SampleKind::kStale;
  return SampleKind::kDropped;
}

}  // namespace crunch::signal
