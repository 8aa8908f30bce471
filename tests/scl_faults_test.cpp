// State machines whose code throws (docs/robustness.md): a state or a controller hook that throws
// stops its controller, reported once, and under a config-wide `on_exception: stop` the manager.

#include <catch2/catch.hpp>
#include <cstdint>
#include <map>
#include <string>

#include "fault_support.hpp"

using namespace arbiter;
using namespace arbiter::test;

TEST_CASE("a throwing state stops its controller and, under a config-wide stop, the manager",
          "[robustness][faults][scl]") {
  const std::string config = R"(arbiter: 1
name: t
POLICY
layers:
  - name: l
    behaviours:
      fine: test.Probe
state_machines:
  plan:
    states:
      boom: {type: test.Planner, params: {op: throw, hold: 2}}
    queue: [boom]
)";
  for (const std::string policy : {"on_exception: inactive", "on_exception: stop"}) {
    DYNAMIC_SECTION(policy) {
      std::string text = config;
      text.replace(text.find("POLICY"), 6, policy);
      Log log;
      auto manager = make(text, log);
      for (int step = 0; step < 5 && !manager.stopped(); ++step) manager.step();
      const Controller* plan = manager.program().find_controller("plan");
      CHECK(plan->status() == ControllerStatus::kError);
      CHECK_THAT(plan->error(), Catch::Matchers::Contains("state failure"));
      if (policy == "on_exception: inactive") {
        CHECK_FALSE(manager.stopped());
        CHECK(manager.steps() == 5);
      } else {
        CHECK(manager.stopped());
        CHECK(manager.steps() == 2);
        CHECK_THAT(manager.stop_reason(),
                   Catch::Matchers::Contains("state machine 'plan' stopped with an error"));
      }
      CHECK(test::activation_of(manager, "l", "fine") == 1.0);
    }
  }
}

TEST_CASE("a state that throws from any callback stops its controller, reported once",
          "[robustness][faults][scl]") {
  const std::string config = test::one_layer(R"(
    behaviours:
      fine: test.Probe
state_machines:
  plan:
    states:
      boom: {type: robust.FaultyState, params: {callback: CALLBACK}}
      after: test.Planner
    queue: [boom, after]
)",
                                             "on_exception: POLICY\n");
  // The step in which each callback first runs: boom is activated and executed in step 1 and,
  // having asked to proceed, deactivated in step 2.
  const std::map<std::string, std::uint64_t> first_call = {
      {"activate", 1}, {"execute", 1}, {"deactivate", 2}};
  for (const auto& [callback, step] : first_call) {
    for (const std::string policy : {"inactive", "stop"}) {
      DYNAMIC_SECTION(callback << ", on_exception: " << policy) {
        std::string text = config;
        text.replace(text.find("POLICY"), 6, policy);
        text.replace(text.find("CALLBACK"), 8, callback);
        Log log;
        auto manager = make(text, log);
        JsonTrace trace(manager);
        for (int i = 0; i < 5 && !manager.stopped(); ++i) manager.step();
        const Controller* plan = manager.program().find_controller("plan");
        CHECK(plan->status() == ControllerStatus::kError);
        const std::string error =
            "controller 'plan' (inline.yaml:9:3), state 'boom' "
            "(inline.yaml:11:7): a state threw: faulty " +
            callback;
        CHECK(plan->error() == error);
        INFO(log.text());
        CHECK(log.count(error + "; the controller stops with status error") == 1);
        CHECK(test::activation_of(manager, "l", "fine") == 1.0);
        const auto records = trace.records();
        REQUIRE(records.size() >= 2);
        CHECK(records.back()["controllers"]["plan"]["status"] == "error");
        CHECK(records.back()["layers"]["l"]["fine"]["active"] == true);
        if (policy == "inactive") {
          CHECK_FALSE(manager.stopped());
          CHECK(manager.steps() == 5);
          CHECK(log.lines() == 1);
        } else {
          CHECK(manager.stopped());
          CHECK(manager.steps() == step);
          CHECK_THAT(
              manager.stop_reason(),
              Catch::Matchers::StartsWith("state machine 'plan' stopped with an error: " + error));
        }
      }
    }
  }
}

TEST_CASE("a controller hook that throws stops that controller only", "[robustness][faults][scl]") {
  for (const std::string hook :
       {"pre_step", "pre_activate", "pre_execute", "post_execute", "post_step", "on_terminate"}) {
    DYNAMIC_SECTION(hook) {
      FaultyHooks hooks(hook);  // outlives the manager, as set_hooks asks
      Log log;
      auto manager = make(test::one_layer(R"(
    behaviours:
      fine: test.Probe
state_machines:
  plan:
    states:
      once: test.Planner
    queue: [once]
  other:
    states:
      again: {type: test.Planner, params: {hold: 100}}
    queue: [again]
)"),
                          log);
      manager.program().controllers[0]->set_hooks(&hooks);
      for (int step = 0; step < 4; ++step) manager.step();
      const Controller* plan = manager.program().find_controller("plan");
      const Controller* other = manager.program().find_controller("other");
      CHECK(plan->status() == ControllerStatus::kError);
      CHECK_THAT(plan->error(),
                 Catch::Matchers::StartsWith("controller 'plan' (inline.yaml:8:3)") &&
                     Catch::Matchers::EndsWith("hook " + hook));
      CHECK(other->status() == ControllerStatus::kRunning);
      CHECK(other->cycle() == 4);
      CHECK_FALSE(manager.stopped());
      CHECK(test::activation_of(manager, "l", "fine") == 1.0);
      INFO(log.text());
      CHECK(log.lines() == 1);
    }
  }
}
