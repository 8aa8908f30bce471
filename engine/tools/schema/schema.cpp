#include "arbiter/schema.hpp"

#include <fmt/format.h>
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include <stdexcept>

#include "arbiter/lint.hpp"
#include "arbiter/model.hpp"
#include "tools/dump/param_json.hpp"

namespace arbiter {

namespace detail {
// schema/arbiter.schema.json, compiled in by engine/CMakeLists.txt (schema_text.cpp).
extern const char* const kConfigSchema;
}  // namespace detail

namespace {

using Json = nlohmann::ordered_json;

const char* const kIdentifierPattern = "^[a-z_][a-z0-9_]*$";

/// A number as JSON: integral values in the param's own kind.
Json bound(double value, ParamKind kind) {
  if (kind == ParamKind::kInt && std::floor(value) == value && std::abs(value) < 9.0e15) {
    return static_cast<std::int64_t>(value);
  }
  return value;
}

Json number_schema(const ParamSpec& spec, const char* type) {
  Json out = {{"type", type}};
  if (spec.minimum) out["minimum"] = bound(*spec.minimum, spec.kind);
  if (spec.maximum) out["maximum"] = bound(*spec.maximum, spec.kind);
  return out;
}

/// Any scalar, as the engine reads a string from one (`label: 5` is "5"). Spelled as anyOf:
/// ajv's strict mode refuses union types other than with "null".
Json scalar_schema(const std::string& title) {
  return {{"title", title},
          {"anyOf", Json::array({{{"title", "Text"}, {"type", "string"}},
                                 {{"title", "Number"}, {"type", "number"}},
                                 {{"title", "Boolean"}, {"type", "boolean"}}})}};
}

Json vector_schema(std::size_t size) {
  return {{"type", "array"},
          {"items", {{"title", "Coordinate"}, {"type", "number"}}},
          {"minItems", size},
          {"maxItems", size}};
}

/// The schema a class gave a param (ParamSpec::schema); a programming error when it is not JSON.
Json class_param_schema(const ClassInfo& cls, const ParamSpec& spec) {
  Json out = Json::parse(spec.json_schema, nullptr, /*allow_exceptions=*/false);
  if (out.is_discarded() || !out.is_object()) {
    throw std::invalid_argument(
        fmt::format("the JSON Schema that class '{}' gives its param '{}' is not a JSON object",
                    cls.name, spec.name));
  }
  return out;
}

Json param_schema(const ClassInfo& cls, const ParamSpec& spec) {
  Json out;
  switch (spec.kind) {
    case ParamKind::kBool:
      out = {{"type", "boolean"}};
      break;
    case ParamKind::kInt:
      out = number_schema(spec, "integer");
      break;
    case ParamKind::kDouble:
      out = number_schema(spec, "number");
      break;
    case ParamKind::kString:
      out = spec.choices.empty() ? scalar_schema(spec.name) : Json{{"enum", spec.choices}};
      break;
    case ParamKind::kVec2:
      out = vector_schema(2);
      break;
    case ParamKind::kVec3:
      out = vector_schema(3);
      break;
    case ParamKind::kDoubleList: {
      // A single number stands for a list of one.
      Json item = number_schema(spec, "number");
      item["title"] = "Number";
      Json list = {
          {"title", "List of numbers"}, {"type", "array"}, {"minItems", 1}, {"items", item}};
      out = {{"anyOf", Json::array({item, std::move(list)})}};
      if (spec.by_step) {
        Json held = {
            {"title", "Level from a step on"},
            {"type", "object"},
            {"required", {"from", "level"}},
            {"additionalProperties", false},
            {"properties",
             {{"from",
               {{"title", "From step"}, {"type", "integer"}, {"minimum", 1}, {"maximum", 1 << 20}}},
              {"level", item}}}};
        out["anyOf"].push_back({{"title", "Levels by step"},
                                {"type", "array"},
                                {"minItems", 1},
                                {"items", std::move(held)}});
      }
      break;
    }
    case ParamKind::kStringList:
      out = {{"type", "array"}, {"items", scalar_schema("Item")}};
      break;
    case ParamKind::kAny:
      out = Json::object();
      break;
  }
  if (!spec.json_schema.empty()) out = class_param_schema(cls, spec);
  if (!out.contains("title")) {
    Json titled = {{"title", spec.name}};
    titled.update(out);
    out = std::move(titled);
  }
  if (!spec.description.empty() && !out.contains("description")) {
    out["description"] = spec.description;
  }
  if (spec.default_value) {
    if (Json json = detail::param_json(*spec.default_value); !json.is_null()) {
      out["default"] = std::move(json);
    }
  }
  return out;
}

/// `params:` of one class. Required params are required only where they must be given with the
/// instance (behaviours and interfaces; a state's may come per queue entry).
Json params_schema(const ClassInfo& cls, bool require) {
  Json properties = Json::object();
  Json required = Json::array();
  for (const auto& spec : cls.params) {
    properties[spec.name] = param_schema(cls, spec);
    if (require && spec.required()) required.push_back(spec.name);
  }
  Json out = {{"title", "Params of " + cls.name},
              {"type", required.empty() ? Json::array({"object", "null"}) : Json("object")},
              {"additionalProperties", false},
              {"properties", std::move(properties)}};
  if (!required.empty()) out["required"] = std::move(required);
  return out;
}

Json ports_schema(const ClassInfo& cls, const Registry& registry) {
  Json properties = Json::object();
  for (const auto& port : cls.ports) {
    const bool input = port.direction == PortDirection::kInput;
    std::string description = std::string(input ? "input" : "output") + " port (" +
                              registry.value_type_name(*port.cpp_type) + "), bound to " +
                              (input ? "a sensor" : "an actuator") +
                              " of this layer; default: the one named '" + port.name + "'";
    if (port.optional) description += " if there is one";
    if (!port.description.empty()) description += ". " + port.description;
    properties[port.name] = {{"title", port.name},
                             {"type", "string"},
                             {"pattern", kIdentifierPattern},
                             {"maxLength", kMaxNameLength},
                             {"description", description}};
  }
  return {{"title", "Ports of " + cls.name},
          {"type", Json::array({"object", "null"})},
          {"additionalProperties", false},
          {"properties", std::move(properties)}};
}

bool needs_params(const ClassInfo& cls) {
  return std::any_of(cls.params.begin(), cls.params.end(),
                     [](const ParamSpec& spec) { return spec.required(); });
}

/// What an instance of a behaviour or interface class declares besides `type:`: its params
/// (`params:` itself is required when the class has a required param) and its ports.
Json instance_schema(const ClassInfo& cls, const Registry& registry) {
  Json out = {
      {"properties",
       {{"params", params_schema(cls, /*require=*/true)}, {"ports", ports_schema(cls, registry)}}}};
  if (needs_params(cls)) out["required"] = Json::array({"params"});
  return out;
}

/// One of the named classes, with each one's description for editors.
Json one_of_classes(const std::vector<const ClassInfo*>& classes, const std::string& what) {
  if (classes.empty()) {
    return {{"title", "Class"},
            {"type", "string"},
            {"not", Json::object()},
            {"description", "no " + what + " is registered"}};
  }
  Json choices = Json::array();
  for (const ClassInfo* cls : classes) {
    Json choice = {{"title", cls->name}, {"const", cls->name}};
    if (!cls->description.empty()) choice["description"] = cls->description;
    choices.push_back(std::move(choice));
  }
  return {{"title", "Class"}, {"anyOf", std::move(choices)}};
}

/// `if` the object's `key` is `name` `then` ...
Json when(const char* key, const std::string& name, Json then) {
  return {{"if", {{"properties", {{key, {{"const", name}}}}}, {"required", Json::array({key})}}},
          {"then", std::move(then)}};
}

std::vector<const ClassInfo*> classes_of(const Registry& registry, ClassKind kind) {
  std::vector<const ClassInfo*> out;
  for (const auto& [key, info] : registry.classes()) {
    if (info->kind == kind) out.push_back(info.get());
  }
  return out;
}

Json parse_base() {
  Json schema = Json::parse(detail::kConfigSchema);
  Json codes = Json::array();
  for (const auto& lint : lint_codes()) codes.push_back(std::string(lint.code));
  schema["definitions"]["lint"]["properties"]["ignore"]["items"]["enum"] = std::move(codes);
  return schema;
}

}  // namespace

std::string config_schema() {
  return parse_base().dump(2) + "\n";
}

std::string config_schema(const Registry& registry) {
  Json schema = parse_base();
  schema["title"] = "Arbiter config, with the registered classes";
  Json& definitions = schema["definitions"];

  Json types = Json::array();
  Json averaged = Json::array();
  for (const auto& type : registry.value_types()) {
    types.push_back(type->name);
    if (type->aggregatable()) averaged.push_back(type->name);
  }
  definitions["value_type"] = {{"title", definitions["value_type"]["title"]},
                               {"enum", types},
                               {"description", definitions["value_type"]["description"]}};
  definitions["actuator"]["anyOf"][1]["if"] = {{"properties", {{"aggregate", {{"const", true}}}}},
                                               {"required", Json::array({"aggregate"})}};
  definitions["actuator"]["anyOf"][1]["then"] = {
      {"properties", {{"type", {{"title", "Value type that averages"}, {"enum", averaged}}}}}};

  const auto behaviours = classes_of(registry, ClassKind::kBehaviour);
  std::vector<const ClassInfo*> short_behaviours;
  Json behaviour_rules = Json::array();
  for (const ClassInfo* cls : behaviours) {
    if (!needs_params(*cls)) short_behaviours.push_back(cls);
    behaviour_rules.push_back(when("type", cls->name, instance_schema(*cls, registry)));
  }
  definitions["behaviour_class"] = one_of_classes(behaviours, "behaviour class");
  definitions["behaviour_short_class"] =
      one_of_classes(short_behaviours, "behaviour class without required params");
  if (!behaviour_rules.empty()) {
    definitions["behaviour"]["anyOf"][1]["allOf"] = std::move(behaviour_rules);
  }

  const auto interfaces = classes_of(registry, ClassKind::kInterface);
  Json layer_rules = Json::array();
  for (const ClassInfo* cls : interfaces) {
    layer_rules.push_back(when("interface", cls->name, instance_schema(*cls, registry)));
  }
  definitions["interface_class"] = one_of_classes(interfaces, "interface class");
  if (!layer_rules.empty()) definitions["layer"]["allOf"] = std::move(layer_rules);

  const auto states = classes_of(registry, ClassKind::kState);
  Json state_rules = Json::array();
  for (const ClassInfo* cls : states) {
    state_rules.push_back(when(
        "type", cls->name, {{"properties", {{"params", params_schema(*cls, /*require=*/false)}}}}));
  }
  definitions["state_class"] = one_of_classes(states, "state class");
  definitions["state_short_class"] = definitions["state_class"];
  if (!state_rules.empty()) definitions["state"]["anyOf"][1]["allOf"] = std::move(state_rules);

  return schema.dump(2) + "\n";
}

}  // namespace arbiter
