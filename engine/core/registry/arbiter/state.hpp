#pragma once
// The C++ API of the State Controller Library (SCL): state classes, the context their callbacks
// receive, the plan (queue) they may edit, and the hooks a controller's owner may install.

#include <array>
#include <cstdint>
#include <string_view>
#include <type_traits>
#include <variant>
#include <vector>

#include "arbiter/behaviour.hpp"
#include "arbiter/registry.hpp"

namespace arbiter {

class Controller;
class StateInitContext;

enum class StateResult { kHold, kProceed };

enum class ControllerStatus { kRunning, kFinished, kError };
const char* to_string(ControllerStatus status);

/// The value of a run-time param of a planned state instance: the kinds a plan edit may set.
using ArgValue = std::variant<bool, std::int64_t, double, Vec2, Vec3>;

/// A param of a state class, bound to the member at registration (ClassBinder::param) and read in a
/// step by index (StateContext::param), with no name lookup.
template <typename T>
struct StateParam {
  using type = T;
  std::uint32_t index = kNoIndex;  ///< among the class's params
  bool bound() const { return index != kNoIndex; }
};

/// A state of the controller with per-instance params from the config, resolved and validated
/// at load (StateInitContext::plan_state). A plan edit refuses one with params that were not
/// resolved so (an error of the controller), rather than run the state without them.
struct PlannedState {
  std::uint32_t state = kNoState;
  std::vector<Param> params;
  /// params[i]'s index among the state class's params, resolved with them.
  std::vector<std::uint32_t> param_index;
};

/// A state of the controller with typed slots for run-time params, resolved and checked at load
/// (StateInitContext::plan_state<Ts...>); a plan edit fills the slots in order:
/// `ctx.plan().append(walk_, x, y, theta)`.
template <typename... Ts>
struct PlannedStateRef {
  static_assert(((std::is_same_v<Ts, bool> || std::is_same_v<Ts, std::int64_t> ||
                  std::is_same_v<Ts, double> || std::is_same_v<Ts, Vec2> ||
                  std::is_same_v<Ts, Vec3>)&&...),
                "a run-time param is a bool, std::int64_t, double, Vec2 or Vec3");
  std::uint32_t state = kNoState;
  std::array<std::uint32_t, sizeof...(Ts)> params{};  ///< each slot's index among the params
  bool bound() const { return state != kNoState; }
};

namespace detail {
template <typename T>
struct Same {
  using type = T;
};
/// One filled slot of a plan edit.
struct PlanArg {
  std::uint32_t param = kNoIndex;
  ArgValue value;
};
}  // namespace detail

/// The controller's queue of future state instances, head first. Every edit that cannot be
/// carried out (capacity exceeded, index out of range, a run-time value out of its param's range)
/// puts the controller into `error` status with a logged message naming the controller, the state
/// and where it was declared; the edit returns false. States and param names are resolved at
/// load, so a typo there fails the load instead.
class Plan {
 public:
  explicit Plan(Controller& controller) : controller_(&controller) {}

  template <typename... Ts>
  bool append(const PlannedStateRef<Ts...>& state, const typename detail::Same<Ts>::type&... args) {
    return edit(kAt, size(), state, args...);
  }
  template <typename... Ts>
  bool prepend(const PlannedStateRef<Ts...>& state,
               const typename detail::Same<Ts>::type&... args) {
    return edit(kAt, 0, state, args...);
  }
  /// Inserts before the queue entry at `index` (0 = head; size() = at the end).
  template <typename... Ts>
  bool insert_before(std::size_t index, const PlannedStateRef<Ts...>& state,
                     const typename detail::Same<Ts>::type&... args) {
    return edit(kAt, index, state, args...);
  }
  template <typename... Ts>
  bool insert_after(std::size_t index, const PlannedStateRef<Ts...>& state,
                    const typename detail::Same<Ts>::type&... args) {
    return edit(kAt, index + 1, state, args...);
  }
  /// Replaces the whole queue with one instance (the current state still decides when to go).
  template <typename... Ts>
  bool go_to(const PlannedStateRef<Ts...>& state, const typename detail::Same<Ts>::type&... args) {
    return edit(kGoTo, 0, state, args...);
  }
  /// `planned` must outlive the instance it plans (the instance reads its params from it): keep
  /// it in the state or hooks object, as their handles.
  bool append(const PlannedState& planned);
  bool prepend(const PlannedState& planned);
  bool go_to(const PlannedState& planned);
  bool remove(std::size_t index);
  void clear();
  /// The name of the queued state at `index`, or "" past the end.
  std::string_view peek(std::size_t index = 0) const;
  std::size_t size() const;
  bool contains(std::string_view state) const;
  /// Ends the controller in this step: the current state is deactivated and the status becomes
  /// `finished`.
  void terminate();

 private:
  enum Mode { kAt, kGoTo };
  template <typename... Ts>
  bool edit(Mode mode, std::size_t index, const PlannedStateRef<Ts...>& state, const Ts&... args) {
    std::array<detail::PlanArg, sizeof...(Ts)> filled{};
    std::size_t slot = 0;
    ((filled[slot] = detail::PlanArg{state.params[slot], ArgValue(args)}, ++slot), ...);
    return edit(mode, index, state.state, nullptr, filled.data(), filled.size());
  }
  /// Every edit that plans an instance: from a handle's slots (`args`) or a `planned` state.
  bool edit(Mode mode, std::size_t index, std::uint32_t state, const PlannedState* planned,
            const detail::PlanArg* args, std::size_t count);

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
  /// This instance's param (its run-time value, else its planned one, else the state's, else the
  /// class default); the type's zero value for an optional param without a value.
  template <typename T>
  const T& param(StateParam<T> handle) const {
    const ParamValue* value = param_value(handle.index);
    if (const T* typed = value == nullptr ? nullptr : std::get_if<T>(value)) return *typed;
    static const T kZero{};
    return kZero;
  }
  Plan& plan() { return plan_; }
  void terminate() { plan_.terminate(); }
  /// The child controller declared for this state (`machine:`), or nullptr.
  Controller* child() const;
  const StepContext& step_context() const { return *this; }

 private:
  const ParamValue* param_value(std::uint32_t index) const;
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
  /// Once per pooled object at load: read the state's params, resolve ports, params and the
  /// states it plans to handles.
  virtual void init(StateInitContext& /*ctx*/) {}
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
ClassBinder<T>& add_state_class(Registry& registry, std::string name) {
  static_assert(std::is_base_of_v<State, T>, "a state class derives from State");
  auto& info = registry.add_bound_class<T>(std::move(name), ClassKind::kState);
  info.make_state = [] { return std::unique_ptr<State>(new T()); };
  return info;
}

}  // namespace arbiter
