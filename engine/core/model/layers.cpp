// Layers and what they declare: actuators (unique in the manager), the sensors that read another
// layer's actuators, behaviours and interface classes, and the binding of their ports. Sensors,
// ports and behaviours are read once every file's actuators are known (check_layers).
#include <algorithm>

#include <fmt/format.h>

#include "arbiter/fields.hpp"
#include "core/model/builder.hpp"

namespace arbiter::detail {

void ModelBuilder::read_layer(const Node& node) {
  Fields fields(node, "a layer",
                {"name", "interface", "params", "ports", "actuators", "sensors", "behaviours",
                 "inhibitions", "normalise", "lint"},
                diagnostics_);
  if (!fields.ok()) return;
  LayerDecl layer;
  PendingLayer pending;
  pending.location = node.location();
  layer.name.location = node.location();
  if (const Node* name = fields.required("name")) {
    layer.name.location = name->location();
    if (auto text = read_name(*name, "a layer")) layer.name.text = *text;
  }
  if (!layer.name.text.empty()) {
    for (const auto& other : model_.layers) {
      if (other.name.text == layer.name.text) {
        auto& error = diagnostics_.error(layer.name.location, "duplicate-name",
                                         fmt::format("duplicate layer '{}'", layer.name.text));
        error.notes.push_back({fmt::format("first declared at {}", to_string(other.name.location)),
                               other.name.location});
      }
    }
  }
  const std::string owner = layer_label(layer);
  if (const Node* interface = fields.optional("interface")) {
    layer.interface = read_class(*interface, ClassKind::kInterface, owner);
    pending.params = fields.optional("params");
    pending.ports = fields.optional("ports");
    for (auto key : {"behaviours", "inhibitions"}) {
      if (fields.optional(key) == nullptr) continue;
      diagnostics_.error(fields.key_location(key), "interface-with-behaviours",
                         fmt::format("interface layer '{}' cannot have {}: its data comes from "
                                     "its interface class",
                                     layer.name.text, key));
    }
  } else {
    for (auto key : {"params", "ports"}) {
      if (fields.optional(key) == nullptr) continue;
      diagnostics_.error(fields.key_location(key), "unknown-key",
                         fmt::format("'{}' belongs to an interface layer; layer '{}' has no "
                                     "'interface:'",
                                     key, layer.name.text));
    }
    pending.behaviours = fields.optional("behaviours");
    pending.inhibitions = fields.optional("inhibitions");
  }
  if (const Node* normalise = fields.optional("normalise")) {
    layer.normalise = read_bool(*normalise, "normalise");
  }
  if (const Node* lint = fields.optional("lint")) read_lint(*lint, layer.lint_ignore);
  if (const Node* actuators = fields.optional("actuators")) read_actuators(*actuators, layer);
  pending.sensors = fields.optional("sensors");
  model_.layers.push_back(std::move(layer));
  pending_layers_.push_back(pending);
}

std::string ModelBuilder::layer_label(const LayerDecl& layer) {
  if (!layer.name.text.empty()) return fmt::format("layer '{}'", layer.name.text);
  const auto& where = layer.name.location;
  return fmt::format("the unnamed layer at {}", to_string(where));
}

void ModelBuilder::read_actuators(const Node& node, LayerDecl& layer) {
  if (node.reads_as_null()) return;
  if (!node.is_mapping()) {
    diagnostics_.error(node.location(), "wrong-type",
                       fmt::format("'actuators' must be a mapping from names to "
                                   "{{type: ...}}, found {}",
                                   node.describe()));
    return;
  }
  for (const auto& entry : node.entries()) {
    // An actuator with a bad name or body is still declared, so that the sensors and ports
    // naming it report nothing more.
    check_identifier(entry.key, entry.key_location, "an actuator");
    ActuatorDecl actuator;
    actuator.name = {entry.key, entry.key_location};
    actuator.layer = layer.name.text;
    const Node* type = nullptr;
    const Node* aggregate = nullptr;
    if (entry.value.is_scalar() && !entry.value.reads_as_null()) {
      type = &entry.value;  // short form `name: vec2`
    } else {
      Fields fields(entry.value, fmt::format("actuator '{}'", entry.key),
                    {"type", "aggregate", "default", "safe"}, diagnostics_,
                    "a value type or a mapping {type: ..., aggregate: ..., default: ..., "
                    "safe: ...}");
      type = fields.required("type");
      aggregate = fields.optional("aggregate");
      if (aggregate != nullptr) {
        actuator.aggregate = read_bool(*aggregate, "aggregate").value_or(false);
      }
      if (const Node* given = fields.optional("default")) actuator.default_value = *given;
      if (const Node* safe = fields.optional("safe")) actuator.safe_value = *safe;
    }
    if (type != nullptr) {
      if (auto text = read_string(*type, "a value type")) {
        actuator.type = registry_.find_value_type(*text);
        // A value type of a listed plugin that did not load: the plugin's error says it.
        if (actuator.type == nullptr &&
            !(from_unloaded_plugin(*text) && diagnostics_.has_errors())) {
          diagnostics_
              .error(type->location(), "unknown-type",
                     fmt::format("unknown value type '{}'", *text))
              .unknown_name(*text, registry_.value_type_names());
        }
      }
    }
    if (actuator.type != nullptr && actuator.aggregate && !actuator.type->aggregatable()) {
      std::vector<std::string> averaged;
      for (const auto& value_type : registry_.value_types()) {
        if (value_type->aggregatable()) averaged.push_back(value_type->name);
      }
      auto& error = diagnostics_.error(
          aggregate->location(), "not-aggregatable",
          fmt::format("actuator '{}' cannot be 'aggregate: true': values of type '{}' cannot "
                      "be averaged",
                      entry.key, actuator.type->name));
      std::sort(averaged.begin(), averaged.end());
      std::string list;
      for (const auto& name : averaged) list += (list.empty() ? "" : ", ") + name;
      error.notes.push_back("types that can be averaged: " + list);
      error.notes.push_back(
          "without 'aggregate', the writer with the highest activation level wins");
    }
    for (const auto& [what, value] : {std::pair{"default", &actuator.default_value},
                                      std::pair{"safe value", &actuator.safe_value}}) {
      if (actuator.type == nullptr || !*value) continue;
      ValueBox scratch(*actuator.type);
      std::string expected;
      if (!actuator.type->from_node(**value, scratch.data(), expected)) {
        add_quote_hint(
            diagnostics_.error(
                (*value)->location(), "wrong-type",
                fmt::format("{} of actuator '{}' must be {} ({}), found {}", what, entry.key,
                            expected, actuator.type->name, (*value)->describe())),
            **value);
      }
    }
    if (auto found = actuator_index_.find(entry.key); found != actuator_index_.end()) {
      auto& error = diagnostics_.error(
          entry.key_location, "duplicate-name",
          fmt::format("duplicate actuator '{}': actuator names are unique in the manager",
                      entry.key));
      const auto& first = found->second;
      error.notes.push_back({fmt::format("first declared in layer '{}' at {}", first.layer,
                                         to_string(first.location)),
                             first.location});
      continue;
    }
    actuator_index_[entry.key] = {actuator.layer, entry.key_location, actuator.type};
    layer.actuators.push_back(std::move(actuator));
  }
}

void ModelBuilder::check_layers() {
  for (std::size_t i = 0; i < model_.layers.size(); ++i) {
    LayerDecl& layer = model_.layers[i];
    PendingLayer& pending = pending_layers_[i];
    if (pending.sensors != nullptr) read_sensors(*pending.sensors, layer, pending);
    if (layer.interface != nullptr) {
      const std::string owner = layer.name.text.empty()
                                    ? layer_label(layer)
                                    : fmt::format("interface layer '{}'", layer.name.text);
      layer.params = read_params(*layer.interface, pending.params, layer.name.location, owner);
      layer.ports = bind_ports(*layer.interface, pending.ports, layer, owner, layer.name.location);
    }
    if (pending.behaviours != nullptr) read_behaviours(*pending.behaviours, layer, pending);
  }
  // Inhibitions last: naming a behaviour of another layer is told apart from a typo only once
  // every layer's behaviours are known.
  for (std::size_t i = 0; i < model_.layers.size(); ++i) {
    if (const Node* inhibitions = pending_layers_[i].inhibitions) {
      read_inhibitions(*inhibitions, model_.layers[i], pending_layers_[i]);
    }
  }
}

void ModelBuilder::read_sensors(const Node& node, LayerDecl& layer, PendingLayer& pending) {
  auto add = [&](const std::string& name, const SourceLocation& where, const Node* type) {
    if (!check_identifier(name, where, "a sensor")) return;
    for (const auto& existing : layer.sensors) {
      if (existing.text == name) {
        diagnostics_
            .error(where, "duplicate-name",
                   fmt::format("sensor '{}' listed twice in {}", name, layer_label(layer)))
            .notes.push_back({fmt::format("first listed at {}", to_string(existing.location)),
                              existing.location});
        return;
      }
    }
    const auto found = actuator_index_.find(name);
    if (found == actuator_index_.end()) {
      auto& error = diagnostics_.error(
          where, "unknown-actuator",
          fmt::format("sensor '{}' of {} names no actuator", name, layer_label(layer)));
      const auto names = actuator_names();
      error.unknown_name(name, names, "the config declares no actuators");
      if (auto meant = closest(name, names)) {
        pending.misspelt_sensors.emplace_back(std::move(*meant), diagnostics_.items().size() - 1);
      }
      return;
    }
    const ActuatorInfo& actuator = found->second;
    if (type != nullptr && !type->is_scalar()) {
      diagnostics_.error(type->location(), "wrong-type",
                         fmt::format("sensor '{}' must map to its value type, such as "
                                     "'{}: double', found {}",
                                     name, name, type->describe()));
    } else if (type != nullptr) {
      auto text = read_string(*type, fmt::format("the value type of sensor '{}'", name));
      if (text && actuator.type != nullptr && *text != actuator.type->name) {
        diagnostics_
            .error(type->location(), "type-mismatch",
                   fmt::format("sensor '{}' expects type '{}' but actuator '{}' is '{}'", name,
                               *text, name, actuator.type->name))
            .notes.push_back({fmt::format("'{}' is declared in layer '{}' at {}", name,
                                          actuator.layer, to_string(actuator.location)),
                              actuator.location});
      }
    }
    layer.sensors.push_back({name, where});
  };
  if (node.reads_as_null()) return;
  if (node.is_sequence()) {
    for (const auto& item : node.items()) {
      if (auto text = read_string(item, "a sensor name")) add(*text, item.location(), nullptr);
    }
  } else if (node.is_mapping()) {
    for (const auto& entry : node.entries()) add(entry.key, entry.key_location, &entry.value);
  } else {
    auto& error = diagnostics_.error(
        node.location(), "wrong-type",
        fmt::format("'sensors' must be a list of actuator names or a mapping from actuator "
                    "names to their types, found {}",
                    node.describe()));
    if (node.is_scalar()) {
      error.notes.push_back(fmt::format("write [{}] for a list of one", node.text()));
    }
  }
}

std::vector<std::string> ModelBuilder::actuator_names() const {
  std::vector<std::string> names;
  for (const auto& [name, info] : actuator_index_) names.push_back(name);
  return names;
}

std::vector<PortBinding> ModelBuilder::bind_ports(const ClassInfo& cls, const Node* ports,
                                                  const LayerDecl& layer, const std::string& owner,
                                                  const SourceLocation& owner_at) {
  std::vector<PortBinding> bindings;
  if (ports != nullptr && ports->reads_as_null()) ports = nullptr;
  if (ports != nullptr && !ports->is_mapping()) {
    diagnostics_.error(ports->location(), "wrong-type",
                       fmt::format("'ports' must map port names to sensors or actuators, "
                                   "found {}",
                                   ports->describe()));
    ports = nullptr;
  }
  if (ports != nullptr) {
    std::vector<std::string> declared;
    for (const auto& spec : cls.ports) declared.push_back(spec.name);
    for (const auto& entry : ports->entries()) {
      if (cls.find_port(entry.key) == nullptr) {
        diagnostics_
            .error(entry.key_location, "unknown-port",
                   fmt::format("unknown port '{}' for {} ({})", entry.key, owner, cls.name))
            .unknown_name(entry.key, declared, fmt::format("{} declares no ports", cls.name));
      }
    }
  }
  for (const auto& spec : cls.ports) {
    PortBinding binding;
    binding.port = &spec;
    binding.location = owner_at;
    const Node* explicit_target = ports != nullptr ? ports->find(spec.name) : nullptr;
    std::string target = spec.name;
    if (explicit_target != nullptr) {
      auto text = read_string(*explicit_target, "a sensor or actuator name");
      if (!text) continue;
      target = *text;
      binding.location = explicit_target->location();
    }
    const bool input = spec.direction == PortDirection::kInput;
    bool found = false;
    if (input) {
      for (const auto& sensor : layer.sensors) found = found || sensor.text == target;
    } else {
      for (const auto& actuator : layer.actuators) found = found || actuator.name.text == target;
    }
    if (!found) {
      if (spec.optional && explicit_target == nullptr) {
        bindings.push_back(binding);  // unbound
        continue;
      }
      // Declared but rejected (a bad sensor entry, a duplicate actuator): already reported.
      if (declared_but_invalid(target, input, layer)) continue;
      // A misspelt sensor is the one mistake: the ports that read what it meant are notes.
      if (input && fold_into_misspelt_sensor(target, layer, owner, spec.name)) continue;
      std::vector<std::string> candidates;
      if (input) {
        for (const auto& sensor : layer.sensors) candidates.push_back(sensor.text);
      } else {
        for (const auto& actuator : layer.actuators) candidates.push_back(actuator.name.text);
      }
      auto& error = diagnostics_.error(
          binding.location, "unbound-port",
          fmt::format("{} port '{}' of {} ({}) binds to '{}', which is not {} of {}",
                      input ? "input" : "output", spec.name, owner, cls.name, target,
                      input ? "a sensor" : "an actuator", layer_label(layer)));
      if (const auto other = actuator_index_.find(target); other != actuator_index_.end()) {
        error.notes.push_back(
            input ? fmt::format("'{}' is an actuator of layer '{}': list it under this "
                                "layer's 'sensors:' to read it",
                                target, other->second.layer)
                  : fmt::format("'{}' is an actuator of layer '{}'; a behaviour writes only to "
                                "actuators of its own layer",
                                target, other->second.layer));
      } else {
        error.unknown_name(target, candidates);
      }
      if (explicit_target == nullptr) {
        error.notes.push_back(fmt::format("bind it with 'ports: {{{}: NAME}}'", spec.name));
      }
      continue;
    }
    const auto& actuator = actuator_index_.at(target);
    const ValueType* port_type = registry_.value_type_of(*spec.cpp_type);
    if (actuator.type != nullptr && port_type != actuator.type) {
      // The declaration is the one place to change for every port, or each port's class: one
      // error there, each port that disagrees a note.
      auto [mismatch, first] = type_mismatches_.try_emplace(target, diagnostics_.items().size());
      if (first) {
        diagnostics_.error(actuator.location, "type-mismatch",
                           fmt::format("actuator '{}' has type '{}', but a port bound to it has "
                                       "another",
                                       target, actuator.type->name));
      }
      diagnostics_.at(mismatch->second)
          .notes.push_back(
              {fmt::format("port '{}' of {} ({}) at {} {} it as '{}'{}", spec.name, owner, cls.name,
                           to_string(binding.location), input ? "reads" : "writes",
                           registry_.value_type_name(*spec.cpp_type),
                           input ? fmt::format(" (sensor '{}')", target) : ""),
               binding.location});
      continue;
    }
    binding.target = target;
    bindings.push_back(binding);
  }
  return bindings;
}

bool ModelBuilder::fold_into_misspelt_sensor(const std::string& target, const LayerDecl& layer,
                                             const std::string& owner, const std::string& port) {
  const PendingLayer& pending =
      pending_layers_[static_cast<std::size_t>(&layer - model_.layers.data())];
  for (const auto& [meant, index] : pending.misspelt_sensors) {
    if (meant != target) continue;
    diagnostics_.at(index).notes.push_back(
        fmt::format("{} reads '{}' through its port '{}'", owner, target, port));
    return true;
  }
  return false;
}

bool ModelBuilder::declared_but_invalid(const std::string& name, bool input,
                                        const LayerDecl& layer) const {
  const PendingLayer& pending =
      pending_layers_[static_cast<std::size_t>(&layer - model_.layers.data())];
  const Node* list = input ? pending.sensors : nullptr;
  if (list == nullptr) return false;
  for (const auto& item : list->items()) {
    if (item.is_scalar() && item.text() == name) return true;
  }
  for (const auto& entry : list->entries()) {
    if (entry.key == name) return true;
  }
  return false;
}

void ModelBuilder::note_misplaced_keys(
    const ClassInfo& cls, const std::vector<std::pair<std::string, std::size_t>>& keys) {
  for (const auto& [key, index] : keys) {
    for (const auto& param : cls.params) {
      if (param.name != key) continue;
      diagnostics_.at(index).notes.push_back(
          fmt::format("'{}' is a param of {}: write it under 'params:', as in "
                      "'params: {{{}: ...}}'",
                      key, cls.name, key));
    }
    for (const auto& port : cls.ports) {
      if (port.name != key) continue;
      diagnostics_.at(index).notes.push_back(
          fmt::format("'{}' is a port of {}: bind it under 'ports:', as in 'ports: {{{}: ...}}'",
                      key, cls.name, key));
    }
  }
}

void ModelBuilder::read_behaviours(const Node& node, LayerDecl& layer, PendingLayer& pending) {
  if (node.reads_as_null()) return;
  if (!node.is_mapping()) {
    diagnostics_.error(node.location(), "wrong-type",
                       fmt::format("'behaviours' must be a mapping from names to "
                                   "{{type: ...}}, found {}",
                                   node.describe()));
    return;
  }
  for (const auto& entry : node.entries()) {
    pending.behaviour_names.push_back(entry.key);
    // The Document hands out a location as a new SourceLocation each time: once here.
    const SourceLocation where = entry.key_location;
    check_identifier(entry.key, where, "a behaviour");
    BehaviourDecl behaviour;
    behaviour.name = {entry.key, where};
    behaviour.location = where;
    const std::string owner = fmt::format("behaviour '{}'", entry.key);
    const Node* type = nullptr;
    const Node* params = nullptr;
    const Node* ports = nullptr;
    std::vector<std::pair<std::string, std::size_t>> misplaced;
    if (entry.value.is_scalar() && !entry.value.reads_as_null()) {
      type = &entry.value;  // short form `name: Class`
    } else {
      Fields fields(entry.value, owner, {"type", "params", "ports", "on_exception"}, diagnostics_,
                    "a class name or a mapping {type: ..., params: ..., ports: ...}");
      if (!fields.ok()) continue;
      type = fields.required("type");
      params = fields.optional("params");
      ports = fields.optional("ports");
      misplaced = fields.unknown();
      if (const Node* policy = fields.optional("on_exception")) {
        behaviour.on_exception = read_fault_policy(*policy);
      }
    }
    if (type == nullptr) continue;
    behaviour.cls = read_class(*type, ClassKind::kBehaviour, owner);
    if (behaviour.cls == nullptr) continue;
    note_misplaced_keys(*behaviour.cls, misplaced);
    misplaced_ = &misplaced;
    behaviour.params = read_params(*behaviour.cls, params, where, owner);
    misplaced_ = nullptr;
    behaviour.ports = bind_ports(*behaviour.cls, ports, layer, owner, where);
    layer.behaviours.push_back(std::move(behaviour));
  }
}

}  // namespace arbiter::detail
