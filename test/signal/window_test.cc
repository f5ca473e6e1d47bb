// The 2 s, 8-channel contact window and its decimation (paper §2.5).
#include "crunch/signal/window.h"

#include <catch2/catch.hpp>

using namespace crunch;
using namespace crunch::signal;

namespace {
std::array<double, kChannels> ramp(int n) {
  std::array<double, kChannels> x;
  for (int c = 0; c < kChannels; ++c) x[c] = 100.0 * c + n;
  return x;
}
}  // namespace

TEST_CASE("Window: stores block means, channel rows, and stops when full", "[signal]") {
  WindowRecorder rec({.samples = 12, .decimation = 4});
  REQUIRE(rec.window().data.rows() == kChannels);
  REQUIRE(rec.window().data.cols() == 3);
  rec.start();
  for (int n = 0; n < 11; ++n) CHECK_FALSE(rec.push(ramp(n)));
  CHECK(rec.push(ramp(11)));
  CHECK(rec.push(ramp(999)));  // ignored
  CHECK(rec.samplesRecorded() == 12);
  for (int c = 0; c < kChannels; ++c) {
    CHECK(rec.window().data(c, 0) == Approx(100.0 * c + 1.5));  // mean of 0..3
    CHECK(rec.window().data(c, 2) == Approx(100.0 * c + 9.5));  // mean of 8..11
  }
  rec.start();
  CHECK(rec.samplesRecorded() == 0);
  CHECK(rec.window().data.isZero());
}

TEST_CASE("Window: the offline decimation equals the recorder's", "[signal]") {
  WindowMatrix full(kChannels, 4000);
  for (int n = 0; n < 4000; ++n) {
    const auto x = ramp(n);
    for (int c = 0; c < kChannels; ++c) full(c, n) = std::sin(0.01 * n * (c + 1)) + x[c];
  }
  WindowRecorder rec;  // defaults: 4000 samples, decimation 20
  rec.start();
  for (int n = 0; n < 4000; ++n) {
    std::array<double, kChannels> x;
    for (int c = 0; c < kChannels; ++c) x[c] = full(c, n);
    rec.push(x);
  }
  const ContactWindow offline = decimateWindow(full, 20);
  CHECK(offline.decimation == 20);
  CHECK(rec.window().decimation == 20);
  REQUIRE(offline.data.cols() == 200);
  CHECK((offline.data - rec.window().data).cwiseAbs().maxCoeff() < 1e-9);
  CHECK(decimateWindow(full, 1).data == full);
}

TEST_CASE("Window: options must divide evenly", "[signal]") {
  CHECK(WindowOptions{}.validate().ok());
  CHECK(WindowOptions{}.columns() == 200);
  const Status s = WindowOptions{.samples = 4000, .decimation = 30}.validate();
  REQUIRE_FALSE(s.ok());
  CHECK_THAT(s.error().message, Catch::Contains("window.decimation"));
  CHECK_FALSE(WindowOptions{.samples = 0, .decimation = 1}.validate().ok());
}
