// Behaviour code that asks for a non-finite activation level or writes non-finite values
// (docs/robustness.md): the manager counts the level as 0 or 1 and ignores the write, reported
// once, and the trace stays valid JSON.

#include <catch2/catch.hpp>
#include <string>

#include "fault_support.hpp"

using namespace arbiter;
using namespace arbiter::test;

TEST_CASE("non-finite activation levels count as 0 or 1 and are reported once",
          "[robustness][levels]") {
  Log log;
  auto manager = make(test::one_layer(R"(
    behaviours:
      nan: {type: robust.Odd, params: {level: nan}}
      high: {type: robust.Odd, params: {level: inf}}
      low: {type: robust.Odd, params: {level: -inf}}
      fine: {type: test.Probe, params: {levels: 0.5}}
)"),
                      log);
  for (int step = 0; step < 4; ++step) manager.step();
  CHECK(test::activation_of(manager, "l", "nan") == 0.0);
  CHECK(test::activation_of(manager, "l", "high") == 1.0);
  CHECK(test::activation_of(manager, "l", "low") == 0.0);
  CHECK(test::activation_of(manager, "l", "fine") == 0.5);
  INFO(log.text());
  CHECK(log.lines() == 3);
  CHECK(log.count("inline.yaml:6:7: behaviour 'nan' requested a NaN activation level; it counts "
                  "as 0") == 1);
  CHECK(log.count("behaviour 'high' requested an infinite activation level; it counts as 1") == 1);
  CHECK(log.count("behaviour 'low' requested a negative infinite activation level; it counts as "
                  "0") == 1);
}

TEST_CASE("non-finite values written to actuators are ignored and reported once",
          "[robustness][actuators]") {
  for (const std::string value : {"nan", "inf", "-inf"}) {
    DYNAMIC_SECTION(value) {
      Log log;
      auto manager = make(test::one_layer(R"(
    actuators:
      speed: {type: double, default: 2}
      mean: {type: double, aggregate: true}
      walk: {type: vec2}
      turn: {type: vec3, aggregate: true}
    behaviours:
      odd: {type: robust.Odd, params: {value: )" +
                                          value + R"(, from: 2},
            ports: {out: speed, out2: walk, out3: turn}}
      odd_too: {type: robust.Odd, params: {value: )" +
                                          value + R"(}, ports: {out: mean}}
      fine: {type: test.Probe, params: {value: 4}, ports: {out: mean}}
)"),
                          log);
      JsonTrace trace(manager);
      for (int step = 0; step < 3; ++step) manager.step();
      CHECK(actuator(manager, "speed") == 2.0);  // its default: never written
      CHECK_FALSE(written(manager, "speed"));
      CHECK(actuator(manager, "mean") == 4.0);  // fine's alone, not a NaN mean
      CHECK(written(manager, "mean"));
      CHECK(manager.actuator<Vec2>(*manager.program().find_actuator("walk")) == Vec2{});
      CHECK(manager.actuator<Vec3>(*manager.program().find_actuator("turn")) == Vec3{});
      CHECK(trace.records().size() == 4);  // every record parses: no NaN in the trace
      INFO(log.text());
      CHECK(log.lines() == 4);  // one per writer and actuator
      CHECK(log.count("inline.yaml:11:7: behaviour 'odd' (robust.Odd) wrote a non-finite value "
                      "(NaN or infinity) to actuator 'speed' in step 2; such writes are ignored") ==
            1);
      CHECK(log.count("to actuator 'walk' in step 2") == 1);
      CHECK(log.count("to actuator 'turn' in step 2") == 1);
      CHECK(log.count("behaviour 'odd_too' (robust.Odd) wrote a non-finite value (NaN or "
                      "infinity) to actuator 'mean' in step 1") == 1);
    }
  }
}
