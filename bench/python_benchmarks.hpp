#pragma once

namespace arbiter::bench {

/// Registers python/step/1000, python/behaviour and python/to_dataframe/N with Google Benchmark
/// (built where the Python module is, ARBITER_PYTHON).
void register_python_benchmarks();

}  // namespace arbiter::bench
