// Behaviour code that throws (docs/robustness.md), as the manager contains it: the throw is
// caught at the step boundary, reported once, and handled by the config's or the behaviour's
// `on_exception` policy; an interface's throw follows the same policy, and a class that throws
// from init() is a load error.

#include <catch2/catch.hpp>
#include <string>
#include <utility>
#include <vector>

#include "config_files.hpp"
#include "fault_support.hpp"

using namespace arbiter;
using namespace arbiter::test;

namespace {

/// One layer in which `broken` (robust.Faulty with the params `faulty`, writing 9) inhibits
/// `fine` (a probe at level 0.5 writing 1), both writing the actuator `speed`. `keys` follow
/// broken's ports; `top` are top-level keys, as one_layer() takes them.
std::string broken_over_fine(const std::string& faulty, const std::string& keys = "",
                             const std::string& top = "") {
  return one_layer(R"(
    actuators:
      speed: {type: double}
    behaviours:
      broken: {type: robust.Faulty, params: {)" +
                       faulty + R"(, value: 9},
               ports: {out: speed})" +
                       keys + R"(}
      fine: {type: test.Probe, params: {levels: 0.5, value: 1}, ports: {out: speed}}
    inhibitions: [broken -> fine]
)",
                   top);
}

}  // namespace

TEST_CASE("a throwing behaviour counts as inactive in that step and is reported once",
          "[robustness][faults]") {
  Log log;
  auto manager = make(broken_over_fine("callback: activation, from: 2, until: 3"), log);
  std::vector<double> broken_levels;
  std::vector<double> fine_levels;
  std::vector<double> speeds;
  for (int step = 0; step < 5; ++step) {
    manager.step();
    broken_levels.push_back(test::activation_of(manager, "l", "broken"));
    fine_levels.push_back(test::activation_of(manager, "l", "fine"));
    speeds.push_back(actuator(manager, "speed"));
  }
  CHECK(broken_levels == std::vector<double>{1, 0, 0, 1, 1});
  CHECK(fine_levels == std::vector<double>{0, 0.5, 0.5, 0, 0});
  CHECK(speeds == std::vector<double>{9, 1, 1, 9, 9});
  CHECK_FALSE(manager.stopped());
  INFO(log.text());
  CHECK(log.lines() == 1);
  CHECK(log.count("inline.yaml:8:7: behaviour 'broken' (robust.Faulty) threw from activation() "
                  "in step 2: faulty activation") == 1);
  CHECK(log.count("on_exception: inactive") == 1);
}

TEST_CASE("a throw from update() or execute() leaves no level and no write for that step",
          "[robustness][faults]") {
  Log log;
  auto manager = make(test::one_layer(R"(
    actuators:
      speed: {type: double, aggregate: true}
    behaviours:
      in_update: {type: robust.Faulty, params: {callback: update, from: 2, until: 2, value: 5},
                  ports: {out: speed}}
      in_execute: {type: robust.Faulty, params: {callback: execute, from: 3, until: 3, value: 7},
                   ports: {out: speed}}
      in_inhibited: {type: robust.Faulty, params: {callback: inhibited, level: 0}}
)"),
                      log);
  auto& in_update = behaviour<Faulty>(manager, "l", "in_update");
  auto& in_inhibited = behaviour<Faulty>(manager, "l", "in_inhibited");
  manager.step();
  CHECK(actuator(manager, "speed") == 6.0);  // (5 + 7) / 2
  manager.step();
  // in_update threw from update(): not asked for a level, not executed, and back next step.
  CHECK(test::activation_of(manager, "l", "in_update") == 0.0);
  CHECK(in_update.activations == 1);
  CHECK(in_update.executions == 1);
  CHECK(actuator(manager, "speed") == 7.0);
  manager.step();
  // in_execute wrote 7, then threw: the write is dropped; its level stays as refined.
  CHECK(test::activation_of(manager, "l", "in_execute") == 1.0);
  CHECK(actuator(manager, "speed") == 5.0);
  CHECK(in_update.activations == 2);
  manager.step();
  CHECK(actuator(manager, "speed") == 6.0);
  CHECK(in_inhibited.inhibitions == 4);  // it throws every step: reported once, called on
  INFO(log.text());
  CHECK(log.count("threw from update() in step 2") == 1);
  CHECK(log.count("threw from execute() in step 3") == 1);
  CHECK(log.count("threw from inhibited() in step 1") == 1);
  CHECK(log.lines() == 3);
}

