#pragma once
// Behaviour code that misbehaves, for the tests of how the manager contains it
// (docs/robustness.md): behaviours, an interface, a state and controller hooks that throw or
// produce non-finite numbers on request, a log to read the reports from, and a trace to read the
// steps from.

#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "arbiter/manager.hpp"
#include "arbiter/registry.hpp"
#include "arbiter/state.hpp"
#include "arbiter/trace.hpp"
#include "test_support.hpp"

namespace arbiter::test {

/// Throws from `callback` (init, update, activation, execute, inhibited) in steps [from, until];
/// otherwise requests `level`. Writes `value` to `out` at the start of execute(), so a throw from
/// execute() leaves a write behind. Counts its calls.
class Faulty : public Behaviour {
 public:
  void init(BehaviourInitContext&) override {
    from = static_cast<std::uint64_t>(from_param);
    until = static_cast<std::uint64_t>(until_param);
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
  std::int64_t from_param = 1;  // the params; a step number is unsigned
  std::int64_t until_param = 0;
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

/// A number given as text: "nan", "inf" and "-inf" too.
double number_of(const std::string& text);

/// Requests `level` and writes `value` to `out` (double), `out2` (vec2, as x) and `out3` (vec3,
/// as z), each given as text so that "nan", "inf" and "-inf" can be written; `from` is the first
/// step in which it writes.
class Odd : public Behaviour {
 public:
  void init(BehaviourInitContext&) override {
    level = number_of(level_text);
    value = number_of(value_text);
    from = static_cast<std::uint64_t>(from_param);
  }
  double activation(const StepContext&) override { return level; }
  void execute(ExecuteContext& ctx) override {
    if (ctx.step() < from) return;
    ctx.write(out, value);
    ctx.write(out2, Vec2{value, 0.0});
    ctx.write(out3, Vec3{0.0, 0.0, value});
  }

  std::string level_text;  // the params, as text
  std::string value_text;
  std::int64_t from_param = 1;
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
  void init(InitContext&) override {
    from = static_cast<std::uint64_t>(from_param);
    until = static_cast<std::uint64_t>(until_param);
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
  std::int64_t from_param = 1;
  std::int64_t until_param = 0;
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
    callback = ctx.param(callback_param);
    if (callback == "init") throw std::runtime_error("faulty state init");
  }
  void activate(StateContext&) override { fail("activate"); }
  StateResult execute(StateContext&) override {
    fail("execute");
    return StateResult::kProceed;
  }
  void deactivate(StateContext&) override { fail("deactivate"); }

  StateParam<std::string> callback_param;
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

/// The test registry plus the classes above, as robust.Faulty, robust.Odd, robust.FaultyFeed
/// and robust.FaultyState.
Registry make_fault_registry();
const Registry& fault_registry();

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

/// A manager of `yaml`, compiled with fault_registry(), that reports into `log`.
Manager make(const std::string& yaml, Log& log);

template <typename T>
T& behaviour(const Manager& manager, const std::string& layer, const std::string& name) {
  return instance<T>(manager.program(), layer, name);
}

/// The value of the double actuator `name`, and whether it was written in the last step.
double actuator(const Manager& manager, const std::string& name);
bool written(const Manager& manager, const std::string& name);

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

}  // namespace arbiter::test
