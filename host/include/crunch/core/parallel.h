// Independent pieces of work on several threads: the global inference's chains
// (mapping/global_chain.h) and any loop whose iterations share nothing mutable.
//
// Determinism is the caller's part: each index's work must depend only on its index (its own
// Rng stream split by Rng::jump(), its own output slot), never on which thread runs it or when;
// the caller combines the slots in index order after parallelFor returns. Then the result is the
// same for every thread count, 1 included.
#pragma once

#include <functional>

namespace crunch {

// The machine's hardware threads (std::thread::hardware_concurrency()), at least 1 (the standard
// allows 0 when it cannot tell).
int hardwareThreads();

// A thread-count setting made concrete: `requested` > 0 as it is; 0 (one per core):
// hardwareThreads(). Negative values are the caller's validation to refuse.
int resolveThreads(int requested);

// Calls body(i) once for every i in [0, n) on min(threads, n) threads: the calling thread and
// min(threads, n) - 1 std::threads started for the call and joined before it returns (no pool
// outlives it). Idle threads take the next index in increasing order. threads <= 1 or n <= 1:
// every body runs in the calling thread in index order, no thread is started.
// If a body throws, indices not yet taken are not started, every thread is joined, and the
// exception of the lowest index that threw is rethrown.
// Thread-safety: body is called concurrently with distinct indices; it must not write state
// another index reads or writes. Allocates the threads' stacks and bookkeeping per call.
void parallelFor(int n, int threads, const std::function<void(int)>& body);

}  // namespace crunch
