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

namespace arbiter {

class Controller;
struct PlannedState;

/// An actuator that a layer declares, or a sensor that it reads, as the config names it.
struct LayerItem {
  std::string name;
  const ValueType* type = nullptr;
  SourceLocation location;  ///< where the layer names it
};

class InitContext {
 public:
  virtual ~InitContext() = default;

  /// The instance's name (behaviour, layer or state) and where it was declared.
  virtual const std::string& name() const = 0;
  virtual const SourceLocation& location() const = 0;
  /// The config's nominal step rate (`rate_hz`); one step lasts 1 / rate_hz seconds.
  virtual double rate_hz() const = 0;

  /// A declared param's validated value (or its default). Asking for an undeclared param, or with
  /// the wrong C++ type, is a programming error reported at the instance's location.
  template <typename T>
  T param(std::string_view param_name) {
    const ParamValue* value = find_param(param_name, typeid(T));
    if (value == nullptr || !std::holds_alternative<T>(*value)) return T{};
    return std::get<T>(*value);
  }
  /// Where a param was written, or the instance's location for a default.
  virtual SourceLocation param_location(std::string_view param_name) const = 0;

  template <typename T>
  Input<T> input(std::string_view port) {
    return Input<T>{resolve_port(port, PortDirection::kInput, typeid(T))};
  }
  template <typename T>
  Output<T> output(std::string_view port) {
    return Output<T>{resolve_port(port, PortDirection::kOutput, typeid(T))};
  }

  /// An output to an actuator of the instance's own layer named in the config rather than
  /// declared as a port. Reports at `where` and returns an unbound output when there is none.
  virtual AnyOutput output_to_actuator(const std::string& actuator,
                                       const SourceLocation& where) = 0;

  /// Reads `node` as a value of `type`; reports at the node and returns an empty box on failure.
  virtual ValueBox make_value(const ValueType& type, const Node& node) = 0;

  /// For a state class: a state of the same controller with per-instance params (a mapping node,
  /// or null), checked now so that a typo in a config fails the load. Reports at `where` and
  /// returns false when the state or a param is wrong.
  virtual bool plan_state(const std::string& state, const Node* params, const SourceLocation& where,
                          PlannedState& out) = 0;

  /// Claims the controller of state machine `machine` for this instance to step (the built-in
  /// `state_machine` behaviour does). Reports and returns nullptr when there is none, or when it
  /// already has an owner.
  virtual Controller* claim_controller(const std::string& machine, const SourceLocation& where) = 0;

  /// Reports a problem of the config at `where` (fails the load) and returns the report, to
  /// which notes can be added: `ctx.error(at, "...").unknown_name(name, known)` for a name that
  /// names nothing.
  virtual Diagnostic& error(const SourceLocation& where, std::string message) = 0;
  virtual Diagnostic& warning(const SourceLocation& where, std::string message) = 0;
  /// The load's diagnostics, for reading a structured param with Fields (<arbiter/fields.hpp>):
  /// its mistakes are then reported with the model's codes and notes.
  virtual Diagnostics& diagnostics() = 0;

 protected:
  virtual const ParamValue* find_param(std::string_view param_name,
                                       const std::type_info& requested) = 0;
  virtual std::uint32_t resolve_port(std::string_view port, PortDirection direction,
                                     const std::type_info& type) = 0;

  // Declared after every earlier virtual function, so that a plugin built against an earlier
  // header of the same API version finds those at the same place in the table.
 public:
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
};

}  // namespace arbiter
