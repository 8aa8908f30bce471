// The index of what a config's files declare and use, by place (arbiter/edit.hpp).

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "arbiter/edit.hpp"

namespace arbiter {

namespace {

class Indexer {
 public:
  Indexer(ConfigIndex& index, const Loaded& loaded, const Registry* registry)
      : a_(index), loaded_(loaded), registry_(registry) {}

  void run() {
    for (const auto& file : loaded_.files.files()) {
      if (file->root && file->root->is_mapping()) read_file(*file->root);
    }
  }

 private:
  // The bytes of a scalar's text in its file (when written verbatim), else of its node.
  std::pair<std::size_t, std::size_t> span(const Node& node, std::size_t from = 0,
                                           std::size_t length = std::string::npos) {
    const SourceLocation where = node.text_location(from);
    const std::string* text = text_of(where.file);
    if (!text) return {0, 0};
    const std::size_t begin = offset(*text, where.line, where.column);
    if (where.line == node.location().line && where.column == node.location().column && from == 0 &&
        node.quoted())
      return {begin, token_end(*text, begin)};
    const std::size_t size =
        std::min(length, node.text().size() - std::min(from, node.text().size()));
    return {begin, begin + size};
  }
  std::pair<std::size_t, std::size_t> key_span(const Node::Entry& entry) {
    const SourceLocation where = entry.key_location;
    const std::string* found = text_of(where.file);
    if (!found) return {0, 0};
    const std::string& text = *found;
    std::size_t begin = offset(text, where.line, where.column);
    if (begin < text.size() && (text[begin] == '"' || text[begin] == '\'')) ++begin;
    return {begin, begin + entry.key.size()};
  }

  void add(SymbolKind kind, std::string scope, const std::string& name, const std::string& file,
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
        add(SymbolKind::kInclude, {}, path, file, span(item), false);
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
        add(SymbolKind::kActuator, {}, port.value.text(), file, span(port.value), false);
    }
  }

