// State controllers (docs/semantics.md, "State machines"), checked as exact event sequences per
// step.

#include <catch2/catch.hpp>

#include "arbiter/trace.hpp"
#include "test_support.hpp"

using namespace arbiter;
using Lines = std::vector<std::string>;

namespace {

const Registry& registry() {
  static const Registry instance = test::make_test_registry();
  return instance;
}

struct Run {
  Manager manager;
  test::ControllerLog log;
};

/// Runs `steps` steps and returns the named controller's events, one line per step.
Lines events(const std::string& yaml, const std::string& controller, int steps) {
  Manager manager(test::compile_text(yaml, registry()));
  test::ControllerLog log(controller);
  manager.add_observer(log);
  for (int i = 0; i < steps; ++i) manager.step();
  return log.lines;
}

std::string machine(const std::string& states, const std::string& queue,
                    const std::string& extra = "") {
  return "arbiter: 1\nname: t\nstate_machines:\n  m:\n    states:\n" + states +
         "    queue: " + queue + "\n" + extra;
}

const std::string kThreeScripted = "      a: scripted\n      b: scripted\n      c: scripted\n";

}  // namespace

TEST_CASE("a plan of three states runs one after the other and finishes", "[scl]") {
  CHECK(events(machine(kThreeScripted, "[a, b, c]"), "m", 5) ==
        Lines{"cycle 1: activate a, execute a", "cycle 2: deactivate a, activate b, execute b",
              "cycle 3: deactivate b, activate c, execute c",
              "cycle 4: deactivate c [finished]",  // proceed on an empty queue finishes
              "cycle 4: [finished]"});
}

TEST_CASE("a state holds for N executions before proceeding", "[scl]") {
  CHECK(events(
            machine("      a: {type: scripted, params: {hold: 3}}\n      b: scripted\n", "[a, b]"),
            "m", 4) == Lines{"cycle 1: activate a, execute a", "cycle 2: execute a",
                             "cycle 3: execute a", "cycle 4: deactivate a, activate b, execute b"});
}

TEST_CASE("an empty initial queue finishes the controller at once", "[scl]") {
  CHECK(events(machine(kThreeScripted, "[]"), "m", 2) ==
        Lines{"cycle 1: [finished]", "cycle 1: [finished]"});
}

TEST_CASE("terminate() takes effect in the same step", "[scl]") {
  SECTION("from activate: the state is not executed") {
    CHECK(events(machine("      a: {type: test.Planner, params: {op: terminate_in_activate}}\n"
                         "      b: scripted\n",
                         "[a, b]"),
                 "m", 2) ==
          Lines{"cycle 1: activate a, deactivate a [finished]", "cycle 1: [finished]"});
  }
  SECTION("from execute") {
    CHECK(events(machine("      a: scripted\n"
                         "      b: {type: test.Planner, params: {op: terminate_in_execute}}\n"
                         "      c: scripted\n",
                         "[a, b, c]"),
                 "m", 3) == Lines{"cycle 1: activate a, execute a",
                                  "cycle 2: deactivate a, activate b, execute b, deactivate b "
                                  "[finished]",
                                  "cycle 2: [finished]"});
  }
  SECTION("scripted: terminate: true") {
    CHECK(events(machine("      a: {type: scripted, params: {terminate: true}}\n"
                         "      b: scripted\n",
                         "[a, b]"),
                 "m", 1) == Lines{"cycle 1: activate a, execute a, deactivate a [finished]"});
  }
}

TEST_CASE("pre-emption from pre-step leaves the current state at once", "[scl]") {
  SECTION("scripted in the config") {
    CHECK(events(machine("      wait: {type: scripted, params: {hold: 100}}\n"
                         "      walk: {type: scripted, params: {hold: 100}}\n",
                         "[wait, walk]", "    preempt:\n      - {cycle: 3, go_to: walk}\n"),
                 "m", 3) == Lines{"cycle 1: activate wait, execute wait", "cycle 2: execute wait",
                                  "cycle 3: deactivate wait, activate walk, execute walk"});
  }
  SECTION("by a hook") {
    struct ButtonPress : ControllerHooks {
      PlannedState target;
      bool pre_step(Controller& controller, Plan& plan) override {
        if (controller.cycle() != 3) return false;
        // Kept by the hooks: the planned instance refers to it.
        target = test::planned(controller, "wait");
        plan.go_to(target);
        return true;
      }
    } hooks;
    Manager manager(test::compile_text(
        machine("      wait: scripted\n      walk: {type: scripted, params: {hold: 100}}\n",
                "[wait, walk]"),
        registry()));
    manager.program().find_controller("m")->set_hooks(&hooks);
    test::ControllerLog log("m");
    manager.add_observer(log);
    for (int i = 0; i < 3; ++i) manager.step();
    CHECK(log.lines == Lines{"cycle 1: activate wait, execute wait",
                             "cycle 2: deactivate wait, activate walk, execute walk",
                             "cycle 3: deactivate walk, activate wait, execute wait"});
  }
}

