// Whether this test executable is built with AddressSanitizer: the asan preset (Debug -O0 with
// ASan + UBSan), which CI runs over every unit test after the Release build's run.
//
// Some unit tests check a property over a long run (an energy audit after every move, a chain's
// frequencies against a reference, every pose of an arena against a brute force). At -O0 under
// the sanitizers such a run is 100-500 times slower than in Release. These tests run a smaller
// case under ASan, scaled by the constants below, with the same assertions; the Release build
// (same sources, same CI run) still runs the full case. What the smaller case gives up is stated
// in each test (docs/BENCHMARKS.md, "CI time").
#pragma once

#if defined(__SANITIZE_ADDRESS__)  // GCC
#define CRUNCH_ASAN 1
#elif defined(__has_feature)  // clang
#if __has_feature(address_sanitizer)
#define CRUNCH_ASAN 1
#endif
#endif

namespace crunch::testing {

#if defined(CRUNCH_ASAN)
inline constexpr bool kUnderAsan = true;
#else
inline constexpr bool kUnderAsan = false;
#endif

// `n` in the Release build, `n / divisor` (at least 1) under AddressSanitizer.
constexpr int asanScaled(int n, int divisor) {
  if (!kUnderAsan) return n;
  return n / divisor > 0 ? n / divisor : 1;
}

}  // namespace crunch::testing
