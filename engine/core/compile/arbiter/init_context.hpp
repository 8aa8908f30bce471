#pragma once
// What a class may do in init(): read its validated params, resolve its ports to handles and
// report problems at config locations. Implemented by the compile stage.

#include <string>
#include <string_view>
#include <typeinfo>
#include <variant>
#include <vector>

#include "arbiter/behaviour.hpp"
#include "arbiter/registry.hpp"
#include "arbiter/state.hpp"

namespace arbiter {

class Controller;

/// An actuator that a layer declares, or a sensor that it reads, as the config names it.
struct LayerItem {
  std::string name;
  const ValueType* type = nullptr;
  SourceLocation location;  ///< where the layer names it
};

/// What every class may do in init(). Interfaces get this; behaviours and states get their own
/// context below, which adds what only they may do.
class InitContext {
 public:
  virtual ~InitContext() = default;

  /// The instance's name (behaviour, layer or state) and where it was declared.
  virtual const std::string& name() const = 0;
  virtual const SourceLocation& location() const = 0;
  /// The config's nominal step rate (`rate_hz`); one step lasts 1 / rate_hz seconds.
  virtual double rate_hz() const = 0;

  /// An output to an actuator of the instance's own layer named in the config rather than
  /// declared as a port. Reports at `where` and returns an unbound output when there is none.
  virtual AnyOutput output_to_actuator(const std::string& actuator,
                                       const SourceLocation& where) = 0;

  /// Reads `node` as a value of `type`; reports at the node and returns an empty box on failure.
  virtual ValueBox make_value(const ValueType& type, const Node& node) = 0;

  /// Reports a problem of the config at `where` (fails the load) and returns the report, to
  /// which notes can be added: `ctx.error(at, "...").unknown_name(name, known)` for a name that
  /// names nothing.
  virtual Diagnostic& error(const SourceLocation& where, std::string message) = 0;
  virtual Diagnostic& warning(const SourceLocation& where, std::string message) = 0;
  /// The load's diagnostics, for reading a structured param with Fields (<arbiter/fields.hpp>):
  /// its mistakes are then reported with the model's codes and notes.
  virtual Diagnostics& diagnostics() = 0;

  /// The actuators the instance's layer declares, in declaration order, and the sensors it
  /// reads, in the order listed: for a class that moves whatever its layer names (a middleware
  /// bridge) rather than ports it declares. Write an actuator through output_to_actuator(), read
  /// a sensor through sensor_input(). Empty for a state that no behaviour steps.
  virtual std::vector<LayerItem> layer_actuators() const = 0;
  virtual std::vector<LayerItem> layer_sensors() const = 0;

  /// An input bound to a sensor of the instance's own layer named in the config rather than
  /// declared as a port; T is the C++ type of the sensor's value type. Reports at `where` and
  /// returns an unbound input when the layer reads no such sensor or T is not its type.
  template <typename T>
  Input<T> sensor_input(const std::string& sensor, const SourceLocation& where) {
    return Input<T>{resolve_sensor(sensor, typeid(T), where)};
  }

 protected:
  virtual std::uint32_t resolve_sensor(const std::string& sensor, const std::type_info& type,
                                       const SourceLocation& where) = 0;

 public:
  /// Where the param bound to `member` was written, or the instance's location for a default:
  /// `ctx.error(ctx.param_location(&GoTo::target_), "...")`. A member that no param is bound to
  /// is a programming error reported at the instance's location.
  template <typename C, typename M>
  SourceLocation param_location(M C::*member) const {
    return bound_param_location(MemberKey(member));
  }

 protected:
  virtual SourceLocation bound_param_location(const MemberKey& member) const = 0;
};

/// A behaviour's init(): also claims a state machine's controller to step.
class BehaviourInitContext : public InitContext {
 public:
  /// Claims the controller of state machine `machine` for this instance to step (the built-in
  /// `state_machine` behaviour does). Reports and returns nullptr when there is none, or when it
  /// already has an owner.
  virtual Controller* claim_controller(const std::string& machine, const SourceLocation& where) = 0;
};

/// A state's init(): also reads the state's own params and resolves the states it plans to
/// handles, so that a step looks up no name and a wrong name in code fails the load at a config
/// location.
class StateInitContext : public InitContext {
 public:
  /// The state's own value of a param bound to `handle` (set on the state, else the class
  /// default): what init() can know of a per-instance param before any instance is planned, as a
  /// state that plans another by a name in its params does. A planned instance's value is read
  /// in a step (StateContext::param). The type's zero value for an unbound handle or an optional
  /// param without a value.
  template <typename T>
  T param(StateParam<T> handle) const {
    const ParamValue* value = state_param(handle.index);
    if (const T* typed = value == nullptr ? nullptr : std::get_if<T>(value)) return *typed;
    return T{};
  }

  /// A state of the same controller with typed slots for run-time params, one per name in
  /// `params`, in order: `ctx.plan_state<double, double>("walk", {"x", "y"})`. Reports at `where`
  /// (by default the state's location) and returns an unbound handle when the machine declares
  /// no such state, its class no such param, a param's kind has another C++ type than its slot,
  /// a name comes twice, or a required param is neither a slot nor set on the state.
  template <typename... Ts>
  PlannedStateRef<Ts...> plan_state(
      const std::string& state, const std::array<std::string_view, sizeof...(Ts)>& params = {}) {
    return plan_state<Ts...>(state, params, location());
  }
  template <typename... Ts>
  PlannedStateRef<Ts...> plan_state(const std::string& state,
                                    const std::array<std::string_view, sizeof...(Ts)>& params,
                                    const SourceLocation& where) {
    const std::array<ParamKind, sizeof...(Ts)> kinds{param_kind_of<Ts>()...};
    PlannedStateRef<Ts...> ref;
    const std::uint32_t index =
        resolve_state(state, params.data(), kinds.data(), sizeof...(Ts), ref.params.data(), where);
    if (index != kNoState) ref.state = index;
    return ref;
  }

  /// A state of the same controller with per-instance params written in the config (a mapping
  /// node, or null), checked now so that a typo in a config fails the load. Reports at `where`
  /// and returns false when the state or a param is wrong.
  virtual bool plan_state(const std::string& state, const Node* params, const SourceLocation& where,
                          PlannedState& out) = 0;

 protected:
  virtual const ParamValue* state_param(std::uint32_t index) const = 0;
  virtual std::uint32_t resolve_state(const std::string& state, const std::string_view* params,
                                      const ParamKind* kinds, std::size_t count,
                                      std::uint32_t* indices, const SourceLocation& where) = 0;
};

}  // namespace arbiter