TEST_CASE("go_to replaces the queue with one state", "[scl]") {
  CHECK(events(machine("      a: {type: test.Planner, params: {op: go_to, target: c}}\n"
                       "      b: scripted\n      c: scripted\n",
                       "[a, b, b]"),
               "m", 3) == Lines{"cycle 1: activate a, execute a",
                                "cycle 2: deactivate a, activate c, execute c",
                                "cycle 3: deactivate c [finished]"});
}

TEST_CASE("prepend plans ahead of a remembered tail", "[scl]") {
  // The goalie's obstacle: detours go in front while monitor stays queued.
  CHECK(
      events(machine(
                 "      avoid: {type: scripted, params: {prepend: [detour, {detour: {hold: 2}}]}}\n"
                 "      detour: scripted\n      monitor: scripted\n",
                 "[avoid, monitor]"),
             "m", 5) == Lines{"cycle 1: activate avoid, execute avoid",
                              "cycle 2: deactivate avoid, activate detour, execute detour",
                              "cycle 3: deactivate detour, activate detour, execute detour",
                              "cycle 4: execute detour",
                              "cycle 5: deactivate detour, activate monitor, execute monitor"});
}

TEST_CASE("queue edits: insert, remove, clear, append with run-time params", "[scl]") {
  test::Pose::seen_x().clear();
  SECTION("insert_before and insert_after") {
    CHECK(events(machine("      a: {type: test.Planner, params: {op: insert_before, target: p, "
                         "x: 2}}\n      p: test.Pose\n      b: scripted\n",
                         "[a, b, b]"),
                 "m", 4) == Lines{"cycle 1: activate a, execute a",
                                  "cycle 2: deactivate a, activate b, execute b",
                                  "cycle 3: deactivate b, activate p, execute p",
                                  "cycle 4: deactivate p, activate b, execute b"});
    CHECK(test::Pose::seen_x() == std::vector<double>{2.0});
  }
  SECTION("remove and clear") {
    CHECK(events(machine("      a: {type: test.Planner, params: {op: remove, target: '0'}}\n"
                         "      b: scripted\n      c: scripted\n",
                         "[a, b, c]"),
                 "m", 2)[1] == "cycle 2: deactivate a, activate c, execute c");
    CHECK(events(machine("      a: {type: test.Planner, params: {op: clear}}\n"
                         "      b: scripted\n",
                         "[a, b, b]"),
                 "m", 2)[1] == "cycle 2: deactivate a [finished]");
  }
  SECTION("per-instance params from the config's queue") {
    events(machine("      p: test.Pose\n", "[{p: {x: 1.5}}, {p: {x: -3}}]"), "m", 3);
    CHECK(test::Pose::seen_x() == std::vector<double>{1.5, -3.0});
  }
}

TEST_CASE("a state steps its child controller", "[scl][hierarchy]") {
  const std::string config = R"(
arbiter: 1
name: t
state_machines:
  parent:
    states:
      delegate: {type: scripted, machine: child}
      after: scripted
    queue: [delegate, after]
  child:
    states:
      x: scripted
      y: scripted
    queue: [x, y]
)";
  Manager manager(test::compile_text(config, registry()));
  test::ControllerLog parent("parent");
  test::ControllerLog child("child");
  manager.add_observer(parent);
  manager.add_observer(child);
  for (int i = 0; i < 4; ++i) manager.step();
  CHECK(parent.lines == Lines{"cycle 1: activate delegate, execute delegate",
                              "cycle 2: execute delegate", "cycle 3: execute delegate",
                              "cycle 4: deactivate delegate, activate after, execute after"});
  CHECK(child.lines == Lines{"cycle 1: activate x, execute x",
                             "cycle 2: deactivate x, activate y, execute y",
                             "cycle 3: deactivate y [finished]", "cycle 3: [finished]"});
}