TEST_CASE("on_exception: disable takes a behaviour out for the rest of the run",
          "[robustness][faults]") {
  Log log;
  auto manager = make(
      broken_over_fine("callback: execute, from: 2, until: 2", ", on_exception: disable"), log);
  auto& broken = behaviour<Faulty>(manager, "l", "broken");
  manager.step();
  CHECK(actuator(manager, "speed") == 9.0);
  manager.step();  // broken writes 9 and throws: dropped; fine is still inhibited this step
  CHECK(actuator(manager, "speed") == 9.0);
  CHECK_FALSE(written(manager, "speed"));
  for (int step = 0; step < 3; ++step) manager.step();
  CHECK(test::activation_of(manager, "l", "broken") == 0.0);
  CHECK(manager.requested(*manager.program().find_behaviour("l", "broken")) == 0.0);
  CHECK(test::activation_of(manager, "l", "fine") == 0.5);
  CHECK(actuator(manager, "speed") == 1.0);
  CHECK(broken.updates == 2);
  CHECK(broken.activations == 2);
  CHECK(broken.executions == 2);
  CHECK(broken.inhibitions == 0);
  CHECK_FALSE(manager.stopped());
  INFO(log.text());
  CHECK(log.lines() == 1);
  CHECK(log.count("'broken' (robust.Faulty) threw from execute() in step 2: faulty execute; it "
                  "is disabled for the rest of the run (on_exception: disable)") == 1);
}

TEST_CASE("on_exception: stop completes the step, then the manager stops", "[robustness][faults]") {
  Log log;
  auto manager =
      make(broken_over_fine("callback: activation, from: 3", "", "on_exception: stop\n"), log);
  JsonTrace trace(manager);
  for (int step = 0; step < 10 && !manager.stopped(); ++step) manager.step();
  CHECK(manager.stopped());
  CHECK(manager.steps() == 3);
  // The step in which it threw ran to the end for everyone else, and was observed.
  CHECK(test::activation_of(manager, "l", "fine") == 0.5);
  CHECK(actuator(manager, "speed") == 1.0);
  const auto records = trace.records();
  REQUIRE(records.size() == 4);  // header and three steps
  CHECK(records[3]["layers"]["l"]["fine"]["active"] == true);
  CHECK_THAT(manager.stop_reason(),
             Catch::Matchers::Contains("inline.yaml:9:7: behaviour 'broken' (robust.Faulty) "
                                       "threw from activation() in step 3"));
  manager.step();
  CHECK(manager.steps() == 3);
  CHECK(behaviour<test::Probe>(manager, "l", "fine").events.size() == 6);  // 3 × update+execute
  INFO(log.text());
  CHECK(log.count("the manager stops after this step (on_exception: stop)") == 1);
}

TEST_CASE("a behaviour's on_exception overrides the config's", "[robustness][faults]") {
  Log log;
  auto manager = make(test::one_layer(R"(
    behaviours:
      tolerated: {type: robust.Faulty, on_exception: inactive}
      fine: {type: test.Probe}
)",
                                      "on_exception: stop\n"),
                      log);
  for (int step = 0; step < 3; ++step) manager.step();
  CHECK_FALSE(manager.stopped());
  CHECK(manager.steps() == 3);
  CHECK(test::activation_of(manager, "l", "fine") == 1.0);
  CHECK(manager.program().behaviours[0].on_exception == FaultPolicy::kInactive);
}

