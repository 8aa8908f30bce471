#pragma once

namespace arbiter::bench {

/// Registers studio/edit/<N> and studio/edit/<operation>/<N>: an operation of the studio answered
/// with its edits and diagnostics, through Studio::edit().
void register_studio_benchmarks();

}  // namespace arbiter::bench
