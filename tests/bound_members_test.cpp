// Params and ports bound to members at registration (ClassBinder<T>::param / port with a member
// pointer): the engine fills the members before init(), registration rejects a name or member
// that comes twice (a member of a class T does not derive from does not compile), and a config's
// mistakes are reported at their location.

#include <catch2/catch.hpp>

#include "arbiter/init_context.hpp"
#include "arbiter/manager.hpp"
#include "arbiter/state.hpp"
#include "test_support.hpp"

using namespace arbiter;

namespace {

/// A base whose members a derived class binds, as a mixin's ports are bound.
struct Offset {
  double offset = 0.0;
};

/// Writes gain * in + offset to `out`; remembers what its members held when init() ran.
class Gain final : public Behaviour, public Offset {
 public:
  void init(BehaviourInitContext& ctx) override {
    gain_in_init = gain;
    out_bound_in_init = out.bound();
    target_at = ctx.param_location(&Gain::target);
  }
  double activation(const StepContext&) override { return 1.0; }
  void execute(ExecuteContext& ctx) override { ctx.write(out, gain * ctx.read(in) + offset); }

  double gain = 0.0;
  Vec2 target;
  Input<double> in;
  Output<double> out;
  double gain_in_init = -1.0;
  bool out_bound_in_init = false;
  SourceLocation target_at;
};

/// Holds for its `steps` param, as each planned instance sets it.
class Wait final : public State {
 public:
  void activate(StateContext& ctx) override { left_ = ctx.param(steps); }
  StateResult execute(StateContext&) override {
    return --left_ > 0 ? StateResult::kHold : StateResult::kProceed;
  }
  StateParam<std::int64_t> steps;

 private:
  std::int64_t left_ = 0;
};

/// Binds a per-instance param to a plain member, which would hold one value for every instance.
class Misbound final : public State {
 public:
  StateResult execute(StateContext&) override { return StateResult::kProceed; }
  std::int64_t steps = 0;
};

class Other final : public Behaviour {
 public:
  double activation(const StepContext&) override { return 0.0; }
  double level = 0.0;
  StateParam<double> handle;
};

/// Derives from Offset privately: its binder may not reach Offset's members.
class Hidden final : public Behaviour, private Offset {
 public:
  double activation(const StepContext&) override { return 0.0; }
};

// What ClassBinder<T>::param and port require of a member, so that a member of another class, of
// a private base, or a handle in a class that is no state, does not compile.
static_assert(detail::kMemberOf<Gain, Gain> && detail::kMemberOf<Gain, Offset>);
static_assert(!detail::kMemberOf<Gain, Other> && !detail::kMemberOf<Hidden, Offset>);
static_assert(detail::kParamMember<Wait, StateParam<std::int64_t>>);
static_assert(detail::kParamMember<Other, double>);
static_assert(!detail::kParamMember<Other, StateParam<double>>);

Registry make_registry() {
  Registry registry = test::make_test_registry();
  auto& gain = registry.add_behaviour<Gain>("test.Gain");
  gain.param("gain", &Gain::gain).defaults_to(1.5).range(0.0, 10.0);
  gain.param("target", &Gain::target).defaults_to(Vec2{0.0, 0.0});
  gain.param("offset", &Gain::offset).defaults_to(0.0);
  gain.port("in", &Gain::in).make_optional();
  gain.port("out", &Gain::out);
  add_state_class<Wait>(registry, "test.Wait").param("steps", &Wait::steps).defaults_to(2);
  add_state_class<Misbound>(registry, "test.Misbound")
      .param("steps", &Misbound::steps)
      .defaults_to(2);
  return registry;
}

std::string config(const std::string& params) {
  return "arbiter: 1\nname: t\nlayers:\n  - name: control\n    actuators:\n"
         "      in: {type: double}\n      out: {type: double}\n    behaviours:\n"
         "      g: {type: test.Gain, params: " +
         params + "}\n";
}

}  // namespace

TEST_CASE("params and ports bound to members hold their values before init() and in steps",
          "[plugins][bound]") {
  const Registry registry = make_registry();
  Manager manager(test::compile_text(config("{gain: 2, offset: 0.25, target: [1, 2]}"), registry));
  const auto& gain = test::instance<Gain>(manager.program(), "control", "g");
  CHECK(gain.gain_in_init == 2.0);
  CHECK(gain.out_bound_in_init);
  CHECK(gain.offset == 0.25);  // bound through the public base Offset
  CHECK(gain.target.x == 1.0);
  CHECK(gain.target.y == 2.0);
  CHECK(gain.target_at.line == 9);
  CHECK(gain.target_at.column == 68);
  manager.step();
  CHECK(manager.actuator<double>(*manager.program().find_actuator("out")) == 0.25);
}

