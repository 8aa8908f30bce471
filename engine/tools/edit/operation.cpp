#include <fmt/format.h>

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "arbiter/document.hpp"
#include "arbiter/edit.hpp"

namespace arbiter {

namespace {

// Ordered: a set_param's object value is written with its keys as the request gave them.
using Json = nlohmann::ordered_json;

/// Values are written as they are quoted: bytes that are not UTF-8 are replaced, not thrown on.
std::string dump(const Json& json) {
  return json.dump(-1, ' ', false, Json::error_handler_t::replace);
}

/// The members of one request, read for its operation: the first that is missing or mistyped
/// is kept, and the operation is not applied.
class Request {
 public:
  Request(const Json& json, const std::string& op) : json_(json), op_(op) {}

  /// A name (a string that is not empty), or "".
  std::string name(const char* key) {
    const auto found = json_.find(key);
    if (found == json_.end() || !found->is_string() || found->get<std::string>().empty()) {
      lack(key, false);
      return "";
    }
    return found->get<std::string>();
  }

  /// A position (an integer from 0), or nullopt.
  std::optional<std::size_t> position(const char* key) {
    const auto found = json_.find(key);
    if (found == json_.end() || !found->is_number_unsigned()) {
      lack(key, true);
      return std::nullopt;
    }
    return found->get<std::size_t>();
  }

  /// An optional position: `absent` when the request does not give one.
  std::size_t position_or(const char* key, std::size_t absent) {
    if (!json_.contains(key)) return absent;
    return position(key).value_or(absent);
  }

  /// An optional string: "" when the request does not give one.
  std::string text_or_empty(const char* key) {
    const auto found = json_.find(key);
    if (found == json_.end()) return "";
    if (!found->is_string()) {
      mistyped(key, "a string");
      return "";
    }
    return found->get<std::string>();
  }

  /// An optional true or false: `absent` when the request does not give one.
  bool flag_or(const char* key, bool absent) {
    const auto found = json_.find(key);
    if (found == json_.end()) return absent;
    if (!found->is_boolean()) {
      mistyped(key, "true or false");
      return absent;
    }
    return found->get<bool>();
  }

  /// A JSON value of any type, as it is to be written: JSON is a YAML flow value too, so one
  /// text serves both formats.
  std::string value(const char* key) {
    const auto found = json_.find(key);
    if (found == json_.end()) {
      lack(key, false);
      return "";
    }
    return dump(*found);
  }

  /// Per-instance params: an optional object of JSON values, each as it is to be written.
  std::vector<std::pair<std::string, std::string>> params(const char* key) {
    std::vector<std::pair<std::string, std::string>> params;
    const auto found = json_.find(key);
    if (found == json_.end()) return params;
    if (!found->is_object()) {
      mistyped(key, "an object of param values");
      return params;
    }
    for (const auto& [param, value] : found->items()) params.emplace_back(param, dump(value));
    return params;
  }

  /// The operations that take positions say how each kind of member is written.
  void explain_members() { explain_ = true; }

  /// Why the request is not the operation, or "" when it is.
  const std::string& invalid() const { return invalid_; }
  void set_invalid(std::string why) {
    if (invalid_.empty()) invalid_ = std::move(why);
  }

 private:
  void lack(const char* key, bool position) {
    if (!invalid_.empty()) return;
    invalid_ = explain_ || position ? fmt::format(
                                          "{} needs '{}' (names as strings, positions as "
                                          "integers from 0)",
                                          op_, key)
                                    : fmt::format("{} needs '{}'", op_, key);
  }
  void mistyped(const char* key, const char* expected) {
    set_invalid(fmt::format("{}'s '{}' is not {}", op_, key, expected));
  }

