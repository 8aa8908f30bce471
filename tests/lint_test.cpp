// The lints (engine/tools/lint/lint.cpp): located, silenced by code, none in the shipped configs, and
// in agreement with the reachability closure on random graphs.

#include <catch2/catch.hpp>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "arbiter/lint.hpp"
#include "arbiter/load.hpp"
#include "tooling_support.hpp"

namespace fs = std::filesystem;
using namespace arbiter;
using namespace arbiter::test;

namespace {

/// The diagnostics of the YAML config `config` (named `file`) through the stages validate runs,
/// lints included; a config that does not compile fails the test with its diagnostics.
Diagnostics linted(const std::string& config, const std::string& file, const Registry& registry) {
  Diagnostics diagnostics;
  auto document = parse_document(config, file, DocumentFormat::kYaml, diagnostics);
  INFO(config << format(diagnostics));
  REQUIRE(document.has_value());
  const Model model = build_model(*document, registry, diagnostics);
  REQUIRE_FALSE(diagnostics.has_errors());
  auto program = compile(model, registry, diagnostics);
  REQUIRE(program.has_value());
  lint(model, *program, diagnostics);
  return diagnostics;
}

}  // namespace

TEST_CASE("each lint is reported once, located, with its code", "[lint]") {
  Registry registry = tooling_registry();
  Diagnostics diagnostics;
  test::WorkingDirectory here(kGoldenDir);
  const auto program = load("lints.yaml", registry, diagnostics, test::with_lints());
  REQUIRE(program.has_value());
  CHECK(diagnostics.error_count() == 0);
  check_golden("lints.expected", format(diagnostics));
  std::vector<std::string> codes;
  for (const auto& item : diagnostics.items()) {
    CHECK(item.severity == Severity::kWarning);
    codes.push_back(item.code);
  }
  for (const auto& lint : lint_codes()) {
    CHECK(std::count(codes.begin(), codes.end(), std::string(lint.code)) == 1);
  }
}

TEST_CASE("a load without the lint step, as on a robot, reports no lint", "[lint]") {
  Registry registry = tooling_registry();
  Diagnostics diagnostics;
  test::WorkingDirectory here(kGoldenDir);
  LoadOptions strict;
  strict.strict = true;  // a lint would be an error here, and the load would fail
  CHECK(load("lints.yaml", registry, diagnostics, strict).has_value());
  CHECK(diagnostics.empty());
}

TEST_CASE("lints are silenced by code, for the config or for one layer", "[lint]") {
  const std::string text = read_text(kGoldenDir / "lints.yaml");
  const auto diagnose = [](const std::string& config) {
    const Diagnostics diagnostics = linted(config, "lints.yaml", tooling_registry());
    std::vector<std::string> codes;
    for (const auto& item : diagnostics.items()) codes.push_back(item.code);
    return codes;
  };
  SECTION("every lint at the top level") {
    std::string ignore_all = "lint: {ignore: [";
    for (const auto& lint : lint_codes()) ignore_all += std::string(lint.code) + ", ";
    ignore_all += "]}\n";
    std::string config = text;
    config.insert(config.find("layers:"), ignore_all);
    CHECK(diagnose(config).empty());
  }
  SECTION("in one layer: that layer's only") {
    std::string config = text;
    config.insert(config.find("    sensors: [distance, kick]"),
                  "    lint: {ignore: [delayed-sensor, unread-actuator, conflicting-writers]}\n");
    CHECK(diagnose(config) ==
          std::vector<std::string>{"redundant-inhibition", "never-active", "unread-actuator"});
  }
  SECTION("an unknown code is reported with the known ones") {
    std::string config = text;
    config.insert(config.find("layers:"), "lint: {ignore: [never-activ]}\n");
    const auto codes = diagnose(config);
    CHECK(std::count(codes.begin(), codes.end(), "unknown-lint") == 1);
    CHECK(std::count(codes.begin(), codes.end(), "never-active") == 1);
  }
}