  void read_layer(const Node& layer, const std::string& file) {
    if (!layer.is_mapping()) return;
    const Node* name = layer.find("name");
    const std::string layer_name = name && name->is_scalar() ? name->text() : std::string();
    if (name && name->is_scalar()) add(SymbolKind::kLayer, {}, layer_name, file, span(*name), true);
    if (const Node* interface = layer.find("interface"); interface && interface->is_scalar()) {
      add(SymbolKind::kClass, {}, interface->text(), file, span(*interface), false);
    }
    read_ports(layer.find("ports"), file);
    if (layer.find("interface")) a_.port_owners.push_back({layer_name, {}, file, &layer});
    if (const Node* actuators = layer.find("actuators"); actuators && actuators->is_mapping()) {
      for (const auto& actuator : actuators->entries()) {
        add(SymbolKind::kActuator, {}, actuator.key, file, key_span(actuator), true,
            type_of(actuator.value));
      }
    }
    if (const Node* sensors = layer.find("sensors"); sensors && sensors->is_sequence()) {
      for (const auto& sensor : sensors->items()) {
        if (sensor.is_scalar())
          add(SymbolKind::kActuator, {}, sensor.text(), file, span(sensor), false, "sensor");
      }
    }
    if (const Node* behaviours = layer.find("behaviours"); behaviours && behaviours->is_mapping()) {
      for (const auto& behaviour : behaviours->entries()) {
        add(SymbolKind::kBehaviour, layer_name, behaviour.key, file, key_span(behaviour), true,
            type_of(behaviour.value));
        const Node& value = behaviour.value;
        a_.port_owners.push_back({layer_name, behaviour.key, file, &value});
        if (value.is_scalar()) add(SymbolKind::kClass, {}, value.text(), file, span(value), false);
        if (!value.is_mapping()) continue;
        if (const Node* type = value.find("type"); type && type->is_scalar()) {
          add(SymbolKind::kClass, {}, type->text(), file, span(*type), false);
        }
        read_ports(value.find("ports"), file);
        if (const Node* params = value.find("params"); params && params->is_mapping()) {
          if (const Node* machine = params->find("machine"); machine && machine->is_scalar()) {
            add(SymbolKind::kMachine, {}, machine->text(), file, span(*machine), false);
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
    const std::string* source = text_of(file);
    if (!source) return;
    const std::size_t start = offset(*source, item.location().line, item.location().column);
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
      add(SymbolKind::kBehaviour, layer, site.inhibitor, file,
          span(item, left.first, left.second - left.first), false);
      add(SymbolKind::kBehaviour, layer, site.inhibited, file,
          span(item, right.first, right.second - right.first), false);
      site.begin = start;
      site.end = item.quoted() ? token_end(*source, start) : span(item).second;
    } else if (item.is_mapping()) {
      const Node* inhibitor = item.find("inhibitor");
      const Node* inhibited = item.find("inhibited");
      if (!inhibitor || !inhibited || !inhibitor->is_scalar() || !inhibited->is_scalar()) return;
      site.inhibitor = inhibitor->text();
      site.inhibited = inhibited->text();
      const Node* chaining = item.find("chaining");
      site.chaining = chaining && chaining->as_bool().value_or(false);
      add(SymbolKind::kBehaviour, layer, site.inhibitor, file, span(*inhibitor), false);
      add(SymbolKind::kBehaviour, layer, site.inhibited, file, span(*inhibited), false);
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
    const ClassInfo* cls = registry_ ? registry_->find_class(ClassKind::kState, type) : nullptr;
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
      add(SymbolKind::kState, machine, entry.text(), file, span(entry), false);
      return;
    }
    if (!entry.is_mapping() || entry.size() != 1) return;
    const auto& only = entry.entries().front();
    add(SymbolKind::kState, machine, only.key, file, key_span(only), false);
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
    add(SymbolKind::kMachine, {}, machine.key, file, key_span(machine), true);
    if (!machine.value.is_mapping()) return;
    const Node* states = machine.value.find("states");
    if (states && !states->is_mapping()) states = nullptr;
    if (states) {
      for (const auto& state : states->entries()) {
        add(SymbolKind::kState, machine.key, state.key, file, key_span(state), true,
            type_of(state.value));
        if (state.value.is_scalar())
          add(SymbolKind::kClass, {}, state.value.text(), file, span(state.value), false);
        if (!state.value.is_mapping()) continue;
        if (const Node* type = state.value.find("type"); type && type->is_scalar()) {
          add(SymbolKind::kClass, {}, type->text(), file, span(*type), false);
        }
        if (const Node* child = state.value.find("machine"); child && child->is_scalar()) {
          add(SymbolKind::kMachine, {}, child->text(), file, span(*child), false);
        }
        read_planned(type_of(state.value), state.value.find("params"), machine.key, states, file);
      }
    }
    auto queue_entry = [&](const Node& entry) {
      read_queue_entry(entry, machine.key, states, file);
    };
    if (const Node* queue = machine.value.find("queue"); queue && queue->is_sequence()) {
      for (std::size_t i = 0; i < queue->size(); ++i) {
        const Node& entry = queue->items()[i];
        queue_entry(entry);
        if (entry.is_scalar()) {
          const auto at = span(entry);
          a_.queue_items.push_back({machine.key, entry.text(), i, file, at.first, at.second});
        } else if (entry.is_mapping() && entry.size() == 1) {
          const auto at = key_span(entry.entries().front());
          a_.queue_items.push_back(
              {machine.key, entry.entries().front().key, i, file, at.first, at.second});
        }
      }
    }
    if (const Node* preempt = machine.value.find("preempt"); preempt && preempt->is_sequence()) {
      for (const auto& item : preempt->items()) {
        if (const Node* go_to = item.is_mapping() ? item.find("go_to") : nullptr)
          queue_entry(*go_to);
      }
    }
  }

  const std::string* text_of(const std::string& file) const {
    const SourceFile* found = loaded_.files.find(file);
    return found ? &found->text : nullptr;
  }

  /// offset_of(), from the line starts of `text` found once: a config of 1000 behaviours has
  /// some 10 000 names, and offset_of() walks the text from its start for each.
  std::size_t offset(const std::string& text, int line, int column) {
    std::vector<std::size_t>& starts = line_starts_[&text];
    if (starts.empty()) {
      starts.push_back(0);
      for (std::size_t at = text.find('\n'); at != std::string::npos; at = text.find('\n', at + 1))
        starts.push_back(at + 1);
    }
    if (line < 1) return offset_of(text, line, column);
    const std::size_t l = static_cast<std::size_t>(line - 1);
    if (l >= starts.size()) return text.size();
    const std::size_t start = starts[l];
    // The column counted on the line alone, as offset_of() counts it.
    const std::size_t end = l + 1 < starts.size() ? starts[l + 1] : text.size();
    return start + offset_of(text.substr(start, end - start), 1, column);
  }

  ConfigIndex& a_;
  const Loaded& loaded_;
  const Registry* registry_;
  std::unordered_map<const std::string*, std::vector<std::size_t>> line_starts_;
};

}  // namespace

ConfigIndex index_config(const Loaded& loaded, const Registry* registry) {
  ConfigIndex index;
  Indexer(index, loaded, registry).run();
  return index;
}

bool plans_states(const ParamSpec& param) {
  return param.json_schema.find("#/definitions/queue_entry") != std::string::npos;
}

std::size_t token_end(const std::string& text, std::size_t begin) {
  if (begin >= text.size()) return begin;
  const char first = text[begin];
  if (first == '"' || first == '\'') {
    for (std::size_t at = begin + 1; at < text.size() && text[at] != '\n'; ++at) {
      if (text[at] == '\\' && first == '"') {
        ++at;
      } else if (text[at] == first) {
        return at + 1;
      }
    }
    return begin + 1;
  }
  std::size_t at = begin;
  while (at < text.size()) {
    const auto c = static_cast<unsigned char>(text[at]);
    const bool name = std::isalnum(c) || c == '_' || c == '.' || c == '$' || c == '/' ||
                      c >= 0x80 || (c == '-' && at + 1 < text.size() && text[at + 1] != '>');
    if (!name) break;
    ++at;
  }
  if (at != begin) return at;
  std::size_t line_end = std::min(text.find('\n', begin), text.size());
  if (line_end > begin && text[line_end - 1] == '\r') --line_end;
  return std::min(begin + 1, line_end);
}

}  // namespace arbiter
