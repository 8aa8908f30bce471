// URIs and paths, the index of what a config's files declare and use, and the text readings the
// request handlers share.

#include "lsp/analysis.hpp"

#include <fmt/format.h>

#include <cctype>
#include <filesystem>
#include <utility>

namespace arbiter::lsp {

std::string uri_to_path(const std::string& uri) {
  std::string rest = uri.rfind("file://", 0) == 0 ? uri.substr(7) : uri;
  std::string path;
  for (std::size_t i = 0; i < rest.size(); ++i) {
    if (rest[i] == '%' && i + 2 < rest.size() &&
        std::isxdigit(static_cast<unsigned char>(rest[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(rest[i + 2]))) {
      path += static_cast<char>(std::stoi(rest.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      path += rest[i];
    }
  }
  return std::filesystem::path(path).lexically_normal().string();
}

std::string path_to_uri(const std::string& path) {
  std::string uri = "file://";
  for (unsigned char c : path) {
    if (std::isalnum(c) || c == '/' || c == '-' || c == '_' || c == '.' || c == '~') {
      uri += static_cast<char>(c);
    } else {
      uri += fmt::format("%{:02X}", c);
    }
  }
  return uri;
}

namespace {

class Indexer {
 public:
  explicit Indexer(Analysis& analysis) : a_(analysis) {}

  void run() {
    for (const auto& file : a_.loaded.files.files()) {
      a_.lines[file->path] = std::make_unique<Lines>(file->text);
    }
    for (const auto& file : a_.loaded.files.files()) {
      if (file->root && file->root->is_mapping()) read_file(*file->root);
    }
  }

 private:
  // The bytes of a scalar's text in its file (when written verbatim), else of its node.
  std::pair<std::size_t, std::size_t> span(const Node& node, std::size_t from = 0,
                                           std::size_t length = std::string::npos) {
    const SourceLocation where = node.text_location(from);
    const Lines* lines = a_.lines_of(where.file);
    if (!lines) return {0, 0};
    const std::size_t begin = lines->offset(where.line, where.column);
    if (where.line == node.location().line && where.column == node.location().column && from == 0 &&
        node.quoted())
      return {begin, lines->token_end(begin)};
    const std::size_t size =
        std::min(length, node.text().size() - std::min(from, node.text().size()));
    return {begin, begin + size};
  }
  std::pair<std::size_t, std::size_t> key_span(const Node::Entry& entry) {
    const SourceLocation where = entry.key_location;
    const Lines* lines = a_.lines_of(where.file);
    if (!lines) return {0, 0};
    std::size_t begin = lines->offset(where.line, where.column);
    const auto& text = lines->text();
    if (begin < text.size() && (text[begin] == '"' || text[begin] == '\'')) ++begin;
    return {begin, begin + entry.key.size()};
  }

  void add(Kind kind, std::string scope, const std::string& name, const std::string& file,
           std::pair<std::size_t, std::size_t> at, bool definition, std::string detail = {}) {
    a_.occurrences.push_back(
        {kind, std::move(scope), name, file, at.first, at.second, definition, std::move(detail)});
  }

  static std::string type_of(const Node& value) {
    if (value.is_scalar()) return value.text();
    if (const Node* type = value.find("type"); type && type->is_scalar()) return type->text();
    return {};
  }

  void read_file(const Node& root) {
    const std::string file = root.location().file;
    if (const Node* include = root.find("include"); include && include->is_sequence()) {
      for (const auto& item : include->items()) {
        if (!item.is_scalar()) continue;
        const auto path =
            (std::filesystem::path(file).parent_path() / item.text()).lexically_normal().string();
        add(Kind::kInclude, {}, path, file, span(item), false);
      }
    }
    if (const Node* layers = root.find("layers"); layers && layers->is_sequence()) {
      for (const auto& layer : layers->items()) read_layer(layer, file);
    }
    if (const Node* machines = root.find("state_machines"); machines && machines->is_mapping()) {
      for (const auto& machine : machines->entries()) read_machine(machine, file);
    }
  }

  void read_ports(const Node* ports, const std::string& file) {
    if (!ports || !ports->is_mapping()) return;
    for (const auto& port : ports->entries()) {
      if (port.value.is_scalar())
        add(Kind::kActuator, {}, port.value.text(), file, span(port.value), false);
    }
  }

  void read_layer(const Node& layer, const std::string& file) {
    if (!layer.is_mapping()) return;
    const Node* name = layer.find("name");
    const std::string layer_name = name && name->is_scalar() ? name->text() : std::string();
    if (name && name->is_scalar()) add(Kind::kLayer, {}, layer_name, file, span(*name), true);
    if (const Node* interface = layer.find("interface"); interface && interface->is_scalar()) {
      add(Kind::kClass, {}, interface->text(), file, span(*interface), false);
    }
    read_ports(layer.find("ports"), file);
    if (layer.find("interface")) a_.port_owners.push_back({layer_name, {}, file, &layer});
    if (const Node* actuators = layer.find("actuators"); actuators && actuators->is_mapping()) {
      for (const auto& actuator : actuators->entries()) {
        add(Kind::kActuator, {}, actuator.key, file, key_span(actuator), true,
            type_of(actuator.value));
      }
    }
    if (const Node* sensors = layer.find("sensors"); sensors && sensors->is_sequence()) {
      for (const auto& sensor : sensors->items()) {
        if (sensor.is_scalar())
          add(Kind::kActuator, {}, sensor.text(), file, span(sensor), false, "sensor");
      }
    }
    if (const Node* behaviours = layer.find("behaviours"); behaviours && behaviours->is_mapping()) {
      for (const auto& behaviour : behaviours->entries()) {
        add(Kind::kBehaviour, layer_name, behaviour.key, file, key_span(behaviour), true,
            type_of(behaviour.value));
        const Node& value = behaviour.value;
        a_.port_owners.push_back({layer_name, behaviour.key, file, &value});
        if (value.is_scalar()) add(Kind::kClass, {}, value.text(), file, span(value), false);
        if (!value.is_mapping()) continue;
        if (const Node* type = value.find("type"); type && type->is_scalar()) {
          add(Kind::kClass, {}, type->text(), file, span(*type), false);
        }
        read_ports(value.find("ports"), file);
        if (const Node* params = value.find("params"); params && params->is_mapping()) {
          if (const Node* machine = params->find("machine"); machine && machine->is_scalar()) {
            add(Kind::kMachine, {}, machine->text(), file, span(*machine), false);
          }
        }
      }
    }
    if (const Node* inhibitions = layer.find("inhibitions");
        inhibitions && inhibitions->is_sequence()) {
      for (const auto& item : inhibitions->items()) read_inhibition(item, layer_name, file);
    }
  }

  void read_inhibition(const Node& item, const std::string& layer, const std::string& file) {
    InhibitionSite site{layer, {}, {}, false, file, 0, 0};
    const Lines* lines = a_.lines_of(file);
    if (!lines) return;
    const std::size_t start = lines->offset(item.location().line, item.location().column);
    if (item.is_scalar()) {
      const std::string& text = item.text();
      std::size_t arrow = text.find("=>");
      site.chaining = arrow != std::string::npos;
      if (!site.chaining) arrow = text.find("->");
      if (arrow == std::string::npos) return;
      auto trimmed = [&](std::size_t from, std::size_t to) {
        while (from < to && text[from] == ' ') ++from;
        while (to > from && text[to - 1] == ' ') --to;
        return std::make_pair(from, to);
      };
      const auto left = trimmed(0, arrow);
      const auto right = trimmed(arrow + 2, text.size());
      site.inhibitor = text.substr(left.first, left.second - left.first);
      site.inhibited = text.substr(right.first, right.second - right.first);
      add(Kind::kBehaviour, layer, site.inhibitor, file,
          span(item, left.first, left.second - left.first), false);
      add(Kind::kBehaviour, layer, site.inhibited, file,
          span(item, right.first, right.second - right.first), false);
      site.begin = start;
      site.end = item.quoted() ? lines->token_end(start) : span(item).second;
    } else if (item.is_mapping()) {
      const Node* inhibitor = item.find("inhibitor");
      const Node* inhibited = item.find("inhibited");
      if (!inhibitor || !inhibited || !inhibitor->is_scalar() || !inhibited->is_scalar()) return;
      site.inhibitor = inhibitor->text();
      site.inhibited = inhibited->text();
      const Node* chaining = item.find("chaining");
      site.chaining = chaining && chaining->as_bool().value_or(false);
      add(Kind::kBehaviour, layer, site.inhibitor, file, span(*inhibitor), false);
      add(Kind::kBehaviour, layer, site.inhibited, file, span(*inhibited), false);
      site.begin = start;
      site.end = start;
    } else {
      return;
    }
    a_.inhibitions.push_back(std::move(site));
  }

  // The params of a state's class that plan states (plans_states).
  std::vector<std::string> planning_params(const std::string& type) const {
    std::vector<std::string> names;
    const ClassInfo* cls = a_.registry ? a_.registry->find_class(ClassKind::kState, type) : nullptr;
    if (!cls) return names;
    for (const auto& param : cls->params) {
      if (plans_states(param)) names.push_back(param.name);
    }
    return names;
  }

  // A queue entry, a state name or {state: {params}}, in `machine`, and the states its params
  // plan in turn.
  void read_queue_entry(const Node& entry, const std::string& machine, const Node* states,
                        const std::string& file) {
    if (entry.is_scalar()) {
      add(Kind::kState, machine, entry.text(), file, span(entry), false);
      return;
    }
    if (!entry.is_mapping() || entry.size() != 1) return;
    const auto& only = entry.entries().front();
    add(Kind::kState, machine, only.key, file, key_span(only), false);
    const Node* state = states ? states->find(only.key) : nullptr;
    if (state) read_planned(type_of(*state), &only.value, machine, states, file);
  }

  void read_planned(const std::string& type, const Node* params, const std::string& machine,
                    const Node* states, const std::string& file) {
    if (!params || !params->is_mapping()) return;
    for (const auto& name : planning_params(type)) {
      const Node* list = params->find(name);
      if (!list || !list->is_sequence()) continue;
      for (const auto& item : list->items()) read_queue_entry(item, machine, states, file);
    }
  }

  void read_machine(const Node::Entry& machine, const std::string& file) {
    add(Kind::kMachine, {}, machine.key, file, key_span(machine), true);
    if (!machine.value.is_mapping()) return;
    const Node* states = machine.value.find("states");
    if (states && !states->is_mapping()) states = nullptr;
    if (states) {
      for (const auto& state : states->entries()) {
        add(Kind::kState, machine.key, state.key, file, key_span(state), true,
            type_of(state.value));
        if (state.value.is_scalar())
          add(Kind::kClass, {}, state.value.text(), file, span(state.value), false);
        if (!state.value.is_mapping()) continue;
        if (const Node* type = state.value.find("type"); type && type->is_scalar()) {
          add(Kind::kClass, {}, type->text(), file, span(*type), false);
        }
        if (const Node* child = state.value.find("machine"); child && child->is_scalar()) {
          add(Kind::kMachine, {}, child->text(), file, span(*child), false);
        }
        read_planned(type_of(state.value), state.value.find("params"), machine.key, states, file);
      }
    }
    auto queue_entry = [&](const Node& entry) {
      read_queue_entry(entry, machine.key, states, file);
    };
    if (const Node* queue = machine.value.find("queue"); queue && queue->is_sequence()) {
      for (const auto& entry : queue->items()) queue_entry(entry);
    }
    if (const Node* preempt = machine.value.find("preempt"); preempt && preempt->is_sequence()) {
      for (const auto& item : preempt->items()) {
        if (const Node* go_to = item.is_mapping() ? item.find("go_to") : nullptr)
          queue_entry(*go_to);
      }
    }
  }

  Analysis& a_;
};

}  // namespace

void index_config(Analysis& analysis) {
  Indexer(analysis).run();
}

json range_json(int line, int character) {
  return {{"start", {{"line", line}, {"character", character}}},
          {"end", {{"line", line}, {"character", character}}}};
}

Cursor cursor_of(const json& params, const Analysis* analysis) {
  Cursor cursor;
  cursor.path = uri_to_path(params.at("textDocument").at("uri"));
  if (analysis) {
    if (const Lines* lines = analysis->lines_of(cursor.path))
      cursor.offset = lines->offset(params.at("position"));
  }
  return cursor;
}

json location_json(const Analysis& analysis, const std::string& file, std::size_t begin,
                   std::size_t end) {
  const Lines* lines = analysis.lines_of(file);
  return {{"uri", path_to_uri(file)},
          {"range", lines ? lines->range(begin, end) : range_json(0, 0)}};
}

void add_changes(const Analysis& analysis, const std::vector<TextEdit>& edits, json& changes) {
  for (const auto& edit : edits) {
    const Lines* lines = analysis.lines_of(edit.file);
    if (!lines) continue;
    changes[path_to_uri(edit.file)].push_back(
        {{"range", lines->range(edit.begin, edit.end)}, {"newText", edit.text}});
  }
}

bool name_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '$' ||
         c == '-';
}

YamlLine parse_yaml_line(const std::string& line) {
  YamlLine result;
  std::size_t at = 0;
  while (at < line.size() && line[at] == ' ') ++at;
  if (at >= line.size() || line[at] == '#' || line[at] == '\r') return result;
  result.blank = false;
  if (line[at] == '-' && (at + 1 == line.size() || line[at + 1] == ' ')) {
    result.dash = static_cast<int>(at);
    ++at;
    while (at < line.size() && line[at] == ' ') ++at;
  }
  result.content = static_cast<int>(at);
  std::size_t end = at;
  const bool quoted = at < line.size() && (line[at] == '"' || line[at] == '\'');
  if (quoted) ++end;
  while (end < line.size() && name_char(line[end])) ++end;
  std::size_t colon = end;
  if (quoted && colon < line.size() && line[colon] == line[at]) ++colon;
  if (colon < line.size() && line[colon] == ':' &&
      (colon + 1 == line.size() || line[colon + 1] == ' ' || line[colon + 1] == '\r')) {
    result.key = line.substr(at + (quoted ? 1 : 0), end - at - (quoted ? 1 : 0));
  }
  return result;
}

}  // namespace arbiter::lsp
