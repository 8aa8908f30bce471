#pragma once
// Generated configs for the benchmarks, and for users who want to measure their own sizes
// (`arbiter_bench --generate`). By default every behaviour is the built-in `scripted` one, so a
// generated config also runs with `arbiter validate` and `arbiter run`.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace arbiter::bench {

enum class Graph {
  kNone,    ///< N behaviours in one layer, no inhibitions
  kChain,   ///< b0 => b1 => ... => b(N-1): a closure of N(N-1)/2 inhibitions
  kDag,     ///< a random DAG of `inhibitions` declared edges (default 3N), every other chaining
  kLayers,  ///< 10 layers of N/10 behaviours, each layer writing an aggregatable actuator that
            ///< the next layer reads
};

std::string_view to_string(Graph graph);
std::optional<Graph> graph_from_string(std::string_view name);

struct GeneratorOptions {
  Graph graph = Graph::kDag;
  std::size_t behaviours = 1000;
  std::size_t inhibitions = 0;  ///< for kDag; 0 means 3 per behaviour
  std::uint64_t seed = 1;
  bool json = false;  ///< JSON instead of YAML
  /// The behaviours' class: `scripted` runs anywhere (the CLI too); the benchmarks use their own
  /// `bench.Trivial`, which writes through typed ports (`out`, and `in` from the layer above).
  std::string behaviour_class = "scripted";
};

/// The config text. Requested levels are seeded per behaviour: half request 0, a tenth 1, the
/// rest a level in [0.05, 0.95], so that refinement multiplies real factors.
std::string generate_config(const GeneratorOptions& options);

/// How many inhibitions generate_config() declares.
std::size_t declared_inhibitions(const GeneratorOptions& options);

}  // namespace arbiter::bench