  const Json& json_;
  const std::string& op_;
  bool explain_ = false;
  std::string invalid_;
};

std::optional<SymbolKind> kind_named(const std::string& name) {
  if (name == "behaviour") return SymbolKind::kBehaviour;
  if (name == "actuator") return SymbolKind::kActuator;
  if (name == "layer") return SymbolKind::kLayer;
  if (name == "state") return SymbolKind::kState;
  if (name == "machine") return SymbolKind::kMachine;
  return std::nullopt;
}

EditResult rename(const Loaded& loaded, const ConfigIndex& index, SymbolKind kind,
                  const std::string& kind_name, const std::string& scope, const std::string& name,
                  const std::string& to) {
  for (const auto& occurrence : index.occurrences) {
    if (occurrence.definition && occurrence.kind == kind && occurrence.name == name &&
        (scope.empty() || occurrence.scope == scope))
      return rename_symbol(loaded, index, occurrence, to);
  }
  EditResult result;
  result.refused = scope.empty() ? fmt::format("no {} '{}' is declared", kind_name, name)
                                 : fmt::format("no {} '{}' in '{}'", kind_name, name, scope);
  return result;
}

/// The operation `op` of `request`, or the request's first missing or mistyped member.
OperationResult run(const Loaded& loaded, const Registry* registry, const ConfigIndex* given,
                    const Json& json, const std::string& op) {
  Request request(json, op);
  OperationResult out;
  // Computed only for the operations that read it.
  std::optional<ConfigIndex> computed;
  auto index = [&]() -> const ConfigIndex& {
    if (given) return *given;
    if (!computed) computed = index_config(loaded, registry);
    return *computed;
  };
  // Each branch reads every member before it applies anything: a request missing one is
  // refused without an edit.
  auto apply = [&](auto&& operation) {
    if (request.invalid().empty()) {
      out.result = operation();
    } else {
      out.invalid = request.invalid();
    }
    return out;
  };
  if (op == "add_inhibition" || op == "remove_inhibition" || op == "flip_chaining") {
    const InhibitionRef inhibition{request.name("layer"), request.name("inhibitor"),
                                   request.name("inhibited")};
    if (op == "add_inhibition") {
      const bool chaining = request.flag_or("chaining", true);
      return apply([&] { return add_inhibition(loaded, inhibition, chaining); });
    }
    if (op == "remove_inhibition")
      return apply([&] { return remove_inhibition(loaded, inhibition); });
    return apply([&] { return flip_chaining(loaded, inhibition); });
  }
  if (op == "set_param") {
    const std::string layer = request.name("layer");
    const std::string behaviour = request.name("behaviour");
    const std::string param = request.name("param");
    const std::string value = request.value("value");
    return apply([&] { return set_param(loaded, layer, behaviour, param, value); });
  }
  if (op == "add_behaviour" || op == "remove_behaviour") {
    const std::string layer = request.name("layer");
    const std::string name = request.name("name");
    if (op == "remove_behaviour")
      return apply([&] { return remove_behaviour(loaded, layer, name); });
    const std::string type = request.name("type");
    return apply([&] { return add_behaviour(loaded, layer, name, type); });
  }
  if (op == "rename") {
    const std::string kind_name = request.name("kind");
    const std::string name = request.name("name");
    const std::string to = request.name("to");
    const std::string scope = request.text_or_empty("scope");
    const auto kind = kind_named(kind_name);
    if (!kind && request.invalid().empty()) {
      request.set_invalid(fmt::format(
          "cannot rename a '{}': a behaviour, actuator, layer, state or machine can be renamed",
          kind_name));
    }
    return apply([&] { return rename(loaded, index(), *kind, kind_name, scope, name, to); });
  }
  // The operations added with positions say how members are written when one is missing.
  request.explain_members();
  if (op == "move_behaviour") {
    const std::string layer = request.name("layer");
    const std::string name = request.name("name");
    const auto at = request.position("index");
    const std::string to_layer = request.text_or_empty("to_layer");
    return apply([&] { return move_behaviour(loaded, layer, name, to_layer, *at); });
  }
  if (op == "move_layer") {
    const std::string layer = request.name("layer");
    const auto at = request.position("index");
    return apply([&] { return move_layer(loaded, layer, *at); });
  }
  if (op == "add_layer") {
    const std::string name = request.name("name");
    const std::size_t at = request.position_or("index", kAtEnd);
    const std::string interface = request.text_or_empty("interface");
    return apply([&] { return add_layer(loaded, name, at, interface); });
  }
  if (op == "remove_layer") {
    const std::string name = request.name("name");
    return apply([&] { return remove_layer(loaded, name); });
  }
  if (op == "add_sensor" || op == "remove_sensor") {
    const std::string layer = request.name("layer");
    const std::string name = request.name("name");
    return apply([&] {
      return op == "add_sensor" ? add_sensor(loaded, layer, name)
                                : remove_sensor(loaded, layer, name);
    });
  }
  if (op == "add_plugin") {
    const std::string name = request.name("name");
    return apply([&] { return add_plugin(loaded, name); });
  }
  if (op == "add_state_machine" || op == "remove_state_machine") {
    const std::string name = request.name("name");
    return apply([&] {
      return op == "add_state_machine" ? add_state_machine(loaded, name)
                                       : remove_state_machine(loaded, index(), name);
    });
  }
  if (op == "add_actuator" || op == "remove_actuator") {
    const std::string layer = request.name("layer");
    const std::string name = request.name("name");
    if (op == "remove_actuator") return apply([&] { return remove_actuator(loaded, layer, name); });
    const std::string type = request.name("type");
    return apply([&] { return add_actuator(loaded, layer, name, type); });
  }
  if (op == "wire_port") {
    const std::string layer = request.name("layer");
    const std::string behaviour = request.name("behaviour");
    const std::string port = request.name("port");
    const std::string target = request.name("target");
    return apply([&] { return wire_port(loaded, layer, behaviour, port, target); });
  }
  if (op == "add_queue_entry") {
    const std::string machine = request.name("machine");
    const std::string state = request.name("state");
    const auto params = request.params("params");
    const std::size_t at = request.position_or("index", kAtEnd);
    return apply([&] { return add_queue_entry(loaded, machine, state, params, at); });
  }
  if (op == "remove_queue_entry") {
    const std::string machine = request.name("machine");
    const auto at = request.position("index");
    return apply([&] { return remove_queue_entry(loaded, machine, *at); });
  }
  if (op == "add_state" || op == "remove_state") {
    const std::string machine = request.name("machine");
    const std::string name = request.name("name");
    if (op == "remove_state")
      return apply([&] { return remove_state(loaded, index(), machine, name); });
    const std::string type = request.name("type");
    return apply([&] { return add_state(loaded, machine, name, type); });
  }
  if (op == "move_queue_entry") {
    const std::string machine = request.name("machine");
    const auto from = request.position("from");
    const auto to = request.position("to");
    return apply([&] { return move_queue_entry(loaded, machine, *from, *to); });
  }
  out.invalid = fmt::format(
      "no operation '{}': add_inhibition, remove_inhibition, flip_chaining, set_param, "
      "add_behaviour, remove_behaviour, rename, move_behaviour, move_layer, add_layer, "
      "remove_layer, add_actuator, remove_actuator, add_sensor, remove_sensor, wire_port, "
      "add_plugin, add_state_machine, remove_state_machine, add_state, remove_state, "
      "add_queue_entry, remove_queue_entry or move_queue_entry",
      op);
  return out;
}

}  // namespace

OperationResult apply_operation(const Loaded& loaded, const std::string& request,
                                const Registry* registry, const ConfigIndex* index) {
  OperationResult out;
  // A value is printed again for the edit it makes, and printing a JSON tree recurses once per
  // level: a request nested 50 000 deep would overflow the stack and end the process (the
  // running robot's, under `run --serve --edit`).
  if (const auto deep = find_too_deep_json(request)) {
    out.invalid = fmt::format("the body is nested deeper than {} levels (at byte {})",
                              ReadLimits().max_depth, *deep);
    return out;
  }
  const Json json = Json::parse(request, nullptr, false);
  if (!json.is_object()) {
    out.invalid = "the body is not a JSON object";
    return out;
  }
  const auto op = json.find("op");
  if (op == json.end() || (op->is_string() && op->get<std::string>().empty())) {
    out.invalid = "an operation needs 'op'";
    return out;
  }
  if (!op->is_string()) {
    out.invalid = fmt::format("'op' is {}, not the name of an operation", op->dump());
    return out;
  }
  return run(loaded, registry, index, json, op->get<std::string>());
}

}  // namespace arbiter
