// Behaviour code that misbehaves (docs/robustness.md), as the manager contains it: code that
// throws, asks for a non-finite level or writes non-finite values is contained at the step
// boundary, reported once, and handled by the config's `on_exception` policy; the safe pass
// outputs the safe values when a run ends.

#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "arbiter/load.hpp"
#include "arbiter/program.hpp"
#include "arbiter/state.hpp"
#include "arbiter/trace.hpp"
#include "config_files.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace arbiter;

namespace {

/// Throws from `callback` (init, update, activation, execute, inhibited) in steps [from, until];
/// otherwise requests `level`. Writes `value` to `out` at the start of execute(), so a throw from
/// execute() leaves a write behind. Counts its calls.
class Faulty : public Behaviour {
 public:
  void init(BehaviourInitContext& ctx) override {
    callback = ctx.param<std::string>("callback");
    from = static_cast<std::uint64_t>(ctx.param<std::int64_t>("from"));
    until = static_cast<std::uint64_t>(ctx.param<std::int64_t>("until"));
    level = ctx.param<double>("level");
    value = ctx.param<double>("value");
    out = ctx.output<double>("out");
    if (callback == "init") throw std::runtime_error("faulty init");
  }
  void update(const StepContext& ctx) override {
    ++updates;
    fail("update", ctx);
  }
  double activation(const StepContext& ctx) override {
    ++activations;
    fail("activation", ctx);
    return level;
  }
  void execute(ExecuteContext& ctx) override {
    ++executions;
    ctx.write(out, value);
    fail("execute", ctx);
  }
  void inhibited(const InhibitedContext& ctx) override {
    ++inhibitions;
    fail("inhibited", ctx);
  }

  std::string callback;
  std::uint64_t from = 1;
  std::uint64_t until = 0;
  double level = 1.0;
  double value = 0.0;
  Output<double> out;
  int updates = 0;
  int activations = 0;
  int executions = 0;
  int inhibitions = 0;

 private:
  void fail(const std::string& here, const StepContext& ctx) const {
    if (here == callback && ctx.step() >= from && ctx.step() <= until) {
      throw std::runtime_error("faulty " + here);
    }
  }
};

double number_of(const std::string& text) {
  if (text == "nan") return std::numeric_limits<double>::quiet_NaN();
  if (text == "inf") return std::numeric_limits<double>::infinity();
  if (text == "-inf") return -std::numeric_limits<double>::infinity();
  return std::stod(text);
}

/// Requests `level` and writes `value` to `out` (double), `out2` (vec2, as x) and `out3` (vec3,
/// as z), each given as text so that "nan", "inf" and "-inf" can be written; `from` is the first
/// step in which it writes.
class Odd : public Behaviour {
 public:
  void init(BehaviourInitContext& ctx) override {
    level = number_of(ctx.param<std::string>("level"));
    value = number_of(ctx.param<std::string>("value"));
    from = static_cast<std::uint64_t>(ctx.param<std::int64_t>("from"));
    out = ctx.output<double>("out");
    out2 = ctx.output<Vec2>("out2");
    out3 = ctx.output<Vec3>("out3");
  }
  double activation(const StepContext&) override { return level; }
  void execute(ExecuteContext& ctx) override {
    if (ctx.step() < from) return;
    ctx.write(out, value);
    ctx.write(out2, Vec2{value, 0.0});
    ctx.write(out3, Vec3{0.0, 0.0, value});
  }

  double level = 1.0;
  double value = 0.0;
  std::uint64_t from = 1;
  Output<double> out;
  Output<Vec2> out2;
  Output<Vec3> out3;
};

/// An interface that writes the step number to `out` in the input pass and throws from
/// `callback` (input or output) in steps [from, until], or from init.
class FaultyFeed : public Interface {
 public:
  void init(InitContext& ctx) override {
    callback = ctx.param<std::string>("callback");
    from = static_cast<std::uint64_t>(ctx.param<std::int64_t>("from"));
    until = static_cast<std::uint64_t>(ctx.param<std::int64_t>("until"));
    out = ctx.output<double>("out");
    if (callback == "init") throw 7;
  }
  void input(WriteContext& ctx) override {
    ++inputs;
    ctx.write(out, static_cast<double>(ctx.step()));
    if (callback == "input" && ctx.step() >= from && ctx.step() <= until) {
      throw std::runtime_error("feed input");
    }
  }
  void output(const StepContext& ctx) override {
    ++outputs;
    if (callback == "output" && ctx.step() >= from && ctx.step() <= until) throw 42;
  }