TEST_CASE("the configs in configs/ have no lint", "[lint]") {
  for (const auto& path : configs_under(kSourceDir / "configs")) {
    DYNAMIC_SECTION(fs::relative(path, kSourceDir).string()) {
      if (!plugins_built(path)) continue;
      Registry registry = builtin_registry();
      Diagnostics diagnostics;
      const auto program = load(path.string(), registry, diagnostics, test::with_lints());
      INFO(format(diagnostics));
      CHECK(program.has_value());
      CHECK(diagnostics.empty());
    }
  }
}

TEST_CASE("a chain of always-full scripted behaviours is followed through the closure", "[lint]") {
  // a requests 1 and nothing inhibits it: b is never active. b never active leaves c free, but
  // a => b => c also makes a inhibit c: c is never active too, through the chain.
  const std::string config = R"(
arbiter: 1
name: chain
layers:
  - name: l
    behaviours:
      a: scripted
      b: {type: scripted, params: {activation: 0.5}}
      c: {type: scripted, params: {activation: [1, 0]}}
      d: {type: scripted, params: {activation: 0}}
      e: scripted
    inhibitions: [a => b, b => c, d -> e]
)";
  const Diagnostics diagnostics = linted(config, "chain.yaml", builtin_registry());
  std::string text = format(diagnostics);
  CHECK(contains(text, "behaviour 'b' can never be active: 'a' inhibits it"));
  CHECK(contains(text, "behaviour 'c' can never be active: 'a' inhibits it"));
  CHECK(contains(text, "'a' inhibits 'c' through chaining: a => b => c"));
  CHECK(contains(text, "'a' is scripted to request 1 at every step (its default activation)"));
  // d requests 0 at every step, so e (requesting 1) is not covered: it is always active.
  CHECK_FALSE(contains(text, "behaviour 'e'"));
  CHECK(diagnostics.warning_count() == 2);
}

