// The fuzz targets' invariant check: a failed invariant aborts, which libFuzzer reports as a
// crash with the input that broke it.
#pragma once

#include <cstdlib>

namespace fuzz {
inline void check(bool ok) {
  if (!ok) std::abort();
}
}  // namespace fuzz