TEST_CASE("an interface that throws loses that pass's writes and follows the policy",
          "[robustness][faults]") {
  const std::string config = R"(arbiter: 1
name: t
on_exception: POLICY
layers:
  - name: world
    interface: robust.FaultyFeed
    params: {callback: input, from: 2, until: 2}
    ports: {out: ticks}
    actuators:
      ticks: {type: double}
  - name: l
    sensors: [ticks]
    behaviours:
      fine: test.Probe
)";
  const auto with = [&](const std::string& policy) {
    std::string text = config;
    text.replace(text.find("POLICY"), 6, policy);
    return text;
  };
  SECTION("inactive") {
    Log log;
    auto manager = make(with("inactive"), log);
    std::vector<double> ticks;
    std::vector<bool> fresh;
    for (int step = 0; step < 3; ++step) {
      manager.step();
      ticks.push_back(actuator(manager, "ticks"));
      fresh.push_back(written(manager, "ticks"));
    }
    CHECK(ticks == std::vector<double>{1, 1, 3});
    CHECK(fresh == std::vector<bool>{true, false, true});
    INFO(log.text());
    CHECK(log.count("inline.yaml:5:11: interface of layer 'world' (robust.FaultyFeed) threw "
                    "from input() in step 2: feed input") == 1);
  }
  SECTION("disable") {
    Log log;
    auto manager = make(with("disable"), log);
    for (int step = 0; step < 4; ++step) manager.step();
    const auto& program = manager.program();
    const auto& feed = dynamic_cast<const FaultyFeed&>(*program.layers[0].interface);
    CHECK(feed.inputs == 2);
    CHECK(feed.outputs == 1);
    CHECK(actuator(manager, "ticks") == 1.0);
    CHECK_FALSE(written(manager, "ticks"));
  }
  SECTION("stop") {
    Log log;
    auto manager = make(with("stop"), log);
    for (int step = 0; step < 4 && !manager.stopped(); ++step) manager.step();
    CHECK(manager.stopped());
    CHECK(manager.steps() == 2);
  }
  SECTION("a throw of something that is not an exception") {
    Log log;
    std::string text = with("inactive");
    text.replace(text.find("callback: input"), 15, "callback: output");
    auto manager = make(text, log);
    for (int step = 0; step < 3; ++step) manager.step();
    INFO(log.text());
    CHECK(log.count("threw from output() in step 2: unknown exception") == 1);
  }
}

TEST_CASE("a class that throws from init() is a load error at its declaration",
          "[robustness][faults][config]") {
  const auto errors = [](const std::string& config) {
    std::vector<std::string> lines;
    const Diagnostics diagnostics = test::diagnose_text(config, fault_registry());
    for (const auto& item : diagnostics.items()) {
      CHECK(item.code == "init-failed");
      const std::string text = format(item);
      lines.push_back(text.substr(0, text.find('\n')));
    }
    return lines;
  };
  CHECK(errors(R"(arbiter: 1
name: t
layers:
  - name: world
    interface: robust.FaultyFeed
    params: {callback: init}
  - name: l
    behaviours:
      broken: {type: robust.Faulty, params: {callback: init}}
      fine: test.Probe
)") == std::vector<std::string>{"inline.yaml:4:11: error: class robust.FaultyFeed failed to "
                                "initialise (unknown exception)",
                                "inline.yaml:9:7: error: class robust.Faulty failed to "
                                "initialise: faulty init"});
  // Every object of the state's pool (capacity 4) is initialised alike: one error, not four.
  const auto state_errors = errors(R"(arbiter: 1
name: t
state_machines:
  plan:
    capacity: 4
    states:
      boom: {type: robust.FaultyState, params: {callback: init}}
    queue: [boom]
)");
  CHECK(state_errors == std::vector<std::string>{"inline.yaml:7:7: error: class "
                                                 "robust.FaultyState failed to initialise: "
                                                 "faulty state init"});
}

