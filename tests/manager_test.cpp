// The behaviour manager's step, checked against docs/semantics.md one rule at a time.

#include <catch2/catch.hpp>

#include <fstream>
#include <sstream>

#include "arbiter/trace.hpp"
#include "test_support.hpp"

using namespace arbiter;
using Catch::Matchers::WithinAbs;

namespace {

const Registry& registry() {
  static const Registry instance = test::make_test_registry();
  return instance;
}

Manager run(const std::string& yaml, int steps) {
  Manager manager(test::compile_text(yaml, registry()));
  for (int i = 0; i < steps; ++i) manager.step();
  return manager;
}

std::vector<std::string> order_of(const Program& program, const std::string& layer) {
  std::vector<std::string> names;
  for (const auto& compiled : program.layers) {
    if (compiled.name != layer) continue;
    for (auto b = compiled.behaviour_begin; b < compiled.behaviour_end; ++b) {
      names.push_back(program.behaviours[b].name);
    }
  }
  return names;
}

std::vector<std::string> inhibitors_of(const Program& program, const std::string& layer,
                                       const std::string& name) {
  const auto b = *program.find_behaviour(layer, name);
  std::vector<std::string> names;
  for (const auto inhibitor : program.inhibitions.closed(b)) {
    names.push_back(program.behaviours[inhibitor].name);
  }
  return names;
}

std::string trace_of(const std::string& text, const std::string& file, int steps) {
  Manager manager(test::compile_text(text, registry(), file));
  return test::run_traced(manager, steps);
}

}  // namespace

TEST_CASE("0.7 inhibiting 0.9 leaves 0.27, as in the paper", "[semantics][refinement]") {
  const std::string config = R"(
arbiter: 1
name: paper
layers:
  - name: l
    behaviours:
      a: {type: test.Probe, params: {levels: 0.7}}
      b: {type: test.Probe, params: {levels: 0.9}}
    inhibitions: [a -> b]
)";
  auto manager = run(config, 1);
  CHECK_THAT(test::activation_of(manager, "l", "a"), WithinAbs(0.7, 1e-12));
  CHECK_THAT(test::activation_of(manager, "l", "b"), WithinAbs(0.27, 1e-12));
  CHECK(manager.requested(*manager.program().find_behaviour("l", "b")) == 0.9);

  SECTION("normalise divides by the layer's sum: 0.7/0.97 and 0.27/0.97") {
    for (const std::string where : {"manager", "layer"}) {
      std::string normalised = config;
      if (where == "manager") {
        normalised.insert(normalised.find("layers:"), "normalise: true\n");
      } else {
        normalised.insert(normalised.find("    behaviours:"), "    normalise: true\n");
      }
      auto normal = run(normalised, 1);
      CHECK_THAT(test::activation_of(normal, "l", "a"), WithinAbs(0.7 / 0.97, 1e-12));
      CHECK_THAT(test::activation_of(normal, "l", "b"), WithinAbs(0.27 / 0.97, 1e-12));
    }
  }
}

TEST_CASE("refinement uses the inhibitors' refined levels in topological order",
          "[semantics][refinement]") {
  // c is declared first but runs last: a -> b -> c.
  auto manager = run(test::one_layer(R"(
    behaviours:
      c: {type: test.Probe, params: {levels: 1.0}}
      b: {type: test.Probe, params: {levels: 0.5}}
      a: {type: test.Probe, params: {levels: 0.5}}
    inhibitions: [a -> b, b -> c]
)"),
                     1);
  CHECK(order_of(manager.program(), "l") == std::vector<std::string>{"a", "b", "c"});
  CHECK_THAT(test::activation_of(manager, "l", "b"), WithinAbs(0.25, 1e-12));
  CHECK_THAT(test::activation_of(manager, "l", "c"), WithinAbs(0.75, 1e-12));
}

