// Completion and hover: where the cursor is in the config's tree, and what the schema and the
// registry's classes offer there.

#include <fmt/format.h>

#include <algorithm>
#include <set>

#include "lsp/analysis.hpp"
#include "lsp/server.hpp"

namespace arbiter::lsp {

namespace {

/// Where the cursor is in the config's tree: the path of keys (sequence items as "*") to the
/// mapping or sequence that holds it, and whether a key, a value (of `key`) or an item is typed.
struct Context {
  enum class At { kKey, kValue, kItem } at = At::kKey;
  std::vector<std::string> path;
  std::string key;
  std::size_t word_begin = 0;
  /// The `type:` written in the flow mapping that holds the cursor's `params:` mapping, for a
  /// behaviour or state the last config that parsed did not have yet.
  std::string type;
};

/// Scans flow text (JSON, or a YAML flow collection) from `begin` to `end` into `context`.
void scan_flow(const std::string& text, std::size_t begin, std::size_t end, Context& context) {
  struct Frame {
    bool object;
    std::string key;
    bool after_colon = false;
    std::string type;  // the value of this mapping's `type:`
  };
  std::vector<Frame> frames;
  std::string last_string;
  for (std::size_t i = begin; i < end; ++i) {
    const char c = text[i];
    if (c == '"' || c == '\'') {
      std::size_t j = i + 1;
      std::string value;
      while (j < end && text[j] != c) {
        if (text[j] == '\\' && c == '"' && j + 1 < end) ++j;
        value += text[j++];
      }
      if (j >= end) break;  // the cursor is inside this string
      last_string = value;
      if (!frames.empty() && frames.back().after_colon && frames.back().key == "type")
        frames.back().type = value;
      i = j;
    } else if (c == '{' || c == '[') {
      if (!frames.empty()) {
        context.path.push_back(frames.back().object ? frames.back().key : "*");
        context.type = frames.back().object ? frames.back().type : std::string();
      }
      frames.push_back({c == '{', {}, false, {}});
    } else if (c == '}' || c == ']') {
      if (!frames.empty()) frames.pop_back();
      if (!frames.empty() && !context.path.empty()) context.path.pop_back();
    } else if (c == ':' && !frames.empty() && frames.back().object) {
      frames.back().key = last_string;
      frames.back().after_colon = true;
    } else if (c == ',' && !frames.empty()) {
      frames.back().after_colon = false;
    } else if (!frames.empty() && frames.back().object && name_char(c)) {
      // an unquoted YAML flow key, or value
      std::size_t j = i;
      while (j < end && name_char(text[j])) ++j;
      if (!frames.back().after_colon) {
        last_string = text.substr(i, j - i);
      } else if (frames.back().key == "type") {
        frames.back().type = text.substr(i, j - i);
      }
      i = j - 1;
    }
  }
  if (frames.empty()) return;
  if (!frames.back().object) {
    context.at = Context::At::kItem;
  } else if (frames.back().after_colon) {
    context.at = Context::At::kValue;
    context.key = frames.back().key;
  } else {
    context.at = Context::At::kKey;
  }
}

const std::set<std::string>& scalar_lists() {
  static const std::set<std::string> names = {"sensors", "inhibitions", "queue",
                                              "include", "plugins",     "ignore"};
  return names;
}

Context context_at(const Lines& lines, std::size_t offset, bool json_format) {
  Context context;
  const std::string& text = lines.text();
  std::size_t word = offset;
  while (word > 0 && name_char(text[word - 1])) --word;
  context.word_begin = word;
  if (json_format) {
    scan_flow(text, 0, offset, context);
    return context;
  }
  const std::size_t line = lines.line_of(offset);
  const std::string current = text.substr(lines.line_start(line), offset - lines.line_start(line));
  const YamlLine here = parse_yaml_line(current + "x");
  std::vector<std::string> reversed;
  int column = here.content;
  bool in_sequence = false;
  // The current line: `key: value`, `- item`, `key: {flow`, `- {flow` or a key being typed.
  const auto colon = current.find(": ");
  const std::string key = here.key.empty() ? parse_yaml_line(current).key : here.key;
  const auto content = static_cast<std::size_t>(here.content);
  auto opens_flow = [&](std::size_t at) {
    return at < current.size() && (current[at] == '{' || current[at] == '[');
  };
  std::size_t flow = std::string::npos;
  if (opens_flow(content)) {
    flow = content;  // the whole item or line is a flow collection
  } else if (!key.empty()) {
    std::size_t at = current.find(':', content) + 1;
    while (at < current.size() && current[at] == ' ') ++at;
    if (opens_flow(at)) flow = at;
  }
  if (flow != std::string::npos) {
    Context inner;
    scan_flow(current, flow, current.size(), inner);
    context.at = inner.at;
    context.key = inner.key;
    context.type = inner.type;
    if (flow != content) inner.path.insert(inner.path.begin(), key);
    context.path = inner.path;
  } else if (colon != std::string::npos) {
    context.at = Context::At::kValue;
    context.key = parse_yaml_line(current.substr(0, colon + 1)).key;
  }
  if (here.dash >= 0) {
    in_sequence = true;
    column = here.dash;
  }
  for (std::size_t l = line; l-- > 0;) {
    const std::string text_line =
        text.substr(lines.line_start(l), lines.line_end(l) - lines.line_start(l));
    const YamlLine up = parse_yaml_line(text_line);
    if (up.blank) continue;
    if (in_sequence) {
      if (up.dash >= 0 && up.dash == column) continue;  // a sibling item
      if (up.content <= column && !up.key.empty()) {
        reversed.push_back("*");
        reversed.push_back(up.key);
        column = up.dash >= 0 ? up.dash : up.content;
        in_sequence = up.dash >= 0;
        if (column == 0 && !in_sequence) break;
      }
      continue;
    }
    if (up.dash >= 0 && up.content == column) {  // the first key of this item's mapping
      in_sequence = true;
      column = up.dash;
      continue;
    }
    if (up.content < column && !up.key.empty()) {
      reversed.push_back(up.key);
      column = up.content;
      if (up.dash >= 0) {
        in_sequence = true;
        column = up.dash;
      }
    }
  }
  if (in_sequence) reversed.push_back("*");
  std::vector<std::string> path(reversed.rbegin(), reversed.rend());
  // A key at the root of the line's own sequence: `- name` under `sensors:` is an item.
  if (here.dash >= 0 && context.path.empty()) {
    // The item's own key (`- name: x`) is within the item's mapping.
    if (context.at == Context::At::kKey && !path.empty() && path.size() >= 2 &&
        scalar_lists().count(path[path.size() - 2])) {
      context.at = Context::At::kItem;
      path.pop_back();
    } else if (context.at == Context::At::kValue) {
      // `- key: value` in a sequence of mappings
    }
  }
  if (!path.empty() && path.back() == "*" && context.at == Context::At::kItem) path.pop_back();
  path.insert(path.end(), context.path.begin(), context.path.end());
  context.path = std::move(path);
  return context;
}

bool matches(const std::vector<std::string>& path, std::initializer_list<const char*> pattern) {
  if (path.size() != pattern.size()) return false;
  std::size_t i = 0;
  for (const char* part : pattern) {
    if (std::string(part) != "*" && path[i] != part) return false;
    ++i;
  }
  return true;
}

// The keys a schema definition allows (following $ref and anyOf).
void schema_keys(const json& schema, const json& definition, std::vector<std::string>& keys,
                 int depth = 0) {
  if (depth > 8 || !definition.is_object()) return;
  if (auto ref = definition.find("$ref"); ref != definition.end() && ref->is_string()) {
    const std::string name = ref->get<std::string>().substr(ref->get<std::string>().rfind('/') + 1);
    if (schema.contains("definitions") && schema["definitions"].contains(name)) {
      schema_keys(schema, schema["definitions"][name], keys, depth + 1);
    }
  }
  if (auto properties = definition.find("properties"); properties != definition.end()) {
    for (const auto& [key, value] : properties->items()) {
      if (std::find(keys.begin(), keys.end(), key) == keys.end()) keys.push_back(key);
    }
  }
  for (const char* group : {"anyOf", "oneOf", "allOf"}) {
    if (auto alternatives = definition.find(group); alternatives != definition.end()) {
      for (const auto& alternative : *alternatives)
        schema_keys(schema, alternative, keys, depth + 1);
    }
  }
  for (const char* branch : {"then", "else"}) {
    if (auto part = definition.find(branch); part != definition.end()) {
      schema_keys(schema, *part, keys, depth + 1);
    }
  }
}

std::string param_summary(const json& param) {
  std::string text = param.value("type", "");
  const bool low = param.contains("minimum") && param["minimum"].is_number();
  const bool high = param.contains("maximum") && param["maximum"].is_number();
  if (low && high) {
    text += fmt::format(", {} to {}", param["minimum"].dump(), param["maximum"].dump());
  } else if (low) {
    text += fmt::format(", at least {}", param["minimum"].dump());
  } else if (high) {
    text += fmt::format(", at most {}", param["maximum"].dump());
  }
  if (!param.value("choices", json::array()).empty()) {
    text += ", one of " + param["choices"].dump();
  }
  text += param.value("required", false) ? ", required"
                                         : ", default " + param.value("default", json()).dump();
  return text;
}

std::string class_markdown(const json& cls) {
  std::string text =
      fmt::format("**{}** ({}, {})\n\n{}\n", cls.value("name", ""), cls.value("kind", ""),
                  cls.value("origin", ""), cls.value("description", ""));
  if (!cls.value("params", json::array()).empty()) {
    text += "\nParams:\n";
    for (const auto& param : cls["params"]) {
      text += fmt::format("- `{}`: {} — {}\n", param.value("name", ""), param_summary(param),
                          param.value("description", ""));
    }
  }
  if (!cls.value("ports", json::array()).empty()) {
    text += "\nPorts:\n";
    for (const auto& port : cls["ports"]) {
      text +=
          fmt::format("- `{}`: {} {}{} — {}\n", port.value("name", ""), port.value("direction", ""),
                      port.value("type", ""), port.value("optional", false) ? ", optional" : "",
                      port.value("description", ""));
    }
  }
  return text;
}

}  // namespace

json Server::completion(const json& params) const {
  const std::string path = uri_to_path(params.at("textDocument").at("uri"));
  const std::string* text = text_of(path);
  // Nothing for the other YAML and JSON files an editor attaches the server to.
  if (!text || (kind_of(path) == ConfigText::kNone && !analysis_of(path))) return json::array();
  const Lines lines(*text);
  const std::size_t offset = lines.offset(params.at("position"));
  const Context context = context_at(lines, offset, format_of(path) == DocumentFormat::kJson);
  const Analysis* analysis = good_analysis_of(path);
  const Catalog& catalog = catalog_of(analysis);
  json items = json::array();
  // The item replaces the word typed so far, a dotted prefix included: without a range, clients
  // take their own idea of a word (`type: soccer.` would become `soccer.soccer.KickBall`).
  const json replaced = lines.range(context.word_begin, offset);
  auto add = [&](const std::string& label, int kind, const std::string& detail,
                 const std::string& documentation = {}) {
    json item = {
        {"label", label}, {"kind", kind}, {"textEdit", {{"range", replaced}, {"newText", label}}}};
    if (!detail.empty()) item["detail"] = detail;
    if (!documentation.empty())
      item["documentation"] = {{"kind", "markdown"}, {"value", documentation}};
    items.push_back(std::move(item));
  };
  auto keys = [&](const json& definition) {
    std::vector<std::string> names;
    schema_keys(catalog.schema, definition, names);
    for (const auto& name : names) add(name, 10, "key");
  };
  auto definition = [&](const char* name) { return catalog.schema["definitions"][name]; };
  auto classes = [&](const char* kind) {
    for (const auto& cls : catalog.classes["classes"]) {
      if (cls.value("kind", "") == kind)
        add(cls["name"], 7, cls.value("origin", ""), class_markdown(cls));
    }
  };
  auto names = [&](Kind kind, const std::string& scope, bool any_scope) {
    if (!analysis) return;
    std::set<std::string> seen;
    for (const auto& item : analysis->occurrences) {
      if (item.definition && item.kind == kind && (any_scope || item.scope == scope) &&
          seen.insert(item.name).second) {
        add(item.name, kind == Kind::kActuator ? 6 : kind == Kind::kMachine ? 9 : 12, item.detail);
      }
    }
  };
  // The layer the cursor is in: the last layer name declared above it in this file.
  auto layer_here = [&]() -> std::pair<std::string, bool> {
    if (!analysis) return {"", true};
    std::string layer;
    bool found = false;
    for (const auto& item : analysis->occurrences) {
      if (item.kind == Kind::kLayer && item.file == path && item.begin <= offset) {
        layer = item.name;
        found = true;
      }
    }
    return {layer, !found};
  };
  const auto& p = context.path;
  using At = Context::At;
  // Within a state's param that plans states of its machine (scripted's append: and prepend:).
  auto plans_states_at = [&](const std::vector<std::string>& at) {
    if (!analysis || !analysis->registry ||
        !matches(at, {"state_machines", "*", "states", "*", "params", "*"}))
      return false;
    for (const auto& item : analysis->occurrences) {
      if (!item.definition || item.kind != Kind::kState || item.scope != at[1] ||
          item.name != at[3])
        continue;
      const ClassInfo* cls = analysis->registry->find_class(ClassKind::kState, item.detail);
      const ParamSpec* param = cls ? cls->find_param(at[5]) : nullptr;
      return param && plans_states(*param);
    }
    return false;
  };
  if (context.at == At::kKey) {
    if (p.empty()) {
      keys(catalog.schema);
    } else if (matches(p, {"layers", "*"})) {
      keys(definition("layer"));
    } else if (matches(p, {"layers", "*", "actuators", "*"})) {
      keys(definition("actuator"));
    } else if (matches(p, {"layers", "*", "behaviours", "*"})) {
      keys(definition("behaviour"));
    } else if (matches(p, {"state_machines", "*"})) {
      keys(definition("state_machine"));
    } else if (matches(p, {"state_machines", "*", "states", "*"})) {
      keys(definition("state"));
    } else if (matches(p, {"state_machines", "*", "queue", "*"}) ||
               (p.size() == 7 && p[6] == "*" && plans_states_at({p.begin(), p.end() - 1}))) {
      names(Kind::kState, p[1], false);
    } else if (matches(p, {"layers", "*", "behaviours", "*", "params"}) ||
               matches(p, {"state_machines", "*", "states", "*", "params"})) {
      // The params of the class the enclosing behaviour or state names.
      const Kind kind = p[0] == "layers" ? Kind::kBehaviour : Kind::kState;
      std::string type = context.type;
      if (analysis && type.empty()) {
        for (const auto& item : analysis->occurrences) {
          if (item.definition && item.kind == kind && item.name == p[3]) type = item.detail;
        }
      }
      for (const auto& cls : catalog.classes["classes"]) {
        if (cls.value("name", "") != type) continue;
        for (const auto& param : cls["params"]) {
          add(param["name"], 5, param_summary(param), param.value("description", ""));
        }
      }
    }
  } else if (context.at == At::kValue) {
    const std::string& key = context.key;
    if (key == "type" && matches(p, {"layers", "*", "behaviours", "*"})) {
      classes("behaviour");
    } else if (key == "type" && matches(p, {"layers", "*", "actuators", "*"})) {
      for (const auto& type : catalog.classes["value_types"])
        add(type["name"], 22, type.value("origin", ""));
    } else if (key == "interface") {
      classes("interface");
    } else if ((key == "type" && matches(p, {"state_machines", "*", "states", "*"})) ||
               matches(p, {"state_machines", "*", "states"})) {
      classes("state");
    } else if (matches(p, {"layers", "*", "behaviours"})) {
      classes("behaviour");
    } else if (key == "machine") {
      names(Kind::kMachine, {}, true);
    } else if (key == "go_to") {
      if (p.size() >= 2 && p[0] == "state_machines") names(Kind::kState, p[1], false);
    } else if (!p.empty() && p.back() == "ports") {
      names(Kind::kActuator, {}, true);
    } else if (key == "sensors") {
      names(Kind::kActuator, {}, true);
    }
  } else if (plans_states_at(p)) {
    names(Kind::kState, p[1], false);
  } else {
    const std::string list = p.empty() ? std::string() : p.back();
    if (list == "inhibitions" || list == "sensors" || list == "queue") {
      if (list == "inhibitions") {
        const auto [layer, any] = layer_here();
        names(Kind::kBehaviour, layer, any);
      } else if (list == "sensors") {
        names(Kind::kActuator, {}, true);
      } else if (p.size() >= 2 && p[0] == "state_machines") {
        names(Kind::kState, p[1], false);
      }
    }
  }
  return {{"isIncomplete", false}, {"items", items}};
}

json Server::hover(const json& params) const {
  const std::string path = uri_to_path(params.at("textDocument").at("uri"));
  const Analysis* analysis = good_analysis_of(path);
  const Catalog& catalog = catalog_of(analysis);
  if (!analysis) return nullptr;
  const Cursor cursor = cursor_of(params, analysis);
  const Lines* lines = analysis->lines_of(path);
  const Occurrence* item = analysis->at(path, cursor.offset);
  // The last program that compiled: a config being edited is often invalid for a while.
  const Program* program = program_of(path);
  const auto& model = analysis->loaded.model;
  std::string text;
  std::size_t begin = 0, end = 0;
  if (item) {
    begin = item->begin;
    end = item->end;
    if (item->kind == Kind::kClass) {
      for (const auto& cls : catalog.classes["classes"]) {
        if (cls.value("name", "") == item->name) text = class_markdown(cls);
      }
      if (text.empty()) text = fmt::format("unknown class `{}`", item->name);
    } else if (item->kind == Kind::kBehaviour) {
      const Occurrence* definition = analysis->definition_of(*item);
      text = fmt::format("**behaviour** `{}` in layer `{}`", item->name, item->scope);
      if (definition && !definition->detail.empty())
        text += fmt::format(" (class `{}`)", definition->detail);
      text += "\n";
      std::optional<std::uint32_t> index =
          program ? program->find_behaviour(item->scope, item->name) : std::nullopt;
      if (index) {
        auto name = [&](std::uint32_t b) { return program->behaviours[b].name; };
        auto describe = [&](const CompiledInhibition& inhibition) {
          std::string line =
              fmt::format("`{}` {} `{}`", name(inhibition.inhibitor),
                          inhibition.chaining ? "=>" : "->", name(inhibition.inhibited));
          if (inhibition.implicit) {
            std::string chain;
            for (auto b : program->chain(inhibition.inhibitor, inhibition.inhibited)) {
              chain += (chain.empty() ? "" : " => ") + name(b);
            }
            line = fmt::format("`{}` inhibits `{}`, implied by chaining {}",
                               name(inhibition.inhibitor), name(inhibition.inhibited), chain);
          }
          return line;
        };
        text += "\nInhibited by:\n";
        const auto by = program->inhibitions.of(*index);
        if (by.empty()) text += "- nothing\n";
        for (const auto& inhibition : by) text += "- " + describe(inhibition) + "\n";
        text += "\nInhibits:\n";
        bool any = false;
        const auto& layer = program->layers[program->behaviours[*index].layer];
        for (std::uint32_t b = layer.behaviour_begin; b < layer.behaviour_end; ++b) {
          for (const auto& inhibition : program->inhibitions.of(b)) {
            if (inhibition.inhibitor != *index) continue;
            text += "- " + describe(inhibition) + "\n";
            any = true;
          }
        }
        if (!any) text += "- nothing\n";
      }
    } else if (item->kind == Kind::kActuator) {
      text = fmt::format("**actuator** `{}`", item->name);
      if (model) {
        if (const ActuatorDecl* actuator = model->find_actuator(item->name)) {
          text += fmt::format(" of layer `{}`, type `{}`{}", actuator->layer,
                              actuator->type ? actuator->type->name : "?",
                              actuator->aggregate ? ", aggregate" : "");
        }
        std::string writers, readers;
        for (const auto& layer : model->layers) {
          for (const auto& port : layer.ports) {
            if (port.target != item->name || !port.port) continue;
            (port.port->direction == PortDirection::kOutput ? writers : readers) += fmt::format(
                "- interface of layer `{}` (port `{}`)\n", layer.name.text, port.port->name);
          }
          for (const auto& sensor : layer.sensors) {
            if (sensor.text == item->name)
              readers += fmt::format("- layer `{}` (sensor)\n", layer.name.text);
          }
          for (const auto& behaviour : layer.behaviours) {
            for (const auto& port : behaviour.ports) {
              if (port.target != item->name || !port.port) continue;
              (port.port->direction == PortDirection::kOutput ? writers : readers) += fmt::format(
                  "- `{}/{}` (port `{}`)\n", layer.name.text, behaviour.name.text, port.port->name);
            }
          }
        }
        text += "\n\nWritten by:\n" + (writers.empty() ? "- nothing\n" : writers);
        text += "\nRead by:\n" + (readers.empty() ? "- nothing\n" : readers);
      }
    } else if (item->kind == Kind::kState) {
      const Occurrence* definition = analysis->definition_of(*item);
      text = fmt::format("**state** `{}` of state machine `{}`", item->name, item->scope);
      if (definition && !definition->detail.empty())
        text += fmt::format(" (class `{}`)", definition->detail);
    } else if (item->kind == Kind::kMachine) {
      text = fmt::format("**state machine** `{}`", item->name);
    } else if (item->kind == Kind::kLayer) {
      text = fmt::format("**layer** `{}`", item->name);
    } else if (item->kind == Kind::kInclude) {
      text = fmt::format("includes `{}`", item->name);
    }
  }
  // An inhibition line: what it implies through chaining.
  for (const auto& site : analysis->inhibitions) {
    if (site.file != path || cursor.offset < site.begin ||
        cursor.offset > std::max(site.end, site.begin) || item)
      continue;
    begin = site.begin;
    end = site.end;
    text = fmt::format("**inhibition** `{}` {} `{}` ({})\n", site.inhibitor,
                       site.chaining ? "=>" : "->", site.inhibited,
                       site.chaining ? "chaining" : "non-chaining");
    if (!program) break;
    const auto from = program->find_behaviour(site.layer, site.inhibitor);
    const auto via = program->find_behaviour(site.layer, site.inhibited);
    if (!from || !via) break;
    std::string implied;
    const auto& layer = program->layers[program->behaviours[*from].layer];
    for (std::uint32_t b = layer.behaviour_begin; b < layer.behaviour_end; ++b) {
      for (const auto& inhibition : program->inhibitions.of(b)) {
        if (!inhibition.implicit) continue;
        const auto chain = program->chain(inhibition.inhibitor, inhibition.inhibited);
        for (std::size_t i = 0; i + 1 < chain.size(); ++i) {
          if (chain[i] != *from || chain[i + 1] != *via) continue;
          std::string path_text;
          for (auto c : chain)
            path_text += (path_text.empty() ? "" : " => ") + program->behaviours[c].name;
          implied += fmt::format("- `{}` inhibits `{}` ({})\n",
                                 program->behaviours[inhibition.inhibitor].name,
                                 program->behaviours[inhibition.inhibited].name, path_text);
          break;
        }
      }
    }
    text += "\nImplies through chaining:\n" + (implied.empty() ? "- nothing\n" : implied);
    break;
  }
  if (text.empty()) return nullptr;
  json result = {{"contents", {{"kind", "markdown"}, {"value", text}}}};
  if (lines) result["range"] = lines->range(begin, end);
  return result;
}

}  // namespace arbiter::lsp
