#include "crunch/core/parallel.h"

#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

using namespace crunch;

TEST_CASE("parallelFor: every index runs exactly once whatever the thread count", "[core]") {
  const int threads = GENERATE(1, 2, 3, 8, 200);
  INFO("threads " << threads);
  std::vector<std::atomic<int>> runs(100);
  parallelFor(100, threads, [&](int i) { runs[static_cast<size_t>(i)].fetch_add(1); });
  for (const auto& r : runs) CHECK(r.load() == 1);
  int called = 0;
  parallelFor(0, threads, [&](int) { ++called; });
  CHECK(called == 0);
}

TEST_CASE("parallelFor: one thread runs the bodies in order on the caller's thread", "[core]") {
  const int threads = GENERATE(-1, 0, 1);
  std::vector<int> order;
  const auto caller = std::this_thread::get_id();
  bool same_thread = true;
  parallelFor(5, threads, [&](int i) {
    order.push_back(i);
    same_thread &= std::this_thread::get_id() == caller;
  });
  CHECK(order == std::vector<int>{0, 1, 2, 3, 4});
  CHECK(same_thread);
}

TEST_CASE("parallelFor: two threads run two bodies at the same time", "[core]") {
  // Each body waits for the other to start: only concurrent bodies both finish. The wait is
  // bounded so a serial parallelFor fails the test instead of hanging it.
  std::atomic<int> started{0};
  std::atomic<int> met{0};
  parallelFor(2, 2, [&](int) {
    started.fetch_add(1);
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (started.load() < 2 && std::chrono::steady_clock::now() < give_up)
      std::this_thread::yield();
    if (started.load() == 2) met.fetch_add(1);
  });
  CHECK(met.load() == 2);
}

TEST_CASE("parallelFor: a throwing body stops new work and its exception reaches the caller",
          "[core]") {
  const int threads = GENERATE(1, 2, 4);
  INFO("threads " << threads);
  std::vector<std::atomic<int>> runs(50);
  std::string what;
  try {
    parallelFor(50, threads, [&](int i) {
      runs[static_cast<size_t>(i)].fetch_add(1);
      if (i == 3 || i == 7) throw std::runtime_error("index " + std::to_string(i));
    });
  } catch (const std::runtime_error& e) {
    what = e.what();
  }
  // Indices are taken in order, so index 3 ran whenever 7 did: the lowest failure is 3's.
  CHECK(what == "index 3");
  // No index ran twice, and the ones that ran are a prefix 0 .. k-1 with k > 3: an index is
  // started only when it was taken before a worker saw the failure, and indices are taken in
  // order. How far the other workers got before index 3's worker set the failure depends on
  // the scheduler (a worker descheduled between the throw and the flag lets the others take
  // every index), so with threads only the prefix is asserted; one thread stops exactly there.
  int ran = 0;
  for (const auto& r : runs) {
    CHECK(r.load() <= 1);
    ran += r.load();
  }
  CHECK(ran >= 4);
  for (int i = 0; i < ran; ++i) CHECK(runs[static_cast<size_t>(i)].load() == 1);
  if (threads == 1) CHECK(ran == 4);
}