TEST_CASE("on_exception is checked like any other key", "[robustness][faults][config]") {
  const auto codes = [](const std::string& text) {
    return error_codes(test::diagnose_text(text, fault_registry()));
  };
  CHECK(codes("arbiter: 1\nname: t\non_exception: abort\n") ==
        std::vector<std::string>{"out-of-range"});
  const auto diagnostics =
      test::diagnose_text("arbiter: 1\nname: t\non_exception: disabled\n", fault_registry());
  REQUIRE(diagnostics.items().size() == 1);
  CHECK(diagnostics.items()[0].message ==
        "'on_exception' must be inactive, disable or stop, found the string 'disabled'");
  REQUIRE(diagnostics.items()[0].notes.size() == 1);
  CHECK(diagnostics.items()[0].notes[0].text ==
        "did you mean 'disable'? allowed: disable, inactive, stop");
  CHECK(codes("arbiter: 1\nname: t\non_exception: [stop]\n") ==
        std::vector<std::string>{"wrong-type"});
  CHECK(codes("arbiter: 1\nname: t\nlayers:\n  - name: l\n    behaviours:\n      b: {type: "
              "scripted, on_exception: 1}\n") == std::vector<std::string>{"out-of-range"});
  CHECK(codes("arbiter: 1\nname: t\nlayers:\n  - name: l\n    behaviours:\n      b: {type: "
              "scripted, on_exception: stop}\n")
            .empty());
  TempDir dir;
  write_text(dir / "part.yaml", "arbiter: 1\non_exception: stop\n");
  write_text(dir / "main.yaml", "arbiter: 1\nname: t\ninclude: [part.yaml]\n");
  const Outcome outcome = load_file(dir / "main.yaml");
  CHECK(error_codes(outcome.diagnostics) == std::vector<std::string>{"unknown-key"});
}

TEST_CASE("a behaviour that fails every way at once leaves the others and the trace intact",
          "[robustness][faults]") {
  // The same config with and without the faulty behaviours gives the same records for the rest.
  const std::string base = test::one_layer(R"(
    actuators:
      speed: {type: double, aggregate: true}
    behaviours:
      a: {type: test.Probe, params: {levels: [1, 0, 0.5], value: 1}, ports: {out: speed}}
      b: {type: test.Probe, params: {levels: 0.5, value: 3}, ports: {out: speed}}
)");
  const std::string faulty =
      base + R"(      t1: {type: robust.Faulty, params: {callback: update, level: 0}}
      t2: {type: robust.Faulty, params: {callback: execute, level: 0.000001}, ports: {out: speed}}
      t3: {type: robust.Odd, params: {level: nan, value: nan}, ports: {out: speed}}
      t4: {type: test.Thrower, on_exception: disable}
)";
  const auto records_of = [](const std::string& text) {
    Log log;
    auto manager = make(text, log);
    JsonTrace trace(manager);
    std::vector<double> speeds;
    for (int step = 0; step < 6; ++step) {
      manager.step();
      speeds.push_back(actuator(manager, "speed"));
    }
    auto records = trace.records();
    for (auto& record : records) {
      if (!record.contains("step")) continue;
      for (const auto* name : {"t1", "t2", "t3", "t4"}) record["layers"]["l"].erase(name);
    }
    return std::make_pair(records, speeds);
  };
  const auto [plain_records, plain_speeds] = records_of(base);
  const auto [faulty_records, faulty_speeds] = records_of(faulty);
  REQUIRE(plain_records.size() == faulty_records.size());
  for (std::size_t i = 1; i < plain_records.size(); ++i) {
    CHECK(plain_records[i]["layers"] == faulty_records[i]["layers"]);
  }
  CHECK(plain_speeds == faulty_speeds);
}