  std::string callback;
  std::uint64_t from = 1;
  std::uint64_t until = 0;
  Output<double> out;
  int inputs = 0;
  int outputs = 0;
};

/// A state that throws from `callback` (init, activate, execute or deactivate); it proceeds
/// after its first execution.
class FaultyState : public State {
 public:
  void init(StateInitContext& ctx) override {
    callback = ctx.param<std::string>("callback");
    if (callback == "init") throw std::runtime_error("faulty state init");
  }
  void activate(StateContext&) override { fail("activate"); }
  StateResult execute(StateContext&) override {
    fail("execute");
    return StateResult::kProceed;
  }
  void deactivate(StateContext&) override { fail("deactivate"); }

  std::string callback;

 private:
  void fail(const std::string& here) const {
    if (here == callback) throw std::runtime_error("faulty " + here);
  }
};

/// Controller hooks that throw from the one named `callback`.
class FaultyHooks : public ControllerHooks {
 public:
  explicit FaultyHooks(std::string callback) : callback_(std::move(callback)) {}
  bool pre_step(Controller&, Plan&) override { return fail("pre_step"); }
  void pre_activate(Controller&, std::string_view) override { fail("pre_activate"); }
  void pre_execute(Controller&, std::string_view) override { fail("pre_execute"); }
  bool post_execute(Controller&, std::string_view, StateResult) override {
    return fail("post_execute");
  }
  void post_step(Controller&) override { fail("post_step"); }
  void on_terminate(Controller&) override { fail("on_terminate"); }

 private:
  bool fail(const std::string& here) const {
    if (here == callback_) throw std::runtime_error("hook " + here);
    return false;
  }
  std::string callback_;
};

/// The test registry plus the classes above.
Registry make_registry() {
  Registry r = test::make_test_registry();
  r.set_origin("robustness_test");
  constexpr std::int64_t kForever = std::numeric_limits<std::int64_t>::max();
  auto& faulty = r.add_behaviour<Faulty>("robust.Faulty");
  faulty.param<std::string>("callback")
      .defaults_to(std::string("activation"))
      .one_of({"init", "update", "activation", "execute", "inhibited"});
  faulty.param<std::int64_t>("from").defaults_to(1);
  faulty.param<std::int64_t>("until").defaults_to(kForever);
  faulty.param<double>("level").defaults_to(1.0);
  faulty.param<double>("value").defaults_to(0.0);
  faulty.output<double>("out").make_optional();
  auto& odd = r.add_behaviour<Odd>("robust.Odd");
  odd.param<std::string>("level").defaults_to(std::string("1"));
  odd.param<std::string>("value").defaults_to(std::string("0"));
  odd.param<std::int64_t>("from").defaults_to(1);
  odd.output<double>("out").make_optional();
  odd.output<Vec2>("out2").make_optional();
  odd.output<Vec3>("out3").make_optional();
  auto& feed = r.add_interface<FaultyFeed>("robust.FaultyFeed");
  feed.param<std::string>("callback").defaults_to(std::string("input"));
  feed.param<std::int64_t>("from").defaults_to(1);
  feed.param<std::int64_t>("until").defaults_to(kForever);
  feed.output<double>("out").make_optional();
  auto& state = add_state_class<FaultyState>(r, "robust.FaultyState");
  state.param<std::string>("callback")
      .defaults_to(std::string("execute"))
      .one_of({"init", "activate", "execute", "deactivate"});
  return r;
}

const Registry& registry() {
  static const Registry instance = make_registry();
  return instance;
}

/// A logger whose lines ("error: ..." / "warning: ...") the test can read.
class Log {
 public:
  Log()
      : logger(std::make_shared<spdlog::logger>(
            "robustness", std::make_shared<spdlog::sinks::ostream_sink_st>(text_))) {
    logger->set_pattern("%l: %v");
    logger->set_level(spdlog::level::trace);
  }
  Log(const Log&) = delete;
  Log& operator=(const Log&) = delete;

  std::string text() const { return text_.str(); }
  std::size_t count(const std::string& needle) const {
    const std::string all = text_.str();
    std::size_t n = 0;
    for (auto at = all.find(needle); at != std::string::npos; at = all.find(needle, at + 1)) ++n;
    return n;
  }
  std::size_t lines() const { return count("\n"); }

  std::shared_ptr<spdlog::logger> logger;

 private:
  std::ostringstream text_;
};

Manager make(const std::string& yaml, Log& log) {
  return Manager(test::compile_text(yaml, registry()), log.logger);
}

template <typename T>
T& behaviour(const Manager& manager, const std::string& layer, const std::string& name) {
  return test::instance<T>(manager.program(), layer, name);
}

double actuator(const Manager& manager, const std::string& name) {
  return manager.actuator<double>(*manager.program().find_actuator(name));
}

bool written(const Manager& manager, const std::string& name) {
  return manager.actuator_written(*manager.program().find_actuator(name));
}

/// Collects the trace of every step as parsed JSON: a non-finite number would not parse.
class JsonTrace {
 public:
  explicit JsonTrace(Manager& manager) : writer_(out_) { manager.add_observer(writer_); }
  std::vector<nlohmann::json> records() const {
    std::vector<nlohmann::json> parsed;
    std::istringstream in(out_.str());
    std::string line;
    while (std::getline(in, line)) parsed.push_back(nlohmann::json::parse(line));
    return parsed;
  }