TEST_CASE("never-active and redundant-inhibition agree with the closure on random graphs",
          "[lint]") {
  // The lints carry their properties along declared edges; here they are checked against a
  // brute force over Program's closed inhibitor lists and a search over chaining edges.
  std::mt19937 random(7);
  const Registry registry = builtin_registry();
  for (int round = 0; round < 40; ++round) {
    const int n = 5 + static_cast<int>(random() % 30);
    std::string config = "arbiter: 1\nname: random\nlayers:\n  - name: l\n    behaviours:\n";
    const char* levels[] = {"0", "1", "0.5", "[1, 1]", "[0, 1]"};
    for (int b = 0; b < n; ++b) {
      config += "      b" + std::to_string(b) +
                ": {type: scripted, params: {activation: " + levels[random() % 5] + "}}\n";
    }
    config += "    inhibitions:\n";
    struct Edge {
      int from, to;
      bool chaining;
    };
    std::vector<Edge> edges;
    for (int e = 0; e < 2 * n; ++e) {
      const int from = static_cast<int>(random() % n);
      const int to = static_cast<int>(random() % n);
      if (from >= to) continue;
      if (std::any_of(edges.begin(), edges.end(),
                      [&](const Edge& x) { return x.from == from && x.to == to; })) {
        continue;
      }
      edges.push_back({from, to, random() % 3 != 0});
      config += "      - b" + std::to_string(from) + (edges.back().chaining ? " => b" : " -> b") +
                std::to_string(to) + "\n";
    }
    Diagnostics diagnostics;
    auto document = parse_document(config, "random.yaml", DocumentFormat::kYaml, diagnostics);
    const Model model = build_model(*document, registry, diagnostics);
    auto program = compile(model, registry, diagnostics);
    INFO(config << format(diagnostics));
    REQUIRE(program.has_value());
    lint(model, *program, diagnostics);

    std::set<std::string> never_reported;
    std::set<std::string> redundant_reported;
    for (const auto& item : diagnostics.items()) {
      const auto first = item.message.find('\'') + 1;
      const std::string quoted = item.message.substr(first, item.message.find('\'', first) - first);
      if (item.code == "never-active") never_reported.insert(quoted);
      if (item.code == "redundant-inhibition") redundant_reported.insert(quoted);
    }
    // Brute force, in execution order, over the closed inhibitor lists.
    const auto count = program->behaviours.size();
    std::vector<bool> full(count, false);
    std::vector<bool> never(count, false);
    std::set<std::string> never_expected;
    for (std::uint32_t b = 0; b < count; ++b) {
      const auto closed = program->inhibitions.closed(b);
      const BehaviourDecl* decl = nullptr;
      for (const auto& candidate : model.layers[0].behaviours) {
        if (candidate.name.text == program->behaviours[b].name) decl = &candidate;
      }
      REQUIRE(decl != nullptr);
      const auto& requested = std::get<std::vector<double>>(decl->params.find("activation")->value);
      const auto all = [&](double v) {
        return std::all_of(requested.begin(), requested.end(), [&](double r) { return r == v; });
      };
      const bool covered =
          std::any_of(closed.begin(), closed.end(), [&](std::uint32_t i) { return full[i]; });
      const bool free =
          std::all_of(closed.begin(), closed.end(), [&](std::uint32_t i) { return never[i]; });
      full[b] = all(1.0) && free;
      never[b] = covered || all(0.0);
      if (covered) never_expected.insert(program->behaviours[b].name);
    }
    CHECK(never_reported == never_expected);
    // An edge a -> c is redundant when c is reachable from a chaining successor x != c of a.
    std::set<std::string> redundant_expected;
    for (const auto& edge : edges) {
      std::vector<int> stack;
      std::vector<bool> seen(static_cast<std::size_t>(n), false);
      for (const auto& out : edges) {
        if (out.from == edge.from && out.chaining && out.to != edge.to) stack.push_back(out.to);
      }
      bool reached = false;
      while (!stack.empty() && !reached) {
        const int at = stack.back();
        stack.pop_back();
        if (seen[static_cast<std::size_t>(at)]) continue;
        seen[static_cast<std::size_t>(at)] = true;
        for (const auto& out : edges) {
          if (out.from != at || !out.chaining) continue;
          reached = reached || out.to == edge.to;
          stack.push_back(out.to);
        }
      }
      if (reached) {
        redundant_expected.insert("b" + std::to_string(edge.from) +
                                  (edge.chaining ? " => b" : " -> b") + std::to_string(edge.to));
      }
    }
    CHECK(redundant_reported == redundant_expected);
  }
}

TEST_CASE("redundant inhibitions are found in layers larger than one block of reachability",
          "[lint]") {
  std::string config = "arbiter: 1\nname: long\nlayers:\n  - name: l\n    behaviours:\n";
  constexpr int kCount = 5000;
  for (int b = 0; b < kCount; ++b) {
    config += "      b" + std::to_string(b) + ": {type: scripted, params: {activation: 0.5}}\n";
  }
  config += "    inhibitions:\n";
  for (int b = 0; b + 1 < kCount; ++b) {
    config += "      - b" + std::to_string(b) + " => b" + std::to_string(b + 1) + "\n";
  }
  config += "      - b0 -> b4999\n      - b10 => b4100\n      - b4097 -> b4099\n";
  const Diagnostics diagnostics = linted(config, "long.yaml", builtin_registry());
  std::vector<std::string> messages;
  for (const auto& item : diagnostics.items()) messages.push_back(item.message);
  CHECK(messages ==
        std::vector<std::string>{
            "inhibition 'b0 -> b4999' is already implied by chaining b0 => b1 => b2 => b3 => b4 "
            "=> b5 => b6 => b7 => b8 => b9 => b10 => b11 => b12 => ... => b4999",
            "inhibition 'b10 => b4100' is already implied by chaining b10 => b11 => b12 => b13 => "
            "b14 => b15 => b16 => b17 => b18 => b19 => b20 => b21 => b22 => ... => b4100",
            "inhibition 'b4097 -> b4099' is already implied by chaining b4097 => b4098 => b4099"});
}
