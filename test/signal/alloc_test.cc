// Counts heap allocations to prove SignalPipeline::push() allocates nothing after construction
// and setModels(), through calibration, episodes, classification and invalid samples
// (ARCHITECTURE.md §3). Its own executable: it replaces the global operator new.
#include <catch2/catch.hpp>
#include <cstdlib>
#include <new>

#include "crunch/signal/pipeline.h"
#include "synthetic.h"
#include "support/count_allocations.h"
#include "support/sanitizers.h"


// Eigen's dynamic matrices take their memory from malloc, not operator new, so malloc is
// counted too (glibc: the executable's malloc interposes, __libc_malloc is the real one).
// AddressSanitizer intercepts malloc itself; under it (CRUNCH_ASAN) only operator new is counted.
#if defined(__GLIBC__) && !defined(CRUNCH_ASAN)
extern "C" {
void* __libc_malloc(std::size_t n);
void* __libc_calloc(std::size_t n, std::size_t size);
void* __libc_realloc(void* p, std::size_t n);
void* malloc(std::size_t n) noexcept {
  ++g_allocations;
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t size) noexcept {
  ++g_allocations;
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t n) noexcept {
  ++g_allocations;
  return __libc_realloc(p, n);
}
}
#define CRUNCH_COUNTS_MALLOC 1
#endif


using namespace crunch;
using namespace crunch::signal;
using namespace crunch::signal::testing;

TEST_CASE("Pipeline: push() performs no heap allocation", "[signal]") {
  Result<SignalPipeline> created = SignalPipeline::create();
  REQUIRE(created.ok());
  SignalPipeline p = std::move(created).value();
  SignalModels models;
  for (int w = 0; w < kWhiskers; ++w) {
    models.radial.whiskers[w] = {.a1 = -3.3,
                                 .a0 = 0.2,
                                 .sigma = 0.002,
                                 .samples = 30,
                                 .f1_min = 0.01,
                                 .f1_max = 0.04,
                                 .r_min = 0.09,
                                 .r_max = 0.14};
  }
  models.orientation.decimation = 20;
  models.orientation.columns = 200;
  for (double a : defaultOrientationAngles()) {
    models.orientation.templates.push_back({a, 3, WindowMatrix::Constant(kChannels, 200, a)});
  }
  REQUIRE(p.setModels(models).ok());

  Rng rng(1);
  std::vector<SampleFrame> s = quiet(kCalibrationSeconds, 4.0, rng);
  for (int k = 0; k < 3; ++k) {
    Touches t;
    for (int w = 0; w < kWhiskers; ++w) t[w] = {0.01 + 0.002 * w, 0.3, 0.05 * w};
    append(s, contactFrames(t, 3.0, 4.0, rng));
  }
  for (size_t i = 0; i < s.size(); i += 37) s[i][i % kWhiskers] = {0, 0, status::kTimeout};

  int episodes = 0, with_orientation = 0;
  const long long before = g_allocations;
  for (const SampleFrame& f : s) {
    if (const ContactEpisode* e = p.push(f)) {
      ++episodes;
      with_orientation += e->has_orientation;
    }
  }
  const long long during = g_allocations - before;
  CHECK(episodes == 3);
  CHECK(with_orientation == 3);
  CHECK(during == 0);
}

#ifdef CRUNCH_COUNTS_MALLOC
TEST_CASE("Allocation counter: sees Eigen's allocations", "[signal]") {
  const long long before = g_allocations;
  WindowMatrix m = WindowMatrix::Zero(kChannels, 100);
  CHECK(g_allocations > before);
  CHECK(m.sum() == 0.0);
}
#endif