TEST_CASE("a state machine inside a behaviour pauses while the behaviour is inhibited",
          "[scl][hierarchy]") {
  const std::string config = R"(
arbiter: 1
name: t
layers:
  - name: l
    behaviours:
      interrupt: {type: scripted, params: {activation: [0, 1, 1, 0]}}
      goalie: {type: state_machine, params: {machine: plan, restart: RESTART}}
    inhibitions: [interrupt -> goalie]
state_machines:
  plan:
    states: {a: {type: scripted, params: {hold: 2}}, b: scripted}
    queue: [a, b]
)";
  auto run = [&](const std::string& restart) {
    std::string text = config;
    text.replace(text.find("RESTART"), 7, restart);
    return events(text, "plan", 6);
  };
  CHECK(run("false") ==
        Lines{"cycle 1: activate a, execute a", "cycle 1:", "cycle 1:", "cycle 2: execute a",
              "cycle 3: deactivate a, activate b, execute b", "cycle 4: deactivate b [finished]"});
  CHECK(run("true") == Lines{"cycle 1: activate a, execute a",
                             "cycle 1:", "cycle 1:", "cycle 1: deactivate a, activate a, execute a",
                             "cycle 2: execute a", "cycle 3: deactivate a, activate b, execute b"});

  SECTION("the behaviour requests 0 once its controller has finished") {
    Manager manager(test::compile_text(
        std::string(config).replace(config.find("RESTART"), 7, "false"), registry()));
    for (int i = 0; i < 7; ++i) manager.step();
    CHECK(test::activation_of(manager, "l", "goalie") == 0.0);
  }
}

TEST_CASE("the trace lists every controller in every step", "[scl][trace]") {
  Manager manager(test::compile_text(
      machine("      a: {type: scripted, params: {hold: 2}}\n      b: scripted\n", "[a, b]"),
      registry()));
  std::string record;
  manager.step();
  append_step_record(manager, record);
  CHECK_THAT(record, Catch::Matchers::Contains(
                         R"("controllers": {"m": {"cycle": 1, "state": "a", "queue": ["b"], )"
                         R"("events": ["activate a", "execute a"], "status": "running"}})"));
}

TEST_CASE("misuse is an error naming the controller and the state", "[scl][errors]") {
  SECTION("exceeding the queue capacity") {
    Manager manager(test::compile_text(
        machine("      a: {type: scripted, params: {append: [b, b, b, b]}}\n      b: scripted\n",
                "[a]", "    capacity: 3\n"),
        registry()));
    manager.step();
    const Controller& m = *manager.program().find_controller("m");
    CHECK(m.status() == ControllerStatus::kError);
    CHECK_THAT(m.error(), Catch::Matchers::Contains("controller 'm'") &&
                              Catch::Matchers::Contains("state 'a'") &&
                              Catch::Matchers::Contains("capacity of 3"));
  }
  SECTION("planning a state whose param 'x' is required") {
    Manager manager(test::compile_text(
        machine("      a: {type: test.Planner, params: {op: clear}}\n      p: test.Pose\n", "[a]",
                "    preempt: []\n"),
        registry()));
    manager.step();
    Controller& m = *manager.program().find_controller("m");
    Plan plan(m);
    PlannedState p = test::planned(m, "p");
    SECTION("a run-time plan without the param") {
      CHECK_FALSE(plan.append(p));
      CHECK_THAT(m.error(), Catch::Matchers::Contains("required param 'x'"));
    }
    SECTION("a planned state built by hand, its params not resolved at load") {
      p.params.push_back(Param{"x", ParamValue(1.0), SourceLocation{}, false});
      CHECK_FALSE(plan.append(p));
      CHECK_THAT(m.error(), Catch::Matchers::Contains("state 'p'") &&
                                Catch::Matchers::Contains("not resolved at load"));
    }
  }
  SECTION("stepping a controller from its own callback") {
    struct Reenter : ControllerHooks {
      const StepContext* context = nullptr;
      void pre_execute(Controller& controller, std::string_view) override {
        controller.step(*context);
      }
    } hooks;
    Manager manager(test::compile_text(machine(kThreeScripted, "[a]"), registry()));
    Controller& m = *manager.program().find_controller("m");
    detail::StepData data;
    const StepContext context(data, kUnbound);
    hooks.context = &context;
    m.set_hooks(&hooks);
    manager.step();
    CHECK(m.status() == ControllerStatus::kError);
    CHECK_THAT(m.error(), Catch::Matchers::Contains("from inside its own callback"));
  }
  SECTION("a state that throws stops its controller, not the manager") {
    Manager manager(test::compile_text(
        machine("      a: {type: test.Planner, params: {op: throw}}\n", "[a]"), registry()));
    manager.step();
    manager.step();
    const Controller& m = *manager.program().find_controller("m");
    CHECK(m.status() == ControllerStatus::kError);
    CHECK_THAT(m.error(), Catch::Matchers::Contains("state failure"));
  }
}