TEST_CASE("topological order takes the ready behaviour declared first", "[semantics][order]") {
  auto program = test::compile_text(test::one_layer(R"(
    behaviours:
      e: test.Probe
      d: test.Probe
      c: test.Probe
      b: test.Probe
      a: test.Probe
    inhibitions: [a -> d, b -> e]
)"),
                                    registry());
  // Ready at first: c, a, b (in declaration order: c, b, a ... after e and d are blocked).
  CHECK(order_of(program, "l") == std::vector<std::string>{"c", "b", "e", "a", "d"});

  SECTION("with no inhibitions the order is the declaration order") {
    auto plain = test::compile_text(test::one_layer(R"(
    behaviours: {z: test.Probe, y: test.Probe, x: test.Probe}
)"),
                                    registry());
    CHECK(order_of(plain, "l") == std::vector<std::string>{"z", "y", "x"});
  }
}

TEST_CASE("chaining closes over chaining edges only", "[semantics][closure]") {
  auto program = test::compile_text(test::one_layer(R"(
    behaviours:
      a: test.Probe
      b: test.Probe
      c: test.Probe
      d: test.Probe
      p: test.Probe
      q: test.Probe
      r: test.Probe
      x: test.Probe
      y: test.Probe
      z: test.Probe
    inhibitions:
      - a => b
      - b => c
      - c => d
      - p => q
      - q -> r
      - x -> y
      - y => z
)"),
                                    registry());
  SECTION("a chain of chaining edges gives every implicit edge") {
    CHECK(inhibitors_of(program, "l", "c") == std::vector<std::string>{"a", "b"});
    CHECK(inhibitors_of(program, "l", "d") == std::vector<std::string>{"a", "b", "c"});
  }
  SECTION("A => B -> C gives no A-C edge") {
    CHECK(inhibitors_of(program, "l", "r") == std::vector<std::string>{"q"});
  }
  SECTION("A -> B => C gives no A-C edge") {
    CHECK(inhibitors_of(program, "l", "z") == std::vector<std::string>{"y"});
  }
  SECTION("implicit edges are marked as such") {
    std::size_t implicit = 0;
    for (const auto& inhibition : program.inhibitions) implicit += inhibition.implicit ? 1 : 0;
    CHECK(implicit == 3);  // a-c, b-d, a-d
    const auto a = *program.find_behaviour("l", "a");
    const auto d = *program.find_behaviour("l", "d");
    CHECK(program.chain(a, d).size() == 4);
  }
}

TEST_CASE("an implicit inhibition takes part in refinement", "[semantics][closure]") {
  // a => b => c with b inactive: c is still inhibited by a through the chain.
  auto manager = run(test::one_layer(R"(
    behaviours:
      a: {type: test.Probe, params: {levels: 0.5}}
      b: {type: test.Probe, params: {levels: 0.0}}
      c: {type: test.Probe, params: {levels: 1.0}}
    inhibitions: [a => b, b => c]
)"),
                     1);
  CHECK_THAT(test::activation_of(manager, "l", "c"), WithinAbs(0.5, 1e-12));

  std::ostringstream out;
  TraceWriter trace(out);
  manager.add_observer(trace);
  manager.step();
  CHECK_THAT(out.str(), Catch::Matchers::Contains(
                            R"("c": {"requested": 1.0, "activation": 0.5, "active": true, )"
                            R"("inhibited_by": ["a"]})"));
}

TEST_CASE("a cycle created through the chaining closure is an error", "[semantics][closure]") {
  const auto diagnostics = test::diagnose_text(test::one_layer(R"(
    behaviours: {a: test.Probe, b: test.Probe, c: test.Probe}
    inhibitions: [a => b, b => c, c -> a]
)"),
                                               registry());
  REQUIRE(diagnostics.error_count() == 1);
  CHECK(diagnostics.items()[0].code == "inhibition-cycle");
  // The shortest cycle of the closed graph uses the implicit a => c.
  CHECK_THAT(diagnostics.items()[0].message, Catch::Matchers::Contains("implicit"));
  CHECK_THAT(diagnostics.items()[0].message, Catch::Matchers::EndsWith("-> a"));
}

