// The dumps as text, DOT and JSON (arbiter dump), against the golden files in tests/data/golden.
// Run with ARBITER_UPDATE_GOLDEN=1 to rewrite them from the current output (then review the diff
// by eye; never in CI).

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <string>

#include "arbiter/dump.hpp"
#include "tooling_support.hpp"

namespace fs = std::filesystem;
using namespace arbiter;
using namespace arbiter::test;
using Json = nlohmann::json;

TEST_CASE("arbiter dump prints the paper example the same way every time", "[dump][cli]") {
  for (const std::string format : {"text", "dot", "json"}) {
    DYNAMIC_SECTION(format) {
      const std::string command = std::string("dump ") + kWalkAndKick + " --format " + format;
      const auto first = run_cli(command);
      const auto second = run_cli(command);
      INFO(first.err);
      REQUIRE(first.exit_code == 0);
      CHECK(first.out == second.out);
      check_golden("walk_and_kick." + format, first.out);
    }
  }
}

TEST_CASE("a multi-layer config dumps as text, DOT and JSON", "[dump]") {
  Registry registry = tooling_registry();
  Diagnostics diagnostics;
  test::WorkingDirectory here(kGoldenDir);
  const auto program = load("relay.yaml", registry, diagnostics, test::with_lints());
  INFO(format(diagnostics));
  REQUIRE(program.has_value());
  CHECK(diagnostics.empty());  // its delayed sensor's lint is silenced in its layer
  check_golden("relay.text", dump_text(*program));
  check_golden("relay.dot", dump_dot(*program));
  check_golden("relay.json", dump_json(*program));
  CHECK(dump_dot(*program) == dump_dot(*program));

  SECTION("one layer") {
    const std::string dot = dump_dot(*program, "control");
    CHECK(contains(dot, "cluster_layer_control"));
    CHECK_FALSE(contains(dot, "cluster_layer_planning"));
    CHECK(contains(dot, "\"a:target\" [label=\"target\\nlayer planning\""));
    const Json json = Json::parse(dump_json(*program, "control"));
    REQUIRE(json["layers"].size() == 1);
    CHECK(json["state_machines"].empty());
  }
}

TEST_CASE("the DOT dump draws chaining double, non-chaining single and implicit dashed", "[dump]") {
  Registry registry = tooling_registry();
  Diagnostics diagnostics;
  const auto dot = dump_dot(load_config(kWalkAndKick, registry, diagnostics));
  CHECK(contains(dot,
                 "\"b:control/kick_ball\" -> \"b:control/go_behind_ball\" [color=\"black:invis:"
                 "black\""));
  CHECK(contains(dot, "\"b:control/search_for_ball\" -> \"b:control/head_control\" [tooltip="));
  CHECK(
      contains(dot, "\"b:control/kick_ball\" -> \"b:control/search_for_ball\" [style=\"dashed\""));
  CHECK(contains(dot, "implicit: kick_ball => go_behind_ball => search_for_ball"));
}

TEST_CASE("arbiter dump rejects an unknown layer as a usage error", "[dump][cli]") {
  const auto result = run_cli(std::string("dump ") + kWalkAndKick + " --layer contrl");
  CHECK(result.exit_code == 2);
  CHECK(contains(result.err, "did you mean 'control'?"));
  CHECK(run_cli(std::string("dump ") + kWalkAndKick + " --format svg").exit_code == 2);
}