TEST_CASE("names written in the config are checked at load", "[scl][errors]") {
  const auto diagnostics = test::diagnose_text(
      machine("      a: {type: scripted, params: {append: [walk, {b: {hold: 0}}, p]}}\n"
              "      b: scripted\n      p: test.Pose\n",
              "[a, {p: {x: 1}}]"),
      registry());
  std::string text = format(diagnostics);
  CHECK_THAT(text, Catch::Matchers::Contains("has no state 'walk'"));
  CHECK_THAT(text, Catch::Matchers::Contains("param 'hold'"));
  CHECK_THAT(text, Catch::Matchers::Contains("required param 'x'"));
}

namespace {

/// Resolves one handle wrongly in init(), as `mistake` says.
class Mistaken final : public State {
 public:
  void init(StateInitContext& ctx) override {
    const auto mistake = ctx.param(mistake_);
    if (mistake == "state") ctx.plan_state<double>("pp", {"x"});
    if (mistake == "slot name") ctx.plan_state<double>("p", {"y"});
    if (mistake == "slot kind") ctx.plan_state<std::int64_t>("p", {"x"});
    if (mistake == "slot twice") ctx.plan_state<double, double>("p", {"x", "x"});
    if (mistake == "required") ctx.plan_state<>("p");
    if (mistake == "none") ctx.plan_state<double>("p", {"x"});
  }
  StateResult execute(StateContext&) override { return StateResult::kProceed; }
  StateParam<std::string> mistake_;
};

const Registry& mistaken_registry() {
  static const Registry instance = [] {
    Registry registry = test::make_test_registry();
    auto& info = add_state_class<Mistaken>(registry, "test.Mistaken");
    info.param("mistake", &Mistaken::mistake_);
    return registry;
  }();
  return instance;
}

std::string load_errors(const std::string& mistake) {
  return format(test::diagnose_text(machine("      a: {type: test.Mistaken, params: {mistake: " +
                                                mistake + "}}\n      p: test.Pose\n",
                                            "[a]"),
                                    mistaken_registry()));
}

}  // namespace

TEST_CASE("a wrong name or kind in a state's handles fails the load at the state",
          "[scl][errors]") {
  // The state 'a' is declared at inline.yaml:6:7. Each mistake's reports, under its name.
  std::string reports;
  for (const char* mistake :
       {"none", "state", "'slot name'", "'slot kind'", "'slot twice'", "required"}) {
    reports += std::string("# ") + mistake + "\n" + load_errors(mistake);
  }
  CHECK(reports == R"(# none
# state
inline.yaml:6:7: error: state machine 'm' has no state 'pp'
inline.yaml:6:7: note: did you mean 'p'? known: a, p
# 'slot name'
inline.yaml:6:7: error: class test.Mistaken plans state 'p' (test.Pose) with param 'y', which its class does not declare
inline.yaml:6:7: note: did you mean 'x'? known: x
inline.yaml:6:7: error: class test.Mistaken plans state 'p' without its required param 'x'; give it a slot or set it on the state
# 'slot kind'
inline.yaml:6:7: error: class test.Mistaken plans param 'x' (double) of state 'p' in a slot of kind int
# 'slot twice'
inline.yaml:6:7: error: class test.Mistaken plans param 'x' of state 'p' twice
# required
inline.yaml:6:7: error: class test.Mistaken plans state 'p' without its required param 'x'; give it a slot or set it on the state
)");
}

TEST_CASE("a state name planned from a config param is checked at that param", "[scl][errors]") {
  const auto text = format(test::diagnose_text(
      machine("      a: {type: test.Planner, params: {op: append, target: wlak}}\n"
              "      walk: scripted\n",
              "[a]"),
      registry()));
  CHECK(text ==
        "inline.yaml:6:60: error: state machine 'm' has no state 'wlak'\n"
        "inline.yaml:6:60: note: did you mean 'walk'? known: a, walk\n");
}
