// The step refines levels through per-behaviour recipes instead of walking the chaining closure
// (Inhibitions::recipes()). These tests check the recipes against the plain definition of
// docs/semantics.md
// ("Refinement"), a[X] = r[X] * Π (1 - a[I]) over every inhibitor I of X after closure, on random
// graphs.

#include <catch2/catch.hpp>

#include <algorithm>
#include <random>
#include <set>
#include <sstream>

#include "test_support.hpp"

using namespace arbiter;

namespace {

const Registry& registry() {
  static const Registry instance = test::make_test_registry();
  return instance;
}

/// A random layer: behaviours declared in a shuffled order, inhibitions that respect a hidden
/// topological order, each chaining or not, and levels that include exact 0s and 1s.
struct RandomGraph {
  std::size_t n = 0;
  struct Edge {
    std::size_t from;  // declaration indices
    std::size_t to;
    bool chaining;
  };
  std::vector<Edge> edges;
  std::vector<std::vector<double>> levels;  // per behaviour, per step
  bool normalise = false;

  std::string name(std::size_t b) const { return "b" + std::to_string(b); }

  std::string yaml() const {
    std::ostringstream out;
    out.precision(17);
    out << "arbiter: 1\nname: random\nlayers:\n  - name: l\n";
    if (normalise) out << "    normalise: true\n";
    out << "    behaviours:\n";
    for (std::size_t b = 0; b < n; ++b) {
      out << "      " << name(b) << ": {type: test.Probe, params: {record: false, levels: [";
      for (std::size_t s = 0; s < levels[b].size(); ++s) out << (s ? ", " : "") << levels[b][s];
      out << "]}}\n";
    }
    if (!edges.empty()) {
      out << "    inhibitions:\n";
      for (const auto& edge : edges) {
        out << "      - " << name(edge.from) << (edge.chaining ? " => " : " -> ") << name(edge.to)
            << "\n";
      }
    }
    return out.str();
  }

  /// Every inhibitor of `b` after closure, by the definition: declared, or a chain of chaining
  /// inhibitions of length two or more.
  std::set<std::size_t> closed(std::size_t b) const {
    std::set<std::size_t> out;
    std::vector<std::size_t> pending;
    for (const auto& edge : edges) {
      if (edge.to != b) continue;
      out.insert(edge.from);
      if (edge.chaining) pending.push_back(edge.from);
    }
    std::set<std::size_t> seen(pending.begin(), pending.end());
    while (!pending.empty()) {
      const std::size_t at = pending.back();
      pending.pop_back();
      for (const auto& edge : edges) {
        if (edge.to != at || !edge.chaining) continue;
        out.insert(edge.from);
        if (seen.insert(edge.from).second) pending.push_back(edge.from);
      }
    }
    return out;
  }

