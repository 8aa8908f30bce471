#pragma once
// What the benchmarks share: a registry with the built-ins and the benchmark's own state class,
// compiling config text, heap accounting and the timed load stages.

#include <chrono>
#include <cstddef>
#include <string>
#include <vector>

#include "arbiter/load.hpp"
#include "arbiter/program.hpp"
#include "arbiter/registry.hpp"

namespace arbiter::bench {

/// The built-in classes plus the benchmark's own: `bench.Trivial`, a behaviour that requests a
/// fixed level and writes through typed ports, and `bench.Proceed`, a state that proceeds after
/// every execution and, when it does, appends the states its `append` param lists.
Registry make_registry();

/// Parses, validates and compiles `text` (named `file`); throws ConfigError when it is invalid.
Program compile_text(const std::string& text, Registry& registry,
                     const std::string& file = "generated.yaml");

/// Bytes of heap in use (malloc's own count), or 0 where the C library does not say.
std::size_t heap_in_use();

/// The load pipeline of arbiter::load(), stage by stage, timed.
struct LoadTimes {
  double parse_ms = 0;     ///< read_document: the file to a Document
  double validate_ms = 0;  ///< load_plugins and build_model: the Document to a Model
  double compile_ms = 0;   ///< compile: the Model to a Program
  double total_ms() const { return parse_ms + validate_ms + compile_ms; }
};

/// Loads `path` stage by stage into `registry`; returns nullopt after printing the diagnostics
/// when it is invalid.
std::optional<Program> load_timed(const std::string& path, Registry& registry,
                                  const LoadOptions& options, LoadTimes& times);

/// The smallest of `values` (0 when there are none): on a shared machine other load only ever
/// adds time, so the fastest repetition is the benchmark's figure (ComputeStatistics("min")).
double fastest(const std::vector<double>& values);

/// This thread's CPU time: on a shared machine, time spent descheduled is not the engine's.
double cpu_seconds();

inline double milliseconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

}  // namespace arbiter::bench
