#pragma once
// The allocation counter of counting_new.cpp, for test binaries that link it.

#include <atomic>
#include <cstddef>
#include <thread>

namespace arbiter::test {

/// While true, every operator new adds one to `allocations`.
extern std::atomic<bool> counting;
extern std::atomic<std::size_t> allocations;
/// The thread filter: when set, only the operator new calls of that thread count (a step's, not
/// those of a middleware's threads meanwhile). Default: every thread counts.
extern std::atomic<std::thread::id> only_thread;

/// Whether an allocation now, on this thread, counts (for a binary that counts malloc too).
inline bool counts_here() {
  if (!counting.load(std::memory_order_relaxed)) return false;
  const std::thread::id only = only_thread.load(std::memory_order_relaxed);
  return only == std::thread::id() || only == std::this_thread::get_id();
}

}  // namespace arbiter::test