TEST_CASE("requested levels are clamped and NaN counts as 0", "[semantics][levels]") {
  auto manager = run(test::one_layer(R"(
    behaviours:
      high: {type: test.Probe, params: {levels: 3.5}}
      low: {type: test.Probe, params: {levels: -2}}
      nan: test.NanLevel
)"),
                     2);
  CHECK(test::activation_of(manager, "l", "high") == 1.0);
  CHECK(test::activation_of(manager, "l", "low") == 0.0);
  CHECK(test::activation_of(manager, "l", "nan") == 0.0);
  CHECK_FALSE(manager.active(*manager.program().find_behaviour("l", "nan")));
  CHECK(manager.requested(*manager.program().find_behaviour("l", "nan")) == 0.0);
}

TEST_CASE("a behaviour that throws counts as inactive and the others go on",
          "[semantics][levels]") {
  auto manager = run(test::one_layer(R"(
    behaviours:
      broken: test.Thrower
      fine: {type: test.Probe, params: {levels: 0.5}}
    inhibitions: [broken -> fine]
)"),
                     3);
  CHECK(test::activation_of(manager, "l", "broken") == 0.0);
  CHECK(test::activation_of(manager, "l", "fine") == 0.5);
}

TEST_CASE("active iff a > 0, with just-activated and just-deactivated", "[semantics][activity]") {
  auto manager = run(test::one_layer(R"(
    behaviours:
      a: {type: test.Probe, params: {levels: [0, 0.1, 0.2, 0, 0]}}
)"),
                     5);
  const auto& probe = test::instance<test::Probe>(manager.program(), "l", "a");
  CHECK(probe.events ==
        std::vector<std::string>{"update 1", "inhibited 1", "update 2", "execute 2 just_activated",
                                 "update 3", "execute 3", "update 4",
                                 "inhibited 4 just_deactivated", "update 5", "inhibited 5"});
}

TEST_CASE("aggregatable actuators take the activation-weighted mean", "[semantics][actuators]") {
  auto manager = run(test::one_layer(R"(
    actuators:
      speed: {type: double, aggregate: true}
    behaviours:
      a: {type: test.Probe, params: {levels: 0.5, value: 1.0}, ports: {out: speed}}
      b: {type: test.Probe, params: {levels: 1.0, value: 4.0}, ports: {out: speed}}
      c: {type: test.Probe, params: {levels: 0.0, value: 100.0}, ports: {out: speed}}
)"),
                     1);
  const auto speed = *manager.program().find_actuator("speed");
  // (0.5 * 1 + 1.0 * 4) / 1.5 = 3; the inactive c does not count.
  CHECK_THAT(manager.actuator<double>(speed), WithinAbs(3.0, 1e-12));
  CHECK(manager.actuator_written(speed));
}

TEST_CASE("a non-aggregatable actuator takes the most active writer, ties to the earlier",
          "[semantics][actuators]") {
  const std::string config = test::one_layer(R"(
    actuators:
      speed: {type: double}
    behaviours:
      a: {type: test.Probe, params: {levels: LEVEL_A, value: 1.0}, ports: {out: speed}}
      b: {type: test.Probe, params: {levels: 0.6, value: 2.0}, ports: {out: speed}}
)");
  auto with = [&](const std::string& level) {
    std::string text = config;
    text.replace(text.find("LEVEL_A"), 7, level);
    auto manager = run(text, 1);
    return manager.actuator<double>(*manager.program().find_actuator("speed"));
  };
  CHECK(with("0.9") == 1.0);
  CHECK(with("0.3") == 2.0);
  CHECK(with("0.6") == 1.0);  // tie: a runs first
}

TEST_CASE("written values persist and the written flag is per step", "[semantics][actuators]") {
  auto manager = run(test::one_layer(R"(
    actuators:
      speed: {type: double, default: 7.5}
      idle: {type: double, default: 2.0}
    behaviours:
      a: {type: test.Probe, params: {levels: [1, 0, 0], value: 5.0}, ports: {out: speed}}
)"),
                     0);
  const auto speed = *manager.program().find_actuator("speed");
  const auto idle = *manager.program().find_actuator("idle");
  CHECK(manager.actuator<double>(speed) == 7.5);  // the default before any write
  manager.step();
  CHECK(manager.actuator<double>(speed) == 5.0);
  CHECK(manager.actuator_written(speed));
  manager.step();
  CHECK(manager.actuator<double>(speed) == 5.0);
  CHECK_FALSE(manager.actuator_written(speed));
  CHECK(manager.actuator<double>(idle) == 2.0);
}