 private:
  std::ostringstream out_;
  TraceWriter writer_;
};

using test::error_codes;
using test::load_file;
using test::Outcome;
using test::TempDir;
using test::write_text;

}  // namespace

TEST_CASE("a throwing behaviour counts as inactive in that step and is reported once",
          "[robustness][faults]") {
  Log log;
  auto manager = make(R"(arbiter: 1
name: t
layers:
  - name: l
    actuators:
      speed: {type: double}
    behaviours:
      broken: {type: robust.Faulty, params: {callback: activation, from: 2, until: 3, value: 9},
               ports: {out: speed}}
      fine: {type: test.Probe, params: {levels: 0.5, value: 1}, ports: {out: speed}}
    inhibitions: [broken -> fine]
)",
                      log);
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
  auto manager = make(R"(arbiter: 1
name: t
layers:
  - name: l
    actuators:
      speed: {type: double, aggregate: true}
    behaviours:
      in_update: {type: robust.Faulty, params: {callback: update, from: 2, until: 2, value: 5},
                  ports: {out: speed}}
      in_execute: {type: robust.Faulty, params: {callback: execute, from: 3, until: 3, value: 7},
                   ports: {out: speed}}
      in_inhibited: {type: robust.Faulty, params: {callback: inhibited, level: 0}}
)",
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
  auto manager = make(R"(arbiter: 1
name: t
layers:
  - name: l
    actuators:
      speed: {type: double}
    behaviours:
      broken: {type: robust.Faulty, params: {callback: execute, from: 2, until: 2, value: 9},
               ports: {out: speed}, on_exception: disable}
      fine: {type: test.Probe, params: {levels: 0.5, value: 1}, ports: {out: speed}}
    inhibitions: [broken -> fine]
)",
                      log);
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
  auto manager = make(R"(arbiter: 1
name: t
on_exception: stop
layers:
  - name: l
    actuators:
      speed: {type: double}
    behaviours:
      broken: {type: robust.Faulty, params: {callback: activation, from: 3, value: 9},
               ports: {out: speed}}
      fine: {type: test.Probe, params: {levels: 0.5, value: 1}, ports: {out: speed}}
    inhibitions: [broken -> fine]
)",
                      log);
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
  auto manager = make(R"(arbiter: 1
name: t
on_exception: stop
layers:
  - name: l
    behaviours:
      tolerated: {type: robust.Faulty, on_exception: inactive}
      fine: {type: test.Probe}
)",
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
  const std::string config = R"(arbiter: 1
name: t
on_exception: POLICY
layers:
  - name: l
    behaviours:
      fine: test.Probe
state_machines:
  plan:
    states:
      boom: {type: robust.FaultyState, params: {callback: CALLBACK}}
      after: test.Planner
    queue: [boom, after]
)";
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
      auto manager = make(R"(arbiter: 1
name: t
layers:
  - name: l
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
)",
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

TEST_CASE("a class that throws from init() is a load error at its declaration",
          "[robustness][faults][config]") {
  const auto errors = [](const std::string& config) {
    std::vector<std::string> lines;
    const Diagnostics diagnostics = test::diagnose_text(config, registry());
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
    return error_codes(test::diagnose_text(text, registry()));
  };
  CHECK(codes("arbiter: 1\nname: t\non_exception: abort\n") ==
        std::vector<std::string>{"out-of-range"});
  const auto diagnostics =
      test::diagnose_text("arbiter: 1\nname: t\non_exception: disabled\n", registry());
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

TEST_CASE("non-finite activation levels count as 0 or 1 and are reported once",
          "[robustness][levels]") {
  Log log;
  auto manager = make(R"(arbiter: 1
name: t
layers:
  - name: l
    behaviours:
      nan: {type: robust.Odd, params: {level: nan}}
      high: {type: robust.Odd, params: {level: inf}}
      low: {type: robust.Odd, params: {level: -inf}}
      fine: {type: test.Probe, params: {levels: 0.5}}
)",
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
      auto manager = make(R"(arbiter: 1
name: t
layers:
  - name: l
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
)",
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

TEST_CASE("a behaviour that fails every way at once leaves the others and the trace intact",
          "[robustness][faults]") {
  // The same config with and without the faulty behaviours gives the same records for the rest.
  const std::string base = R"(arbiter: 1
name: t
layers:
  - name: l
    actuators:
      speed: {type: double, aggregate: true}
    behaviours:
      a: {type: test.Probe, params: {levels: [1, 0, 0.5], value: 1}, ports: {out: speed}}
      b: {type: test.Probe, params: {levels: 0.5, value: 3}, ports: {out: speed}}
)";
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
                                               registry());
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
