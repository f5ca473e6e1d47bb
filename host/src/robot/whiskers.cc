#include "crunch/robot/whiskers.h"

#include <cmath>

namespace crunch {
namespace {

constexpr double kDeg = kPi / 180.0;
constexpr double kWhiskerLength = 0.14;  // external length (§2.4: 140 mm of the 160 mm)

}  // namespace

std::vector<WhiskerMount> defaultWhiskerArray() {
  std::vector<WhiskerMount> mounts;
  for (const double deg : {-33.75, -11.25, 11.25, 33.75}) {
    const double b = deg * kDeg;
    mounts.push_back({kRobotRadius * Vec2(std::cos(b), std::sin(b)), b, kWhiskerLength});
  }
  return mounts;
}

}  // namespace crunch
