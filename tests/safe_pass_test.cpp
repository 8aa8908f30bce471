// The safe pass (docs/robustness.md): when a run ends, or the manager stops under
// `on_exception: stop`, every actuator with a `safe:` value is set to it and output.

#include <catch2/catch.hpp>
#include <string>
#include <vector>

#include "fault_support.hpp"

using namespace arbiter;
using namespace arbiter::test;

namespace {

const std::string kSafeConfig = R"(arbiter: 1
name: t
on_exception: POLICY
layers:
  - name: control
    actuators:
      speed: {type: double, safe: -1}
      heading: {type: double}
    behaviours:
      drive: {type: test.Probe, params: {levels: 1, value: 5}, ports: {out: speed}}
      broken: {type: robust.Faulty, params: {callback: execute, from: 3, value: 2},
               ports: {out: heading}}
  - name: world
    interface: test.Feed
    ports: {out: measured, in: speed}
    actuators:
      measured: {type: double}
    sensors: [speed]
)";

std::string safe_config(const std::string& policy) {
  std::string text = kSafeConfig;
  text.replace(text.find("POLICY"), 6, policy);
  return text;
}

/// A clock that advances by a fixed amount at each reading.
class ManualClock : public StepClock {
 public:
  double now() override {
    const double t = time;
    time += tick;
    return t;
  }
  double time = 0.0;
  double tick = 0.25;
};

}  // namespace

TEST_CASE("the safe pass outputs every safe value, written, and the run resumes after it",
          "[robustness][safe]") {
  Log log;
  auto manager = make(safe_config("inactive"), log);
  JsonTrace trace(manager);
  manager.safe_pass();  // before the first step: nothing has been output, nothing to make safe
  CHECK(manager.safe_passes() == 0);
  manager.step();
  manager.step();
  auto& world = *static_cast<test::Feed*>(manager.program().layers[1].interface.get());
  CHECK(world.seen == std::vector<double>{5.0, 5.0});
  manager.safe_pass();  // as when the live page pauses the run
  CHECK(world.seen == std::vector<double>{5.0, 5.0, -1.0});
  CHECK(manager.steps() == 2);
  CHECK(actuator(manager, "speed") == -1.0);
  CHECK(written(manager, "speed"));
  CHECK_FALSE(written(manager, "heading"));  // no safe value: kept, unwritten
  manager.step();                            // resumes: the behaviours write again
  CHECK(world.seen == std::vector<double>{5.0, 5.0, -1.0, 5.0});
  CHECK(manager.steps() == 3);
  const auto records = trace.records();
  REQUIRE(records.size() == 5);  // header, two steps, the safe pass, a step
  CHECK(records[3]["step"] == 2);
  CHECK(records[3]["safe"] == true);
  CHECK(records[3]["actuators"]["speed"]["value"] == -1.0);
  CHECK(records[3]["actuators"]["speed"]["written"] == true);
  CHECK(records[3]["actuators"]["heading"]["written"] == false);
  CHECK_FALSE(records[2].contains("safe"));
  CHECK(records[4]["step"] == 3);
  CHECK_FALSE(records[4].contains("safe"));
}

TEST_CASE("a manager stopped by on_exception: stop outputs its safe values when finished",
          "[robustness][safe]") {
  Log log;
  auto manager = make(safe_config("stop"), log);
  JsonTrace trace(manager);
  for (int step = 0; step < 10 && !manager.stopped(); ++step) manager.step();
  REQUIRE(manager.stopped());
  manager.finish();
  auto& world = *static_cast<test::Feed*>(manager.program().layers[1].interface.get());
  CHECK(world.seen == std::vector<double>{5.0, 5.0, 5.0, -1.0});
  CHECK(manager.safe_passes() == 1);
  const auto records = trace.records();
  REQUIRE(records.size() == 5);
  CHECK(records.back()["safe"] == true);
  CHECK(records.back()["step"] == 3);
}

TEST_CASE("a config without safe values has no safe pass", "[robustness][safe]") {
  Log log;
  std::string text = safe_config("inactive");
  text.replace(text.find(", safe: -1"), 10, "");
  auto manager = make(text, log);
  JsonTrace trace(manager);
  manager.step();
  manager.finish();
  CHECK(manager.safe_passes() == 0);
  CHECK(trace.records().size() == 2);
}

TEST_CASE("a safe value must fit its actuator's type", "[robustness][safe][config]") {
  const auto diagnostics = test::diagnose_text(R"(arbiter: 1
name: t
layers:
  - name: control
    actuators:
      gait: {type: vec3, safe: [0, 0]}
)",
                                               fault_registry());
  CHECK_THAT(format(diagnostics),
             Catch::Matchers::Contains(
                 "inline.yaml:6:32: error: safe value of actuator 'gait' must be a list of 3 "
                 "finite numbers (vec3), found a list of 2 items"));
}

TEST_CASE("a manager with a clock times every step and the safe pass in its records",
          "[robustness][safe][timing]") {
  Log log;
  auto manager = make(safe_config("inactive"), log);
  ManualClock clock;
  manager.set_clock(&clock);
  JsonTrace trace(manager);
  manager.step();
  manager.step();
  manager.finish();
  const auto records = trace.records();
  REQUIRE(records.size() == 4);
  // Each step reads the clock at its start and its end: 0.25 s per reading.
  CHECK(records[1]["t"] == 0.0);
  CHECK(records[1]["duration"] == 0.25);
  CHECK(records[2]["t"] == 0.5);
  CHECK(records[2]["duration"] == 0.25);
  CHECK(records[3]["t"] == 1.0);
  CHECK(records[3]["safe"] == true);
}