  bool declared(std::size_t from, std::size_t to, bool& chaining) const {
    for (const auto& edge : edges) {
      if (edge.from == from && edge.to == to) {
        chaining = edge.chaining;
        return true;
      }
    }
    return false;
  }
};

RandomGraph random_graph(std::mt19937& rng, std::size_t max_n, std::size_t steps) {
  RandomGraph graph;
  graph.n = std::uniform_int_distribution<std::size_t>(1, max_n)(rng);
  std::vector<std::size_t> rank(graph.n);  // rank[i]: the declaration index of the i-th in order
  for (std::size_t i = 0; i < graph.n; ++i) rank[i] = i;
  std::shuffle(rank.begin(), rank.end(), rng);
  std::set<std::pair<std::size_t, std::size_t>> used;
  const double density = std::uniform_real_distribution<double>(0.0, 4.0)(rng);
  const double chaining = std::uniform_real_distribution<double>(0.0, 1.0)(rng);
  const auto wanted = static_cast<std::size_t>(density * static_cast<double>(graph.n));
  std::uniform_int_distribution<std::size_t> pick(0, graph.n - 1);
  std::bernoulli_distribution is_chaining(chaining);
  for (std::size_t tries = 0; graph.n > 1 && used.size() < wanted && tries < 20 * wanted; ++tries) {
    std::size_t i = pick(rng);
    std::size_t j = pick(rng);
    if (i == j) continue;
    if (i > j) std::swap(i, j);
    if (!used.insert({i, j}).second) continue;
    graph.edges.push_back({rank[i], rank[j], is_chaining(rng)});
  }
  std::uniform_int_distribution<int> kind(0, 4);
  std::uniform_real_distribution<double> level(0.0, 1.0);
  graph.levels.resize(graph.n);
  for (auto& levels : graph.levels) {
    for (std::size_t s = 0; s < steps; ++s) {
      const int k = kind(rng);
      levels.push_back(k == 0 ? 0.0 : k == 1 ? 1.0 : level(rng));
    }
  }
  graph.normalise = std::bernoulli_distribution(0.2)(rng);
  return graph;
}

std::vector<std::uint32_t> indices(const Program& program, const RandomGraph& graph,
                                   const std::set<std::size_t>& names) {
  std::vector<std::uint32_t> out;
  for (auto b : names) out.push_back(*program.find_behaviour("l", graph.name(b)));
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

TEST_CASE("refinement through recipes gives the levels of the plain definition",
          "[refinement][closure]") {
  std::mt19937 rng(20240611);
  constexpr std::size_t kSteps = 4;
  for (int round = 0; round < 300; ++round) {
    const RandomGraph graph = random_graph(rng, round < 200 ? 12 : round < 260 ? 60 : 150, kSteps);
    INFO("round " << round << ":\n" << graph.yaml());
    Manager manager(test::compile_text(graph.yaml(), registry()));
    const Program& program = manager.program();
    std::vector<std::size_t> declaration(graph.n);  // behaviour index → declaration index
    for (std::size_t b = 0; b < graph.n; ++b) {
      declaration[*program.find_behaviour("l", graph.name(b))] = b;
    }
    std::vector<std::vector<std::uint32_t>> closed(graph.n);
    for (std::uint32_t b = 0; b < graph.n; ++b) {
      closed[b] = indices(program, graph, graph.closed(declaration[b]));
      REQUIRE(program.inhibitions.closed(b) == closed[b]);
      REQUIRE(program.inhibitions.closed_count(b) == closed[b].size());
      for (auto inhibitor : closed[b]) REQUIRE(inhibitor < b);  // execution order
    }
    for (std::size_t step = 0; step < kSteps; ++step) {
      manager.step();
      std::vector<double> expected(graph.n, 0.0);
      double sum = 0.0;
      for (std::uint32_t b = 0; b < graph.n; ++b) {
        double level = manager.requested(b);
        for (auto inhibitor : closed[b]) level *= 1.0 - expected[inhibitor];
        expected[b] = level;
        sum += level;
      }
      for (std::uint32_t b = 0; b < graph.n; ++b) {
        const double level = graph.normalise && sum > 0.0 ? expected[b] / sum : expected[b];
        INFO("step " << step + 1 << ", " << program.behaviours[b].name);
        REQUIRE_THAT(manager.activation(b), Catch::Matchers::WithinAbs(level, 1e-12));
        REQUIRE(manager.active(b) == (expected[b] > 0.0));
      }
    }
  }
}

TEST_CASE("the inhibition list derives the implicit inhibitions in order",
          "[refinement][closure]") {
  std::mt19937 rng(7);
  for (int round = 0; round < 100; ++round) {
    const RandomGraph graph = random_graph(rng, 30, 1);
    INFO("round " << round << ":\n" << graph.yaml());
    const Program program = test::compile_text(graph.yaml(), registry());
    const std::size_t counted = program.inhibitions.size();  // before the list is built
    const auto& listed = program.inhibitions;
    REQUIRE(std::distance(listed.begin(), listed.end()) == static_cast<std::ptrdiff_t>(counted));
    std::size_t at = 0;
    for (std::uint32_t inhibited = 0; inhibited < graph.n; ++inhibited) {
      const auto of = program.inhibitions.of(inhibited);
      REQUIRE(of.size() == program.inhibitions.closed_count(inhibited));
      for (std::size_t i = 0; i < of.size(); ++i) {
        CHECK(of[i].inhibitor == listed[at + i].inhibitor);
        CHECK(of[i].implicit == listed[at + i].implicit);
        CHECK(of[i].location.line == listed[at + i].location.line);
      }
      const auto& name = program.behaviours[inhibited].name;
      const std::size_t to = std::stoul(name.substr(1));
      for (auto inhibitor : indices(program, graph, graph.closed(to))) {
        REQUIRE(at < listed.size());
        const CompiledInhibition& inhibition = listed[at];
        CHECK(inhibition.inhibitor == inhibitor);
        CHECK(inhibition.inhibited == inhibited);
        bool chaining = true;
        const std::size_t from = std::stoul(program.behaviours[inhibitor].name.substr(1));
        const bool declared = graph.declared(from, to, chaining);
        CHECK(inhibition.implicit == !declared);
        CHECK(inhibition.chaining == chaining);
        CHECK((program.declared(inhibitor, inhibited) != nullptr) == declared);
        if (declared) {
          CHECK(inhibition.location.line > 0);
        } else {
          CHECK(inhibition.location.line == program.behaviours[inhibited].location.line);
          CHECK(program.chain(inhibitor, inhibited).size() >= 3);
        }
        CHECK(&program.inhibitions[at] == &inhibition);
        ++at;
      }
    }
    CHECK(at == counted);
  }
}

TEST_CASE("a chain's refinement costs one term per inhibition, not one per closure edge",
          "[refinement][closure]") {
  constexpr std::size_t kLength = 3000;
  std::ostringstream yaml;
  yaml << "arbiter: 1\nname: chain\nlayers:\n  - name: l\n    behaviours:\n";
  for (std::size_t b = 0; b < kLength; ++b) {
    yaml << "      b" << b << ": {type: test.Probe, params: {record: false, levels: ["
         << (b % 7 == 0 ? 0.25 : 0.0) << "]}}\n";
  }
  yaml << "    inhibitions:\n";
  for (std::size_t b = 1; b < kLength; ++b) yaml << "      - b" << b - 1 << " => b" << b << "\n";
  Manager manager(test::compile_text(yaml.str(), registry()));
  const Program& program = manager.program();
  CHECK(program.inhibitions.recipes().terms.size() == kLength - 1);
  CHECK(program.inhibitions.size() == kLength * (kLength - 1) / 2);
  CHECK(program.inhibitions.closed_count(kLength - 1) == kLength - 1);
  const auto last = program.inhibitions.closed(kLength - 1);
  REQUIRE(last.size() == kLength - 1);
  for (std::uint32_t b = 0; b + 1 < kLength; ++b) REQUIRE(last[b] == b);
  manager.step();
  // Every 7th requests 0.25 and is inhibited by all the earlier ones.
  double product = 1.0;
  for (std::uint32_t b = 0; b < kLength; ++b) {
    const double expected = b % 7 == 0 ? 0.25 * product : 0.0;
    REQUIRE_THAT(manager.activation(b), Catch::Matchers::WithinAbs(expected, 1e-12));
    product *= 1.0 - expected;
  }
}
