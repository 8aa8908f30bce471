// InitContext's view of an interface layer's own actuators and sensors (layer_actuators(),
// layer_sensors(), sensor_input()): what a class that bridges whatever its layer names, rather
// than ports it declares, relies on.

#include <catch2/catch.hpp>

#include "test_support.hpp"

using namespace arbiter;

namespace {

/// Lists its layer's items in init() and binds the sensor named by `read` as the C++ type named
/// by `as` ("double" or "bool"); the output pass copies a double sensor to `seen`.
class Lister : public Interface {
 public:
  void init(InitContext& ctx) override {
    actuators = ctx.layer_actuators();
    sensors = ctx.layer_sensors();
    if (read.empty()) return;
    if (as == "bool") {
      bound = ctx.sensor_input<bool>(read, ctx.param_location(&Lister::read)).bound();
    } else {
      input = ctx.sensor_input<double>(read, ctx.param_location(&Lister::read));
      bound = input.bound();
    }
  }
  void output(const StepContext& ctx) override {
    if (input.bound()) seen = ctx.read(input);
  }
  std::string read;
  std::string as;
  std::vector<LayerItem> actuators;
  std::vector<LayerItem> sensors;
  Input<double> input;
  bool bound = false;
  double seen = -1.0;
};

Registry make_registry() {
  Registry registry = test::make_test_registry();
  auto& lister = registry.add_interface<Lister>("test.Lister");
  lister.param("read", &Lister::read).defaults_to(std::string());
  lister.param("as", &Lister::as).defaults_to(std::string("double"));
  return registry;
}

std::string config(const std::string& params) {
  return R"(arbiter: 1
name: items
layers:
  - name: bridge
    interface: test.Lister
    params: )" +
         params + R"(
    sensors: [speed, kick]
    actuators:
      distance: {type: double}
      seen: {type: bool}
  - name: control
    actuators:
      speed: {type: double, aggregate: true}
      kick: {type: bool}
    behaviours:
      walk: {type: test.Probe, params: {levels: 1, value: 0.75}, ports: {out: speed}}
)";
}

Lister& lister_of(const Program& program) {
  return dynamic_cast<Lister&>(*program.layers.front().interface);
}

}  // namespace

TEST_CASE("an interface lists its layer's actuators and sensors with types and locations",
          "[plugins][interface]") {
  const Registry registry = make_registry();
  const Program program = test::compile_text(config("{read: speed}"), registry);
  const Lister& lister = lister_of(program);
  REQUIRE(lister.actuators.size() == 2);
  CHECK(lister.actuators[0].name == "distance");
  CHECK(lister.actuators[0].type->name == "double");
  CHECK(lister.actuators[1].name == "seen");
  CHECK(lister.actuators[1].type->name == "bool");
  REQUIRE(lister.sensors.size() == 2);
  CHECK(lister.sensors[0].name == "speed");
  CHECK(lister.sensors[0].type->name == "double");
  CHECK(lister.sensors[1].name == "kick");
  CHECK(lister.sensors[1].type->name == "bool");
  CHECK(lister.sensors[1].location.line == 7);
  CHECK(lister.sensors[1].location.column == 22);
  CHECK(lister.bound);
}

TEST_CASE("a sensor bound by name reads what the layer above wrote", "[plugins][interface]") {
  const Registry registry = make_registry();
  Manager manager(test::compile_text(config("{read: speed}"), registry));
  manager.step();
  CHECK(lister_of(manager.program()).seen == Approx(0.75));
}

TEST_CASE("a sensor named wrongly, or read as the wrong type, is a located error",
          "[plugins][interface]") {
  const Registry registry = make_registry();
  SECTION("a sensor the layer does not read") {
    const auto text = format(test::diagnose_text(config("{read: sped}"), registry));
    CHECK_THAT(text, Catch::Contains("inline.yaml:6:20: error:"));
    CHECK_THAT(text, Catch::Contains("'sped' is not a sensor of layer 'bridge'"));
    CHECK_THAT(text, Catch::Contains("did you mean 'speed'?"));
  }
  SECTION("a sensor of another type") {
    const auto text = format(test::diagnose_text(config("{read: speed, as: bool}"), registry));
    CHECK_THAT(text, Catch::Contains("inline.yaml:6:20: error:"));
    CHECK_THAT(text, Catch::Contains("reads sensor 'speed' (double) as a different C++ type"));
  }
}
