// The soccer plugin's classes as a config meets them: their params and ports, and the checks of
// the world's params.

#include <catch2/catch.hpp>
#include <string>

#include "soccer_support.hpp"
#include "test_support.hpp"

using arbiter::Manager;
using arbiter::Registry;
using namespace arbiter::soccer::test;

TEST_CASE("the soccer classes declare described params and ports", "[soccer][classes]") {
  const Registry registry = soccer_registry();
  for (const char* name : {"soccer.WorldLink", "soccer.SearchForBall", "soccer.GoBehindBall",
                           "soccer.KickBall", "soccer.HeadControl"}) {
    INFO(name);
    const auto* info = registry.find_any_class(name);
    REQUIRE(info != nullptr);
    CHECK(info->origin == "soccer");
    CHECK_FALSE(info->description.empty());
    for (const auto& param : info->params) {
      INFO(param.name);
      CHECK_FALSE(param.description.empty());
      CHECK_FALSE(param.required());
    }
    for (const auto& port : info->ports) {
      INFO(port.name);
      CHECK_FALSE(port.description.empty());
    }
  }
}

TEST_CASE("world params outside the field are reported at the param", "[soccer][classes]") {
  const Registry registry = soccer_registry();
  const auto diagnostics = arbiter::test::diagnose_text(
      demo_config_with({-3.0, 0.0, 0.0}, {5.0, 0.0}, 1), registry, "world.yaml");
  REQUIRE(diagnostics.has_errors());
  CHECK_THAT(arbiter::format(diagnostics), Catch::Contains("ball_start [5, 0] is off the field"));
}

TEST_CASE("the world's dt is the step period unless given", "[soccer][classes]") {
  const Registry registry = soccer_registry();
  const std::string config =
      "arbiter: 1\nname: t\nrate_hz: 10\nlayers:\n"
      "  - name: world\n    interface: soccer.WorldLink\n    params: {PARAMS}\n"
      "    actuators: {ball_visible: {type: bool}, ball_position: {type: vec2}}\n"
      "    sensors: [gait_velocity]\n"
      "  - name: control\n    actuators: {gait_velocity: {type: vec3}}\n";
  const auto dt_of = [&](const std::string& params) {
    Manager manager(arbiter::test::compile_text(edited(config, "PARAMS", params), registry));
    return world_link(manager).world()->config().dt;
  };
  CHECK(dt_of("") == 0.1);
  CHECK(dt_of("dt: 0.05") == 0.05);
}

TEST_CASE("the goalie classes declare described params and ports", "[soccer][classes]") {
  const Registry registry = soccer_registry();
  for (const char* name : {"soccer.WaitForButton", "soccer.WalkToPose", "soccer.MonitorBall",
                           "soccer.Dive", "soccer.Goalie"}) {
    INFO(name);
    const auto* info = registry.find_any_class(name);
    REQUIRE(info != nullptr);
    CHECK(info->origin == "soccer");
    CHECK_FALSE(info->description.empty());
    CHECK_FALSE(info->ports.empty());
    for (const auto& param : info->params) {
      INFO(param.name);
      CHECK_FALSE(param.description.empty());
    }
    for (const auto& port : info->ports) {
      INFO(port.name);
      CHECK_FALSE(port.description.empty());
    }
  }
  std::vector<std::string> required;
  for (const char* name : {"soccer.WalkToPose", "soccer.Goalie"}) {
    for (const auto& param : registry.find_any_class(name)->params) {
      if (param.required()) required.push_back(param.name);
    }
  }
  CHECK(required == std::vector<std::string>{"x", "y", "theta", "machine"});
}
