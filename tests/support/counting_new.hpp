#pragma once
// The allocation counter of counting_new.cpp, for test binaries that link it.

#include <atomic>
#include <cstddef>

namespace arbiter::test {

/// While true, every operator new adds one to `allocations`.
extern std::atomic<bool> counting;
extern std::atomic<std::size_t> allocations;

}  // namespace arbiter::test
