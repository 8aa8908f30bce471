// dds.Hold: a value written in one step is written on every step until the timeout.

#include <catch2/catch.hpp>

#include "dds_support.hpp"

using namespace arbiter;
using namespace arbiter::dds_test;

TEST_CASE("a held value is written every step from its arrival until the timeout", "[dds]") {
  TempDir dir;
  Registry registry = make_registry();
  // `command` is written in steps 1 and 8; the hold lasts 0.05 s, 5 steps at 100 Hz.
  Manager manager(load_file(dir.write("hold.yaml", R"(
arbiter: 1
name: hold
rate_hz: 100
layers:
  - name: upper
    actuators: {command: vec3}
    behaviours:
      sender:
        type: scripted
        params: {activation: [1, 0, 0, 0, 0, 0, 0, 1, 0], writes: {command: [1, 2, 3]}}
  - name: lower
    sensors: [command]
    actuators: {held: vec3}
    behaviours:
      hold: {type: dds.HoldVec3, params: {timeout: 0.05}, ports: {from: command, to: held}}
)"),
                            registry));
  std::string written_steps;
  for (int step = 1; step <= 15; ++step) {
    manager.step();
    written_steps += written(manager, "held") ? 'w' : '.';
  }
  CHECK(written_steps == "wwwww..wwwww...");
  CHECK(value_of(manager, "held") == nlohmann::json::parse("[1.0, 2.0, 3.0]"));
}
