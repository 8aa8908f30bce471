#pragma once

namespace arbiter::bench {

/// Registers step/<graph>/<N>, scl/..., load/<stage>/<N> and memory/<graph>/<N> with Google
/// Benchmark.
void register_benchmarks();

}  // namespace arbiter::bench
