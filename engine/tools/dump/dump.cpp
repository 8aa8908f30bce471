#include "arbiter/dump.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>

#include "tools/dump/param_json.hpp"

namespace arbiter {

namespace {

/// Behaviours that write actuator `a`, in execution order (an interface's writes are not listed).
std::vector<std::uint32_t> writers_of(const Program& program, std::uint32_t a) {
  std::vector<std::uint32_t> writers;
  for (auto s = program.actuator_slot_begin[a]; s < program.actuator_slot_begin[a + 1]; ++s) {
    const auto owner = program.slots[program.actuator_slots[s]].owner;
    if (owner != kNoBehaviour) writers.push_back(owner);
  }
  return writers;
}

/// Layers whose sensors read actuator `a`, in layer order.
std::vector<std::uint32_t> readers_of(const Program& program, std::uint32_t a) {
  std::vector<std::uint32_t> readers;
  for (std::uint32_t l = 0; l < program.layers.size(); ++l) {
    const auto& sensors = program.layers[l].sensors;
    if (std::find(sensors.begin(), sensors.end(), a) != sensors.end()) readers.push_back(l);
  }
  return readers;
}

/// Whether layer `reader` sees last step's value of actuator `a` (docs/semantics.md, "Timing: the
/// one-step delay"): a normal layer reading an actuator of its own or a later normal layer.
bool delayed(const Program& program, std::uint32_t reader, std::uint32_t a) {
  const auto source = program.actuators[a].layer;
  return !program.layers[reader].is_interface() && !program.layers[source].is_interface() &&
         source >= reader;
}

/// The declaration behaviour `b` was compiled from, or nullptr when the program has no model.
const BehaviourDecl* declaration_of(const Program& program, std::uint32_t b) {
  if (!program.model) return nullptr;
  const auto& behaviour = program.behaviours[b];
  const LayerDecl* layer = program.model->find_layer(program.layers[behaviour.layer].name);
  if (layer == nullptr) return nullptr;
  for (const auto& declared : layer->behaviours) {
    if (declared.name.text == behaviour.name) return &declared;
  }
  return nullptr;
}

/// Behaviours of layer `l` with an input port bound to its sensor of actuator `a`, in execution
/// order (known only when the program has its model).
std::vector<std::uint32_t> sensor_readers(const Program& program, std::uint32_t l,
                                          std::uint32_t a) {
  std::vector<std::uint32_t> readers;
  const CompiledLayer& layer = program.layers[l];
  for (auto b = layer.behaviour_begin; b < layer.behaviour_end; ++b) {
    const BehaviourDecl* declared = declaration_of(program, b);
    if (declared == nullptr) continue;
    for (const auto& binding : declared->ports) {
      if (binding.port != nullptr && binding.port->direction == PortDirection::kInput &&
          binding.target == program.actuators[a].name) {
        readers.push_back(b);
        break;
      }
    }
  }
  return readers;
}

/// What steps an owned state machine: a behaviour, or a state of a parent machine.
struct Owner {
  std::uint32_t behaviour = kNoBehaviour;
  const Controller* parent = nullptr;
  std::uint32_t state = 0;
};

Owner find_owner(const Program& program, const Controller& controller) {
  Owner owner;
  owner.behaviour = controller.owner_behaviour();
  if (owner.behaviour != kNoBehaviour) return owner;
  for (const auto& other : program.controllers) {
    for (std::uint32_t s = 0; s < other->states().size(); ++s) {
      if (other->child_of(s) == &controller) {
        owner.parent = other.get();
        owner.state = s;
        return owner;
      }
    }
  }
  return owner;
}

/// `layer/behaviour` or `machine/state`; empty for a standalone machine.
std::string owner_name(const Program& program, const Owner& owner) {
  if (owner.behaviour != kNoBehaviour) {
    const auto& behaviour = program.behaviours[owner.behaviour];
    return program.layers[behaviour.layer].name + "/" + behaviour.name;
  }
  if (owner.parent != nullptr) {
    return owner.parent->name() + "/" + owner.parent->states()[owner.state].name;
  }
  return {};
}

/// "stepped by control/play", or "standalone".
std::string stepping(const Program& program, const Controller& controller) {
  if (!controller.owned()) return "standalone";
  const std::string owner = arbiter::owner_of(program, controller);
  return owner.empty() ? "stepped by its owner" : "stepped by " + owner;
}

std::vector<std::string> names_of(const Program& program, const std::vector<std::uint32_t>& ids) {
  std::vector<std::string> names;
  for (auto id : ids) names.push_back(program.behaviours[id].name);
  return names;
}

std::string join_names(const Program& program, const std::vector<std::uint32_t>& behaviours,
                       std::string_view separator) {
  std::string out;
  for (std::size_t i = 0; i < behaviours.size(); ++i) {
    if (i > 0) out += separator;
    out += program.behaviours[behaviours[i]].name;
  }
  return out;
}

}  // namespace

std::string owner_of(const Program& program, const Controller& controller) {
  return owner_name(program, find_owner(program, controller));
}

std::string dump_text(const Program& program, std::string_view only_layer) {
  std::string out =
      fmt::format("manager {} ({} Hz, {}{} layers, {} behaviours)\n", program.name, program.rate_hz,
                  program.steps > 0 ? fmt::format("{} steps, ", program.steps) : "",
                  program.layers.size(), program.behaviours.size());
  for (std::uint32_t l = 0; l < program.layers.size(); ++l) {
    const CompiledLayer& layer = program.layers[l];
    if (!only_layer.empty() && layer.name != only_layer) continue;
    out += fmt::format("\nlayer {}", layer.name);
    if (layer.is_interface()) {
      out += fmt::format(" (interface {})\n", layer.interface_class->name);
    } else {
      out += layer.normalise ? " (normalised)\n" : "\n";
      out += "  behaviours, in execution order:\n";
      for (auto b = layer.behaviour_begin; b < layer.behaviour_end; ++b) {
        out += fmt::format("    {}. {} ({})\n", b - layer.behaviour_begin + 1,
                           program.behaviours[b].name, program.behaviours[b].cls->name);
      }
      std::string declared;
      std::string implicit;
      for (const auto& inhibition : program.inhibitions) {
        if (program.behaviours[inhibition.inhibited].layer != l) continue;
        const auto& from = program.behaviours[inhibition.inhibitor].name;
        const auto& to = program.behaviours[inhibition.inhibited].name;
        if (!inhibition.implicit) {
          declared +=
              fmt::format("    {} {} {}  ({}:{})\n", from, inhibition.chaining ? "=>" : "->", to,
                          inhibition.location.line, inhibition.location.column);
        } else {
          implicit += fmt::format(
              "    {} => {}  (via {})\n", from, to,
              join_names(program, program.chain(inhibition.inhibitor, inhibition.inhibited),
                         " => "));
        }
      }
      out += "  inhibitions declared:\n";
      out += declared.empty() ? "    (none)\n" : declared;
      out += "  inhibitions implied by chaining:\n";
      out += implicit.empty() ? "    (none)\n" : implicit;
    }
    out += "  actuators:\n";
    if (layer.actuator_begin == layer.actuator_end) out += "    (none)\n";
    for (auto a = layer.actuator_begin; a < layer.actuator_end; ++a) {
      const auto& actuator = program.actuators[a];
      std::vector<std::uint32_t> writers;
      for (auto s = program.actuator_slot_begin[a]; s < program.actuator_slot_begin[a + 1]; ++s) {
        const auto owner = program.slots[program.actuator_slots[s]].owner;
        if (owner != kNoBehaviour) writers.push_back(owner);
      }
      std::string readers;
      for (const auto& other : program.layers) {
        for (auto sensor : other.sensors) {
          if (sensor == a) readers += (readers.empty() ? "" : ", ") + other.name;
        }
      }
      out += fmt::format("    {}: {}{}", actuator.name, actuator.type->name,
                         actuator.aggregate ? ", aggregate" : "");
      if (layer.is_interface()) {
        out += ", written by the interface";
      } else {
        out += writers.empty() ? ", no writers"
                               : fmt::format(", written by {}", join_names(program, writers, ", "));
      }
      out += readers.empty() ? ", read by no layer\n" : fmt::format(", read by {}\n", readers);
    }
    out += "  sensors:";
    if (layer.sensors.empty()) out += " (none)";
    for (std::size_t i = 0; i < layer.sensors.size(); ++i) {
      const auto& actuator = program.actuators[layer.sensors[i]];
      const auto readers = sensor_readers(program, l, layer.sensors[i]);
      out += fmt::format("{} {} (from {}{})", i == 0 ? "" : ",", actuator.name,
                         program.layers[actuator.layer].name,
                         readers.empty() ? "" : ", read by " + join_names(program, readers, ", "));
    }
    out += "\n";
  }
  if (!only_layer.empty()) return out;
  for (const auto& controller : program.controllers) {
    out += fmt::format("\nstate machine {} (capacity {}, {})\n", controller->name(),
                       controller->capacity(), stepping(program, *controller));
    out += "  states:\n";
    for (std::uint32_t s = 0; s < controller->states().size(); ++s) {
      const auto& state = controller->states()[s];
      out += fmt::format("    {} ({})", state.name, state.cls->name);
      if (const Controller* child = controller->child_of(s)) {
        out += fmt::format(", steps state machine {}", child->name());
      }
      out += "\n";
    }
    out += "  initial queue:";
    if (controller->queue_size() == 0) out += " (empty)";
    for (std::size_t i = 0; i < controller->queue_size(); ++i) {
      out += fmt::format("{} {}", i == 0 ? "" : ",", controller->queued(i));
    }
    out += "\n";
  }
  return out;
}

namespace {

/// A DOT string literal; a newline becomes a line break of the label.
std::string quote(std::string_view text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

std::string behaviour_id(const Program& program, std::uint32_t b) {
  return quote("b:" + program.layers[program.behaviours[b].layer].name + "/" +
               program.behaviours[b].name);
}

std::string actuator_id(const Program& program, std::uint32_t a) {
  return quote("a:" + program.actuators[a].name);
}

std::string sensor_id(const Program& program, std::uint32_t layer, std::uint32_t a) {
  return quote("s:" + program.layers[layer].name + "/" + program.actuators[a].name);
}

std::string state_id(const Controller& controller, std::uint32_t state) {
  return quote("m:" + controller.name() + "/" + controller.states()[state].name);
}

void dot_layer(const Program& program, std::uint32_t l, std::string& out) {
  const CompiledLayer& layer = program.layers[l];
  out += fmt::format("  subgraph {} {{\n", quote("cluster_layer_" + layer.name));
  out += fmt::format(
      "    label={};\n",
      quote(layer.is_interface()
                ? fmt::format("layer {} (interface {})", layer.name, layer.interface_class->name)
                : fmt::format("layer {}{}", layer.name, layer.normalise ? " (normalised)" : "")));
  out += "    style=\"rounded\";\n    color=\"gray50\";\n";
  for (auto b = layer.behaviour_begin; b < layer.behaviour_end; ++b) {
    out += fmt::format(
        "    {} [label={}, shape=box, style=\"rounded\"];\n", behaviour_id(program, b),
        quote(fmt::format("{}. {}\n{}", b - layer.behaviour_begin + 1, program.behaviours[b].name,
                          program.behaviours[b].cls->name)));
  }
  for (auto a = layer.actuator_begin; a < layer.actuator_end; ++a) {
    const auto& actuator = program.actuators[a];
    out +=
        fmt::format("    {} [label={}, shape=cds, style=\"filled\", fillcolor=\"lightyellow\"];\n",
                    actuator_id(program, a),
                    quote(fmt::format("{}\n{}{}", actuator.name, actuator.type->name,
                                      actuator.aggregate ? ", aggregate" : "")));
  }
  for (auto a : layer.sensors) {
    out += fmt::format(
        "    {} [label={}, shape=invhouse, style=\"filled\", fillcolor=\"honeydew\"];\n",
        sensor_id(program, l, a), quote(program.actuators[a].name));
  }
  out += "  }\n";
}

void dot_layer_edges(const Program& program, std::uint32_t l, bool external_sources,
                     std::string& out) {
  const CompiledLayer& layer = program.layers[l];
  for (const auto& inhibition : program.inhibitions) {
    if (program.behaviours[inhibition.inhibited].layer != l) continue;
    const auto& from = program.behaviours[inhibition.inhibitor].name;
    const auto& to = program.behaviours[inhibition.inhibited].name;
    std::string style;
    if (inhibition.implicit) {
      std::string via;
      for (const auto& name :
           names_of(program, program.chain(inhibition.inhibitor, inhibition.inhibited))) {
        via += (via.empty() ? "" : " => ") + name;
      }
      style = fmt::format("style=\"dashed\", color=\"gray40\", tooltip={}",
                          quote(fmt::format("implicit: {}", via)));
    } else if (inhibition.chaining) {
      style = fmt::format("color=\"black:invis:black\", tooltip={}",
                          quote(fmt::format("{} => {}", from, to)));
    } else {
      style = fmt::format("tooltip={}", quote(fmt::format("{} -> {}", from, to)));
    }
    out += fmt::format("  {} -> {} [{}];\n", behaviour_id(program, inhibition.inhibitor),
                       behaviour_id(program, inhibition.inhibited), style);
  }
  for (auto a = layer.actuator_begin; a < layer.actuator_end; ++a) {
    for (auto writer : writers_of(program, a)) {
      out += fmt::format("  {} -> {} [color=\"steelblue\", arrowhead=\"vee\"];\n",
                         behaviour_id(program, writer), actuator_id(program, a));
    }
  }
  for (auto a : layer.sensors) {
    if (external_sources && program.actuators[a].layer != l) {
      const auto& actuator = program.actuators[a];
      out += fmt::format(
          "  {} [label={}, shape=cds, style=\"dashed\"];\n", actuator_id(program, a),
          quote(fmt::format("{}\nlayer {}", actuator.name, program.layers[actuator.layer].name)));
    }
    const bool late = delayed(program, l, a);
    out += fmt::format("  {} -> {} [color=\"darkgreen\"{}];\n", actuator_id(program, a),
                       sensor_id(program, l, a),
                       late ? ", style=\"dashed\", constraint=false, label=\"last step\"" : "");
    for (auto reader : sensor_readers(program, l, a)) {
      out += fmt::format("  {} -> {} [color=\"darkgreen\", arrowhead=\"vee\"];\n",
                         sensor_id(program, l, a), behaviour_id(program, reader));
    }
  }
}

/// The states of `controller` in the order of its initial queue, then the others as declared.
std::vector<std::uint32_t> states_in_queue_order(const Controller& controller) {
  std::vector<std::uint32_t> order;
  const auto add = [&](std::uint32_t s) {
    if (std::find(order.begin(), order.end(), s) == order.end()) order.push_back(s);
  };
  for (std::size_t i = 0; i < controller.queue_size(); ++i) {
    for (std::uint32_t s = 0; s < controller.states().size(); ++s) {
      if (controller.states()[s].name == controller.queued(i)) add(s);
    }
  }
  for (std::uint32_t s = 0; s < controller.states().size(); ++s) add(s);
  return order;
}

void dot_controller(const Program& program, const Controller& controller, std::string& out) {
  out += fmt::format("  subgraph {} {{\n", quote("cluster_machine_" + controller.name()));
  out += fmt::format("    label={};\n",
                     quote(fmt::format("state machine {} ({}, capacity {})", controller.name(),
                                       stepping(program, controller), controller.capacity())));
  out += "    style=\"rounded,dashed\";\n    color=\"gray50\";\n";
  for (auto s : states_in_queue_order(controller)) {
    const auto& state = controller.states()[s];
    out += fmt::format("    {} [label={}, shape=ellipse];\n", state_id(controller, s),
                       quote(fmt::format("{}\n{}", state.name, state.cls->name)));
  }
  std::string queue = "{initial queue";
  for (std::size_t i = 0; i < controller.queue_size(); ++i) {
    queue += fmt::format("|{}. {}", i + 1, controller.queued(i));
  }
  if (controller.queue_size() == 0) queue += "|(empty)";
  queue += "}";
  out +=
      fmt::format("    {} [label={}, shape=record, style=\"filled\", fillcolor=\"whitesmoke\"];\n",
                  quote("q:" + controller.name()), quote(queue));
  out += "  }\n";
}

/// The edge from what steps a machine (`from`, a node id) into the machine's cluster.
std::string steps_edge(const std::string& from, const Controller& child) {
  return fmt::format("  {} -> {} [lhead={}, style=\"bold\", label=\"steps\"];\n", from,
                     state_id(child, states_in_queue_order(child).front()),
                     quote("cluster_machine_" + child.name()));
}

void dot_controller_edges(const Program& program, const Controller& controller, std::string& out) {
  // The initial queue, state to state: the order the machine runs them in.
  std::optional<std::uint32_t> previous;
  for (std::size_t i = 0; i < controller.queue_size(); ++i) {
    for (std::uint32_t s = 0; s < controller.states().size(); ++s) {
      if (controller.states()[s].name != controller.queued(i)) continue;
      if (previous) {
        out += fmt::format("  {} -> {} [style=\"dotted\", label=\"then\"];\n",
                           state_id(controller, *previous), state_id(controller, s));
      }
      previous = s;
    }
  }
  if (controller.owner_behaviour() != kNoBehaviour && !controller.states().empty()) {
    out += steps_edge(behaviour_id(program, controller.owner_behaviour()), controller);
  }
  for (std::uint32_t s = 0; s < controller.states().size(); ++s) {
    const Controller* child = controller.child_of(s);
    if (child == nullptr || child->states().empty()) continue;
    out += steps_edge(state_id(controller, s), *child);
  }
}

using Json = nlohmann::ordered_json;

// The graph of a large config has tens of thousands of these objects: each is built key by key,
// its values moved in, rather than from an initializer list, which builds every pair as an array
// first and copies what it is not given as a temporary (a studio edit waits for the dump).
Json location_json(const SourceLocation& location) {
  Json out = Json::object();
  out["file"] = location.file;
  out["line"] = location.line;
  out["column"] = location.column;
  return out;
}

/// A value as written in the config: numbers, booleans and null as such, other scalars as
/// strings.
Json node_json(const Node& node) {
  if (node.is_mapping()) {
    Json object = Json::object();
    for (const auto& entry : node.entries()) object[entry.key] = node_json(entry.value);
    return object;
  }
  if (node.is_sequence()) {
    Json array = Json::array();
    for (const auto& item : node.items()) array.push_back(node_json(item));
    return array;
  }
  if (!node.quoted()) {
    if (node.reads_as_null()) return Json();
    if (auto value = node.as_bool()) return *value;
    if (auto value = node.as_int()) return *value;
    if (auto value = node.as_double()) return std::isfinite(*value) ? Json(*value) : Json();
  }
  return node.text();
}

/// {param: value}, in the class's order, defaults included.
Json params_json(const ParamSet& params) {
  Json out = Json::object();
  for (const auto& param : params.items) {
    out[param.name] = std::holds_alternative<Node>(param.value)
                          ? node_json(std::get<Node>(param.value))
                          : detail::param_json(param.value);
  }
  return out;
}

/// {port: the sensor or actuator it is bound to, or null}.
Json ports_json(const std::vector<PortBinding>& ports) {
  Json out = Json::object();
  for (const auto& binding : ports) {
    if (binding.port == nullptr) continue;
    out[binding.port->name] = binding.target.empty() ? Json() : Json(binding.target);
  }
  return out;
}

Json layer_json(const Program& program, std::uint32_t l) {
  const CompiledLayer& layer = program.layers[l];
  // The layer's declarations by name, looked up once per behaviour.
  std::unordered_map<std::string_view, const BehaviourDecl*> declarations;
  if (const LayerDecl* declared = program.model ? program.model->find_layer(layer.name) : nullptr) {
    for (const auto& behaviour : declared->behaviours) {
      declarations.emplace(behaviour.name.text, &behaviour);
    }
  }
  Json behaviours = Json::array();
  for (auto b = layer.behaviour_begin; b < layer.behaviour_end; ++b) {
    const auto& behaviour = program.behaviours[b];
    const auto found = declarations.find(behaviour.name);
    const BehaviourDecl* declared = found == declarations.end() ? nullptr : found->second;
    Json item = Json::object();
    item["name"] = behaviour.name;
    item["class"] = behaviour.cls->name;
    item["order"] = b - layer.behaviour_begin + 1;
    item["params"] = declared ? params_json(declared->params) : Json();
    item["ports"] = declared ? ports_json(declared->ports) : Json();
    item["location"] = location_json(behaviour.location);
    behaviours.push_back(std::move(item));
  }
  Json inhibitions = Json::array();
  for (const auto& inhibition : program.inhibitions) {
    if (program.behaviours[inhibition.inhibited].layer != l) continue;
    Json item = Json::object();
    item["inhibitor"] = program.behaviours[inhibition.inhibitor].name;
    item["inhibited"] = program.behaviours[inhibition.inhibited].name;
    item["chaining"] = inhibition.chaining;
    item["implicit"] = inhibition.implicit;
    if (inhibition.implicit) {
      item["via"] = names_of(program, program.chain(inhibition.inhibitor, inhibition.inhibited));
    } else {
      item["location"] = location_json(inhibition.location);
    }
    inhibitions.push_back(std::move(item));
  }
  Json actuators = Json::array();
  for (auto a = layer.actuator_begin; a < layer.actuator_end; ++a) {
    const auto& actuator = program.actuators[a];
    Json readers = Json::array();
    for (auto reader : readers_of(program, a)) readers.push_back(program.layers[reader].name);
    actuators.push_back({{"name", actuator.name},
                         {"type", actuator.type->name},
                         {"aggregate", actuator.aggregate},
                         {"writers", names_of(program, writers_of(program, a))},
                         {"readers", std::move(readers)},
                         {"location", location_json(actuator.location)}});
  }
  Json sensors = Json::array();
  for (auto a : layer.sensors) {
    sensors.push_back({{"name", program.actuators[a].name},
                       {"layer", program.layers[program.actuators[a].layer].name},
                       {"last_step", delayed(program, l, a)},
                       {"readers", names_of(program, sensor_readers(program, l, a))}});
  }
  // An interface layer's class has params and ports as a behaviour has.
  const LayerDecl* declared = program.model ? program.model->find_layer(layer.name) : nullptr;
  const bool bound = layer.is_interface() && declared != nullptr;
  return {{"name", layer.name},
          {"interface", layer.is_interface() ? Json(layer.interface_class->name) : Json()},
          {"params", bound ? params_json(declared->params) : Json()},
          {"ports", bound ? ports_json(declared->ports) : Json()},
          {"normalise", layer.normalise},
          {"location", location_json(layer.location)},
          {"behaviours", std::move(behaviours)},
          {"inhibitions", std::move(inhibitions)},
          {"actuators", std::move(actuators)},
          {"sensors", std::move(sensors)}};
}

Json controller_json(const Program& program, const Controller& controller) {
  Json states = Json::array();
  for (std::uint32_t s = 0; s < controller.states().size(); ++s) {
    const auto& state = controller.states()[s];
    const Controller* child = controller.child_of(s);
    const StateDecl* declared = nullptr;
    for (std::size_t m = 0; program.model && m < program.model->state_machines.size(); ++m) {
      const auto& machine = program.model->state_machines[m];
      if (machine.name.text != controller.name()) continue;
      for (const auto& candidate : machine.states) {
        if (candidate.name.text == state.name) declared = &candidate;
      }
    }
    states.push_back({{"name", state.name},
                      {"class", state.cls->name},
                      {"params", declared ? params_json(declared->params) : Json()},
                      {"machine", child != nullptr ? Json(child->name()) : Json()},
                      {"location", location_json(state.location)}});
  }
  Json queue = Json::array();
  for (std::size_t i = 0; i < controller.queue_size(); ++i) {
    queue.push_back(std::string(controller.queued(i)));
  }
  const std::string owner = arbiter::owner_of(program, controller);
  return {{"name", controller.name()},
          {"standalone", !controller.owned()},
          {"owner", owner.empty() ? Json() : Json(owner)},
          {"capacity", controller.capacity()},
          {"location", location_json(controller.location())},
          {"states", std::move(states)},
          {"queue", std::move(queue)}};
}

}  // namespace

std::string dump_dot(const Program& program, std::string_view only_layer) {
  std::string out = fmt::format("digraph {} {{\n", quote(program.name));
  out += fmt::format(
      "  graph [label={}, labelloc=\"t\", fontname=\"Helvetica\", fontsize=12, compound=true, "
      "newrank=true];\n",
      quote(fmt::format("{} ({} Hz)\ndouble: chaining inhibition, single: non-chaining, "
                        "dashed: implied by chaining\nblue: writes, green: actuator to sensor",
                        program.name, program.rate_hz)));
  out += "  node [fontname=\"Helvetica\", fontsize=11];\n";
  out += "  edge [fontname=\"Helvetica\", fontsize=9];\n";
  for (std::uint32_t l = 0; l < program.layers.size(); ++l) {
    if (!only_layer.empty() && program.layers[l].name != only_layer) continue;
    dot_layer(program, l, out);
  }
  for (std::uint32_t l = 0; l < program.layers.size(); ++l) {
    if (!only_layer.empty() && program.layers[l].name != only_layer) continue;
    dot_layer_edges(program, l, !only_layer.empty(), out);
  }
  if (only_layer.empty()) {
    for (const auto& controller : program.controllers) dot_controller(program, *controller, out);
    for (const auto& controller : program.controllers) {
      dot_controller_edges(program, *controller, out);
    }
  }
  out += "}\n";
  return out;
}

std::string dump_json(const Program& program, std::string_view only_layer, int indent) {
  Json layers = Json::array();
  for (std::uint32_t l = 0; l < program.layers.size(); ++l) {
    if (!only_layer.empty() && program.layers[l].name != only_layer) continue;
    layers.push_back(layer_json(program, l));
  }
  Json machines = Json::array();
  if (only_layer.empty()) {
    for (const auto& controller : program.controllers) {
      machines.push_back(controller_json(program, *controller));
    }
  }
  Json dump = {{"arbiter_dump", 1}, {"name", program.name}, {"rate_hz", program.rate_hz}};
  if (program.steps > 0) dump["steps"] = program.steps;
  dump["layers"] = std::move(layers);
  dump["state_machines"] = std::move(machines);
  return dump.dump(indent) + "\n";
}

}  // namespace arbiter