TEST_CASE("a bound param left out of the config holds its default", "[plugins][bound]") {
  const Registry registry = make_registry();
  const Program program = test::compile_text(config("{}"), registry);
  const auto& gain = test::instance<Gain>(program, "control", "g");
  CHECK(gain.gain == 1.5);
  CHECK(gain.gain_in_init == 1.5);
  // No param was written: the behaviour's own location stands for the default.
  CHECK(gain.target_at.line == 9);
  CHECK(gain.target_at.column == 7);
}

TEST_CASE("a bound param outside its range fails the load at the value", "[plugins][bound]") {
  const Diagnostics diagnostics = test::diagnose_text(config("{gain: 11}"), make_registry());
  REQUIRE(diagnostics.items().size() == 1);
  CHECK(diagnostics.items()[0].location.line == 9);
  CHECK(diagnostics.items()[0].location.column == 43);
  CHECK_THAT(diagnostics.items()[0].message, Catch::Contains("gain"));
}

TEST_CASE("a misspelt param name in a config fails the load at the name", "[plugins][bound]") {
  const Diagnostics diagnostics = test::diagnose_text(config("{gian: 2}"), make_registry());
  REQUIRE(diagnostics.items().size() == 1);
  const Diagnostic& error = diagnostics.items()[0];
  CHECK(error.code == "unknown-param");
  CHECK(error.location.file == "inline.yaml");
  CHECK(error.location.line == 9);
  CHECK(error.location.column == 37);
  CHECK(error.message == "unknown param 'gian' for behaviour 'g' (test.Gain)");
  CHECK_THAT(error.notes.at(0).text, Catch::Contains("'gain'"));
}

TEST_CASE("a state's param bound to a StateParam handle reads each planned instance's value",
          "[plugins][bound][scl]") {
  const Registry registry = make_registry();
  const std::string text =
      "arbiter: 1\nname: t\nstate_machines:\n  m:\n    states:\n"
      "      a: {type: test.Wait, params: {steps: 3}}\n      b: test.Wait\n    queue: [a, b]\n";
  Manager manager(test::compile_text(text, registry));
  test::ControllerLog log("m");
  manager.add_observer(log);
  for (int i = 0; i < 5; ++i) manager.step();
  CHECK(log.lines == std::vector<std::string>{"cycle 1: activate a, execute a",
                                              "cycle 2: execute a", "cycle 3: execute a",
                                              "cycle 4: deactivate a, activate b, execute b",
                                              "cycle 5: execute b"});
}

TEST_CASE("a state's per-instance param bound to a plain member fails the load at the state",
          "[plugins][bound][scl]") {
  const std::string text =
      "arbiter: 1\nname: t\nstate_machines:\n  m:\n    states:\n"
      "      a: test.Misbound\n    queue: [a]\n";
  const Diagnostics diagnostics = test::diagnose_text(text, make_registry());
  REQUIRE(diagnostics.items().size() == 1);
  CHECK(diagnostics.items()[0].code == "class-error");
  CHECK(diagnostics.items()[0].location.line == 6);
  CHECK(diagnostics.items()[0].message ==
        "class test.Misbound binds param 'steps' to a plain member, but the param may be set per "
        "planned instance: bind a StateParam, or declare it state_level()");
}

TEST_CASE("registration rejects a param or port name, or a member, bound twice",
          "[plugins][bound]") {
  Registry registry;
  auto& gain = registry.add_behaviour<Gain>("test.Gain");
  gain.param("gain", &Gain::gain);
  gain.port("out", &Gain::out);
  CHECK_THROWS_WITH(gain.param("gain", &Gain::offset),
                    "class 'test.Gain' declares param 'gain' twice");
  CHECK_THROWS_WITH(gain.param("factor", &Gain::gain),
                    "class 'test.Gain' binds param 'factor' to the member that param 'gain' is "
                    "already bound to");
  CHECK_THROWS_WITH(gain.port("out", &Gain::in), "class 'test.Gain' declares port 'out' twice");
  CHECK_THROWS_WITH(gain.port("result", &Gain::out),
                    "class 'test.Gain' binds port 'result' to the member that port 'out' is "
                    "already bound to");
  // Nothing of the rejected declarations was kept.
  CHECK(gain.params.size() == 1);
  CHECK(gain.ports.size() == 1);
}