TEST_CASE("sensors see earlier layers' values this step and later layers' last step",
          "[semantics][timing]") {
  // top writes step-dependent values; middle reads top (same step) and bottom (one step late);
  // top reads its own actuator through a sensor (one step late as well).
  auto manager = run(R"(
arbiter: 1
name: t
layers:
  - name: top
    sensors: [from_top]
    actuators:
      from_top: {type: double}
    behaviours:
      writer: {type: test.Probe, params: {levels: 1, value: 1.0}, ports: {out: from_top, in: from_top}}
  - name: middle
    sensors: [from_top, from_bottom]
    behaviours:
      sees_top: {type: test.Probe, ports: {in: from_top}}
      sees_bottom: {type: test.Probe, ports: {in: from_bottom}}
  - name: bottom
    actuators:
      from_bottom: {type: double, default: -1}
    behaviours:
      writer: {type: test.Probe, params: {levels: [0, 1], value: 9.0}, ports: {out: from_bottom}}
)",
                     3);
  const auto& program = manager.program();
  const auto& sees_top = test::instance<test::Probe>(program, "middle", "sees_top");
  const auto& sees_bottom = test::instance<test::Probe>(program, "middle", "sees_bottom");
  const auto& top = test::instance<test::Probe>(program, "top", "writer");
  CHECK(sees_top.seen == std::vector<double>{1.0, 1.0, 1.0});
  CHECK(sees_top.seen_written == std::vector<bool>{true, true, true});
  // bottom first writes in step 2; middle sees it in step 3. Before: the default.
  CHECK(sees_bottom.seen == std::vector<double>{-1.0, -1.0, 9.0});
  CHECK(sees_bottom.seen_written == std::vector<bool>{false, false, true});
  CHECK(top.seen == std::vector<double>{0.0, 1.0, 1.0});
  CHECK(top.seen_written == std::vector<bool>{false, true, true});
}

TEST_CASE("interface layers write in the input pass and read in the output pass",
          "[semantics][interface]") {
  auto manager = run(R"(
arbiter: 1
name: t
layers:
  - name: control
    sensors: [measured]
    actuators:
      command: {type: double}
    behaviours:
      echo: {type: test.Probe, params: {levels: 1, value: 3.0}, ports: {in: measured, out: command}}
  - name: world
    interface: test.Feed
    ports: {out: measured, in: command}
    actuators:
      measured: {type: double}
    sensors: [command]
)",
                     3);
  const auto& program = manager.program();
  // The world layer comes after control, yet control sees this step's measurement...
  CHECK(test::instance<test::Probe>(program, "control", "echo").seen ==
        std::vector<double>{10.0, 20.0, 30.0});
  // ...and the world reads this step's command in the output pass.
  const auto world = program.layers[1].interface.get();
  CHECK(dynamic_cast<test::Feed&>(*world).seen == std::vector<double>{3.0, 3.0, 3.0});
}

TEST_CASE("a behaviour's second write in one step replaces its first", "[semantics][actuators]") {
  auto manager = run(test::one_layer(R"(
    actuators:
      speed: {type: double, aggregate: true}
    behaviours:
      twice: {type: test.Probe, params: {levels: 1, value: 2.0, overwrite: true}, ports: {out: speed}}
      once: {type: test.Probe, params: {levels: 1, value: 4.0}, ports: {out: speed}}
)"),
                     1);
  CHECK(manager.actuator<double>(*manager.program().find_actuator("speed")) == 3.0);
}

TEST_CASE("YAML and JSON configs give identical traces", "[semantics][formats]") {
  const std::string dir = std::string(ARBITER_SOURCE_DIR) + "/configs/paper/";
  auto read = [](const std::string& path) {
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  };
  const auto yaml = trace_of(read(dir + "walk_and_kick.yaml"), "walk_and_kick.yaml", 20);
  const auto json = trace_of(read(dir + "walk_and_kick.json"), "walk_and_kick.json", 20);
  CHECK(std::count(yaml.begin(), yaml.end(), '\n') == 21);
  CHECK(yaml == json);
}
