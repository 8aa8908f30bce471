#pragma once
// The C++ API of the State Controller Library (SCL): state classes, the context their callbacks
// receive, the plan (queue) they may edit, and the hooks a controller's owner may install.

#include <cstdint>
#include <initializer_list>
#include <string_view>
#include <variant>

#include "arbiter/behaviour.hpp"
#include "arbiter/registry.hpp"

namespace arbiter {

class Controller;

enum class StateResult { kHold, kProceed };

enum class ControllerStatus { kRunning, kFinished, kError };
const char* to_string(ControllerStatus status);

/// One run-time param of a state instance created by a state: `{"x", 1.5}`.
struct Arg {
  using Value = std::variant<bool, std::int64_t, double, Vec2, Vec3>;
  Arg(std::string_view param, bool value) : name(param), value(value) {}
  Arg(std::string_view param, int value) : name(param), value(std::int64_t{value}) {}
  Arg(std::string_view param, std::int64_t value) : name(param), value(value) {}
  Arg(std::string_view param, double value) : name(param), value(value) {}
  Arg(std::string_view param, Vec2 value) : name(param), value(value) {}
  Arg(std::string_view param, Vec3 value) : name(param), value(value) {}
  std::string_view name;
  Value value;
};

/// A state and per-instance params, resolved and validated at load (see StateInitContext).
struct PlannedState {
  std::uint32_t state = kUnbound;
  std::vector<Param> params;
};

/// The controller's queue of future state instances, head first. Every edit that cannot be
/// carried out (unknown state or param, capacity exceeded, index out of range) puts the
/// controller into `error` status with a logged message naming the controller, the state and
/// where it was declared; the edit returns false.
class Plan {
 public:
  explicit Plan(Controller& controller) : controller_(&controller) {}

  bool append(std::string_view state, std::initializer_list<Arg> args = {});
  bool prepend(std::string_view state, std::initializer_list<Arg> args = {});
  /// Inserts before the queue entry at `index` (0 = head; size() = at the end).
  bool insert_before(std::size_t index, std::string_view state,
                     std::initializer_list<Arg> args = {});
  bool insert_after(std::size_t index, std::string_view state,
                    std::initializer_list<Arg> args = {});
  bool append(const PlannedState& planned);
  bool prepend(const PlannedState& planned);
  bool remove(std::size_t index);
  void clear();
  /// Replaces the whole queue with one instance (the current state still decides when to go).
  bool go_to(std::string_view state, std::initializer_list<Arg> args = {});
  bool go_to(const PlannedState& planned);
  /// The name of the queued state at `index`, or "" past the end.
  std::string_view peek(std::size_t index = 0) const;
  std::size_t size() const;
  bool contains(std::string_view state) const;
  /// Ends the controller in this step: the current state is deactivated and the status becomes
  /// `finished`.
  void terminate();

 private:
  Controller* controller_;
};

/// What a state's callbacks may do: read sensors (of the owning behaviour's layer), read the
/// instance's params, edit the plan, terminate, and step a child controller.
class StateContext : public StepContext {
 public:
  StateContext(const StepContext& step, ExecuteContext* execute, Controller& controller,
               std::uint32_t instance);

  /// Writes through the owning behaviour (ignored in a standalone controller, which has none).
  template <typename T>
  void write(Output<T> output, const T& value) {
    if (execute_ != nullptr) execute_->write(output, value);
  }
  /// The owning behaviour's execute context, or nullptr (standalone, or a paused owner).
  ExecuteContext* execute_context() const { return execute_; }

  /// The controller's cycle (1 in its first step).
  std::uint64_t cycle() const;
  /// How many times this instance has executed before this call (0 on its first execute()).
  std::uint64_t executions() const;
  /// This instance's param (its per-instance value, else the state's, else the class default).
  template <typename T>
  T param(std::string_view name) const {
    const ParamValue* value = find_param(name);
    if (value == nullptr || !std::holds_alternative<T>(*value)) return T{};
    return std::get<T>(*value);
  }
  Plan& plan() { return plan_; }
  void terminate() { plan_.terminate(); }
  /// The child controller declared for this state (`machine:`), or nullptr.
  Controller* child() const;
  const StepContext& step_context() const { return *this; }

 private:
  const ParamValue* find_param(std::string_view name) const;
  ExecuteContext* execute_;
  Controller* controller_;
  std::uint32_t instance_;
  Plan plan_;
};

/// A state class. Instances are single-use: the controller creates one from the pool each time a
/// state is planned, calls activate() once, execute() until it proceeds, then deactivate().
/// Objects are reused from a pool sized at load, so activate() must set up everything an
/// instance needs (it is the instance's constructor in effect).
class State {
 public:
  virtual ~State() = default;
  /// Once per pooled object at load: read the state's params and resolve ports.
  virtual void init(InitContext& /*ctx*/) {}
  virtual void activate(StateContext& /*ctx*/) {}
  virtual StateResult execute(StateContext& ctx) = 0;
  virtual void deactivate(StateContext& /*ctx*/) {}
};

/// Callbacks of a controller's owner. Each is given the plan so it can redirect the controller.
class ControllerHooks {
 public:
  virtual ~ControllerHooks() = default;
  /// Return true to pre-empt: the current state is left now, as if it had asked to proceed.
  virtual bool pre_step(Controller& /*controller*/, Plan& /*plan*/) { return false; }
  virtual void pre_activate(Controller& /*controller*/, std::string_view /*state*/) {}
  virtual void pre_execute(Controller& /*controller*/, std::string_view /*state*/) {}
  /// Return true to force the current state to proceed whatever it returned.
  virtual bool post_execute(Controller& /*controller*/, std::string_view /*state*/,
                            StateResult /*result*/) {
    return false;
  }
  virtual void post_step(Controller& /*controller*/) {}
  virtual void on_terminate(Controller& /*controller*/) {}
};

/// Registers a state class `T` (default-constructible) under `name`.
template <typename T>
ClassInfo& add_state_class(Registry& registry, std::string name) {
  return registry.add_state(std::move(name), [] { return std::unique_ptr<State>(new T()); });
}

}  // namespace arbiter
