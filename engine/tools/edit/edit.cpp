#include "arbiter/edit.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <tuple>

namespace arbiter {

namespace {

bool space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n';
}

std::size_t line_start(const std::string& text, std::size_t at) {
  const auto newline = at == 0 ? std::string::npos : text.rfind('\n', at - 1);
  return newline == std::string::npos ? 0 : newline + 1;
}

/// The start of the line after the one holding `at` (the text's end on the last line).
std::size_t next_line(const std::string& text, std::size_t at) {
  const auto newline = text.find('\n', at);
  return newline == std::string::npos ? text.size() : newline + 1;
}

/// The offset of the bracket that closes the flow collection opening at `open`, or npos.
std::size_t flow_close(const std::string& text, std::size_t open) {
  int depth = 0;
  for (std::size_t at = open; at < text.size(); ++at) {
    const char c = text[at];
    if (c == '"' || c == '\'') {
      for (++at; at < text.size() && text[at] != c; ++at) {
        if (c == '"' && text[at] == '\\') ++at;
      }
    } else if (c == '#' && at > open && space(text[at - 1])) {
      while (at < text.size() && text[at] != '\n') ++at;  // a YAML comment
    } else if (c == '{' || c == '[') {
      ++depth;
    } else if ((c == '}' || c == ']') && --depth == 0) {
      return at;
    }
  }
  return std::string::npos;
}

/// The end of the block that starts on the line of `begin` with its content at `begin`'s
/// column: after the last line indented at least as deep (blank lines and comments inside are
/// the block's only when content follows them).
std::size_t block_end(const std::string& text, std::size_t begin, std::size_t column) {
  std::size_t end = next_line(text, begin);
  for (std::size_t at = end; at < text.size();) {
    const std::size_t next = next_line(text, at);
    std::size_t indent = at;
    while (indent < next && text[indent] == ' ') ++indent;
    const bool blank = indent == next || space(text[indent]) || text[indent] == '#';
    if (!blank) {
      if (indent - at < column) break;
      end = next;
    }
    at = next;
  }
  return end;
}

/// A scalar inhibition item's parts: the endpoints and the arrow's offset in its text.
struct Arrow {
  std::string inhibitor;
  std::string inhibited;
  std::size_t at = std::string::npos;
  bool chaining = false;
};

Arrow read_arrow(const std::string& text) {
  Arrow arrow;
  arrow.at = text.find("=>");
  arrow.chaining = arrow.at != std::string::npos;
  if (!arrow.chaining) arrow.at = text.find("->");
  if (arrow.at == std::string::npos) return arrow;
  auto trimmed = [&](std::size_t from, std::size_t to) {
    while (from < to && space(text[from])) ++from;
    while (to > from && space(text[to - 1])) --to;
    return text.substr(from, to - from);
  };
  arrow.inhibitor = trimmed(0, arrow.at);
  arrow.inhibited = trimmed(arrow.at + 2, text.size());
  return arrow;
}

bool names(const Node& item, const InhibitionRef& which) {
  if (item.is_scalar()) {
    const Arrow arrow = read_arrow(item.text());
    return arrow.inhibitor == which.inhibitor && arrow.inhibited == which.inhibited;
  }
  if (!item.is_mapping()) return false;
  const Node* inhibitor = item.find("inhibitor");
  const Node* inhibited = item.find("inhibited");
  return inhibitor && inhibited && inhibitor->is_scalar() && inhibited->is_scalar() &&
         inhibitor->text() == which.inhibitor && inhibited->text() == which.inhibited;
}

/// The inhibitor and the inhibited an inhibition item names, as an arrow or a mapping ("" when
/// it names none).
std::pair<std::string, std::string> endpoints(const Node& item) {
  if (item.is_scalar()) {
    const Arrow arrow = read_arrow(item.text());
    return {arrow.inhibitor, arrow.inhibited};
  }
  const Node* inhibitor = item.is_mapping() ? item.find("inhibitor") : nullptr;
  const Node* inhibited = item.is_mapping() ? item.find("inhibited") : nullptr;
  if (!inhibitor || !inhibited || !inhibitor->is_scalar() || !inhibited->is_scalar()) return {};
  return {inhibitor->text(), inhibited->text()};
}

/// A layer's declaration, in the config's file or an include that declares it.
struct LayerSite {
  const SourceFile* file;
  const Node* layer;
};

/// Every declaration of the layer named `layer`, in the order of the config's files.
std::vector<LayerSite> layers_named(const Loaded& loaded, const std::string& layer) {
  std::vector<LayerSite> found;
  for (const auto& file : loaded.files.files()) {
    const Node* layers =
        file->root && file->root->is_mapping() ? file->root->find("layers") : nullptr;
    if (!layers || !layers->is_sequence()) continue;
    for (const auto& item : layers->items()) {
      const Node* name = item.is_mapping() ? item.find("name") : nullptr;
      if (name && name->is_scalar() && name->text() == layer) found.push_back({file.get(), &item});
    }
  }
  return found;
}

/// Where a declared inhibition is: its file, the layer's `inhibitions:` entry and the item.
struct Site {
  const SourceFile* file;
  const Node::Entry* list;
  const Node* item;
};

std::vector<Site> sites_of(const Loaded& loaded, const InhibitionRef& which) {
  std::vector<Site> sites;
  for (const auto& [file, layer] : layers_named(loaded, which.layer)) {
    for (const auto& entry : layer->entries()) {
      if (entry.key != "inhibitions" || !entry.value.is_sequence()) continue;
      for (const auto& item : entry.value.items()) {
        if (names(item, which)) sites.push_back({file, &entry, &item});
      }
    }
  }
  return sites;
}

std::string describe(const InhibitionRef& which) {
  return fmt::format("'{} -> {}' in layer '{}'", which.inhibitor, which.inhibited, which.layer);
}

std::size_t offset_at(const SourceFile& file, const SourceLocation& where) {
  return offset_of(file.text, where.line, where.column);
}

/// The bytes a scalar item's text spans: from its location, through its closing quote if quoted.
std::size_t scalar_end(const std::string& text, std::size_t begin, const Node& node) {
  if (node.quoted() && begin < text.size() && (text[begin] == '"' || text[begin] == '\'')) {
    const char quote = text[begin];
    for (std::size_t at = begin + 1; at < text.size() && text[at] != '\n'; ++at) {
      if (quote == '"' && text[at] == '\\') {
        ++at;
      } else if (text[at] == quote) {
        return at + 1;
      }
    }
  }
  return std::min(text.size(), begin + node.text().size());
}

/// The edit removing `site`'s item from its sequence.
TextEdit remove_item(const Site& site) {
  const std::string& text = site.file->text;
  const Node& list = site.list->value;
  const Node& item = *site.item;
  const std::size_t begin = offset_at(*site.file, item.location());
  const std::size_t start = line_start(text, begin);
  const bool only = list.items().size() == 1;
  std::size_t dash = begin;
  while (dash > start && text[dash - 1] == ' ') --dash;
  const bool block =
      dash > start && text[dash - 1] == '-' && text.find_first_not_of(' ', start) == dash - 1;
  if (block) {
    const std::size_t end = block_end(text, begin, begin - start);
    if (!only) return {site.file->path, start, end, {}};
    // The key goes with its only item: `inhibitions:` with nothing under it would be null.
    const std::size_t key = offset_at(*site.file, site.list->key_location);
    return {site.file->path, line_start(text, key), end, {}};
  }
  std::size_t from = begin;
  std::size_t to = begin;
  if (item.is_scalar()) {
    to = scalar_end(text, begin, item);
  } else if (const std::size_t close = flow_close(text, begin); close != std::string::npos) {
    to = close + 1;
  }
  if (item.is_scalar() && !item.quoted()) {
    // An unquoted flow item runs to the next ',' or ']'.
    to = std::min(text.find_first_of(",]\n", begin), text.size());
    while (to > begin && space(text[to - 1])) --to;
  }
  // With the comma before it (or, for the first item, the one after it).
  std::size_t back = from;
  while (back > 0 && space(text[back - 1])) --back;
  if (back > 0 && text[back - 1] == ',') {
    from = back - 1;
  } else {
    std::size_t after = to;
    while (after < text.size() && space(text[after])) ++after;
    if (after < text.size() && text[after] == ',') {
      to = after + 1;
      while (to < text.size() && space(text[to])) ++to;
    }
  }
  return {site.file->path, from, to, {}};
}

/// The edits that keep the ports bound by name to actuator `old` bound to it as `name`: a
/// `ports:` entry for each, as a person would add it.
EditResult follow_ports(const Loaded& loaded, const ConfigIndex& index, const std::string& old,
                        const std::string& name) {
  const auto& model = loaded.model;
  std::vector<TextEdit> edits;
  // Which ports bind by name is known only from the classes: while a behaviour's or an
  // interface's class is unknown (misspelt, or its plugin not found), it is not.
  static const std::vector<LayerDecl> kNoLayers;
  const auto& layers = model ? model->layers : kNoLayers;
  for (const auto& owner : index.port_owners) {
    bool known = false;
    for (const auto& layer : layers) {
      if (layer.name.text != owner.layer) continue;
      if (owner.behaviour.empty()) known = known || layer.interface != nullptr;
      for (const auto& behaviour : layer.behaviours) {
        if (behaviour.name.text == owner.behaviour) known = known || behaviour.cls != nullptr;
      }
    }
    if (!known) {
      return {{},
              fmt::format("the class of {} is not known, so whether a port of it binds to '{}' by "
                          "name is not: fix the config's errors first",
                          owner.behaviour.empty() ? "the interface of layer '" + owner.layer + "'"
                                                  : "'" + owner.behaviour + "'",
                          old)};
    }
  }
  // A state binds its ports by name only (it has no ports:), so none can follow the rename.
  if (model) {
    for (const auto& machine : model->state_machines) {
      for (const auto& state : machine.states) {
        if (!state.cls) continue;
        for (const auto& port : state.cls->ports) {
          if (port.name != old) continue;
          return {{},
                  fmt::format("state '{}' of state machine '{}' ({}) binds port '{}' by name, "
                              "and a state has no ports: to bind it to '{}'",
                              state.name.text, machine.name.text, state.cls->name, old, name)};
        }
      }
    }
  }
  auto binds = [&](const std::vector<PortBinding>& ports) {
    return std::any_of(ports.begin(), ports.end(), [&](const PortBinding& binding) {
      return binding.port && binding.port->name == old && binding.target == old;
    });
  };
  for (const auto& layer : layers) {
    std::vector<std::string> owners;
    if (binds(layer.ports)) owners.emplace_back();
    for (const auto& behaviour : layer.behaviours) {
      if (binds(behaviour.ports)) owners.push_back(behaviour.name.text);
    }
    for (const auto& owner : owners) {
      const auto found = std::find_if(
          index.port_owners.begin(), index.port_owners.end(), [&](const PortOwner& item) {
            return item.layer == layer.name.text && item.behaviour == owner;
          });
      const std::string who =
          owner.empty() ? "the interface of layer '" + layer.name.text + "'" : "'" + owner + "'";
      if (found == index.port_owners.end() || !found->node)
        return {{},
                fmt::format("{} binds port '{}' by name, and its text was not found to add "
                            "a ports: entry",
                            who, old)};
      const Node& node = *found->node;
      const Node* ports = node.is_mapping() ? node.find("ports") : nullptr;
      if (ports && ports->is_mapping() && ports->find(old)) continue;  // bound explicitly
      const SourceFile* file = loaded.files.find(found->file);
      const bool json_text = format_of(found->file) == DocumentFormat::kJson;
      auto quote = [&](const std::string& word) { return json_text ? "\"" + word + "\"" : word; };
      const std::string entry = quote(old) + ": " + quote(name);
      EditResult added{{}, "its text was not found"};
      if (file && ports && ports->is_mapping()) {
        added = add_entry(*file, *ports, entry);
      } else if (file && node.is_mapping()) {
        added = add_entry(*file, node, quote("ports") + ": {" + entry + "}");
      } else if (file && node.is_scalar()) {
        // `kick_ball: soccer.KickBall` becomes a mapping, to hold its ports.
        const SourceLocation where = node.location();
        const std::size_t begin = offset_of(file->text, where.line, where.column);
        const std::size_t end = token_end(file->text, begin);
        added = {{{found->file, begin, end,
                   fmt::format("{{{}: {}, {}: {{{}}}}}", quote("type"),
                               file->text.substr(begin, end - begin), quote("ports"), entry)}},
                 {}};
      }
      if (!added.ok())
        return {{},
                fmt::format("{} binds port '{}' by name, and no ports: entry could be added "
                            "to its text: {}",
                            who, old, added.refused)};
      edits.insert(edits.end(), added.edits.begin(), added.edits.end());
    }
  }
  return {edits, {}};
}

}  // namespace

std::size_t offset_of(const std::string& text, int line, int column) {
  std::size_t at = 0;
  for (int l = 1; l < line && at < text.size(); ++l) at = next_line(text, at);
  for (int c = 1; c < column && at < text.size() && text[at] != '\n'; ++c) {
    ++at;
    while (at < text.size() && (static_cast<unsigned char>(text[at]) & 0xC0) == 0x80) ++at;
  }
  return at;
}

std::string apply_edits(const std::string& text, const std::string& file,
                        const std::vector<TextEdit>& edits) {
  std::vector<const TextEdit*> own;
  for (const auto& edit : edits) {
    if (edit.file == file) own.push_back(&edit);
  }
  std::sort(own.begin(), own.end(),
            [](const TextEdit* a, const TextEdit* b) { return a->begin > b->begin; });
  std::string result = text;
  for (const TextEdit* edit : own) {
    const std::size_t begin = std::min(edit->begin, result.size());
    result.replace(begin, std::min(edit->end, result.size()) - begin, edit->text);
  }
  return result;
}

EditedConfig load_edited(const Loaded& loaded, const std::vector<TextEdit>& edits,
                         Registry& registry, LoadOptions options) {
  EditedConfig edited;
  edited.texts = std::make_unique<Overlay>();
  if (loaded.files.files().empty()) return edited;
  for (const auto& file : loaded.files.files())
    edited.texts->set(file->path, apply_edits(file->text, file->path, edits));
  options.source = edited.texts.get();
  edited.loaded = load_config(loaded.files.files().front()->path, registry, options);
  return edited;
}

EditResult add_entry(const SourceFile& file, const Node& node, const std::string& entry) {
  const std::string& text = file.text;
  const std::size_t begin = offset_at(file, node.location());
  if (!node.is_mapping() || begin >= text.size())
    return {{}, fmt::format("no mapping at {}:{}", node.location().line, node.location().column)};
  if (text[begin] == '{') {
    const std::size_t close = flow_close(text, begin);
    if (close == std::string::npos) return {{}, "the flow mapping has no closing brace"};
    std::size_t at = close;
    while (at > begin + 1 && space(text[at - 1])) --at;
    const bool empty = at == begin + 1;
    return {{{file.path, at, at, (empty ? "" : ", ") + entry}}, {}};
  }
  const std::size_t column = begin - line_start(text, begin);
  const std::size_t end = block_end(text, begin, column);
  // An entry of several lines (`machine:` and its keys) has each line at the keys' indentation.
  std::string line = std::string(column, ' ') + entry;
  for (std::size_t at = line.find('\n'); at != std::string::npos; at = line.find('\n', at + 1))
    line.insert(at + 1, column, ' ');
  if (end == text.size() && (text.empty() || text.back() != '\n'))
    return {{{file.path, end, end, "\n" + line}}, {}};
  return {{{file.path, end, end, line + "\n"}}, {}};
}

EditResult remove_inhibition(const Loaded& loaded, const InhibitionRef& inhibition) {
  EditResult result;
  for (const Site& site : sites_of(loaded, inhibition)) result.edits.push_back(remove_item(site));
  if (result.edits.empty()) result.refused = "no inhibition " + describe(inhibition);
  return result;
}

EditResult rename_symbol(const Loaded& loaded, const ConfigIndex& index, const Occurrence& symbol,
                         const std::string& name) {
  if (symbol.kind == SymbolKind::kClass || symbol.kind == SymbolKind::kInclude)
    return {{}, "only a behaviour, actuator, layer, state or state machine can be renamed"};
  if (!is_identifier(name)) return {{}, name_error(name, "a valid name")};
  // Else it would be "already taken", by itself.
  if (name == symbol.name) return {{}, fmt::format("'{}' is already its name", name)};
  for (const auto& other : index.occurrences) {
    if (other.definition && other.kind == symbol.kind && other.scope == symbol.scope &&
        other.name == name)
      return {{}, fmt::format("'{}' is already taken", name)};
  }
  EditResult result;
  for (const auto& other : index.occurrences) {
    if (other.kind == symbol.kind && other.scope == symbol.scope && other.name == symbol.name)
      result.edits.push_back({other.file, other.begin, other.end, name});
  }
  if (symbol.kind != SymbolKind::kActuator) return result;
  EditResult ports = follow_ports(loaded, index, symbol.name, name);
  if (!ports.ok()) return ports;
  result.edits.insert(result.edits.end(), ports.edits.begin(), ports.edits.end());
  return result;
}

EditResult checked(const Loaded& loaded, EditResult result, Registry& registry,
                   const LoadOptions& options, EditedConfig* kept) {
  if (!result.ok() || loaded.diagnostics.has_errors()) return result;
  EditedConfig edited = load_edited(loaded, result.edits, registry, options);
  for (const auto& diagnostic : edited.loaded.diagnostics.items()) {
    if (diagnostic.severity != Severity::kError) continue;
    const SourceLocation& at = diagnostic.location;
    return {{},
            fmt::format("the edit would leave an error it does not know how to avoid: {}:{}:{}: {}",
                        at.file, at.line, at.column, diagnostic.message)};
  }
  if (kept != nullptr) *kept = std::move(edited);
  return result;
}

EditResult add_inhibition(const Loaded& loaded, const InhibitionRef& inhibition, bool chaining) {
  if (!sites_of(loaded, inhibition).empty())
    return {{}, fmt::format("the inhibition {} is already declared", describe(inhibition))};
  const std::vector<LayerSite> found = layers_named(loaded, inhibition.layer);
  if (found.empty()) return {{}, fmt::format("no layer '{}'", inhibition.layer)};
  const SourceFile& file = *found.front().file;
  const Node& layer = *found.front().layer;
  const bool json = format_of(file.path) == DocumentFormat::kJson;
  const std::string arrow =
      fmt::format("{} {} {}", inhibition.inhibitor, chaining ? "=>" : "->", inhibition.inhibited);
  const std::string item = json ? "\"" + arrow + "\"" : arrow;
  const Node* list = layer.find("inhibitions");
  if (!list || list->reads_as_null()) {
    if (list) return {{}, "the layer's inhibitions: is empty but not a sequence"};
    return add_entry(file, layer,
                     fmt::format("{}: [{}]", json ? "\"inhibitions\"" : "inhibitions", item));
  }
  if (!list->is_sequence()) return {{}, "the layer's inhibitions: is not a sequence"};
  const std::string& text = file.text;
  const std::size_t begin = offset_at(file, list->location());
  if (begin < text.size() && text[begin] == '[') {
    const std::size_t close = flow_close(text, begin);
    if (close == std::string::npos) return {{}, "the inhibitions' flow sequence has no ']'"};
    std::size_t at = close;
    while (at > begin + 1 && space(text[at - 1])) --at;
    return {{{file.path, at, at, (at == begin + 1 ? "" : ", ") + item}}, {}};
  }
  if (list->items().empty()) return {{}, "the layer's inhibitions: has no item to follow"};
  // A new line like the last item's, after it.
  const std::size_t last = offset_at(file, list->items().back().location());
  std::size_t dash = last;
  while (dash > 0 && text[dash - 1] == ' ') --dash;
  if (dash == 0 || text[dash - 1] != '-')
    return {{}, "the last inhibition is not a '- ' item on a line of its own"};
  --dash;
  const std::size_t start = line_start(text, dash);
  const std::size_t end = block_end(text, last, last - start);
  std::string line = text.substr(start, last - start) + item;
  std::fill(line.begin(), line.begin() + static_cast<std::ptrdiff_t>(dash - start), ' ');
  if (end == text.size() && (text.empty() || text.back() != '\n'))
    return {{{file.path, end, end, "\n" + line}}, {}};
  return {{{file.path, end, end, line + "\n"}}, {}};
}

EditResult flip_chaining(const Loaded& loaded, const InhibitionRef& inhibition) {
  EditResult result;
  for (const Site& site : sites_of(loaded, inhibition)) {
    const Node& item = *site.item;
    if (item.is_scalar()) {
      const Arrow arrow = read_arrow(item.text());
      const SourceLocation where = item.text_location(arrow.at);
      const std::size_t at = offset_at(*site.file, where);
      if (site.file->text.compare(at, 2, item.text(), arrow.at, 2) != 0) {
        return {{},
                fmt::format("the inhibition {} is written over more than one line: its "
                            "arrow cannot be changed in place",
                            describe(inhibition))};
      }
      result.edits.push_back({site.file->path, at, at + 2, arrow.chaining ? "->" : "=>"});
      continue;
    }
    const Node* chaining = item.find("chaining");
    const bool was = chaining && chaining->as_bool().value_or(false);
    if (chaining && chaining->is_scalar()) {
      const std::size_t at = offset_at(*site.file, chaining->location());
      result.edits.push_back({site.file->path, at, scalar_end(site.file->text, at, *chaining),
                              was ? "false" : "true"});
      continue;
    }
    const bool json = format_of(site.file->path) == DocumentFormat::kJson;
    EditResult added = add_entry(*site.file, item, json ? "\"chaining\": true" : "chaining: true");
    if (!added.ok()) return added;
    result.edits.insert(result.edits.end(), added.edits.begin(), added.edits.end());
  }
  if (result.edits.empty()) result.refused = "no inhibition " + describe(inhibition);
  return result;
}

EditResult set_param(const Loaded& loaded, const std::string& layer, const std::string& behaviour,
                     const std::string& param, const std::string& value) {
  for (const auto& [file, declaration] : layers_named(loaded, layer)) {
    const Node* behaviours = declaration->find("behaviours");
    if (!behaviours || !behaviours->is_mapping()) continue;
    const Node* node = behaviours->find(behaviour);
    if (!node) continue;
    const bool json = format_of(file->path) == DocumentFormat::kJson;
    auto key = [&](const std::string& word) { return json ? "\"" + word + "\"" : word; };
    const std::string& text = file->text;
    if (node->is_scalar()) {
      // `kick_ball: soccer.KickBall` becomes a mapping, to hold its params.
      const std::size_t begin = offset_at(*file, node->location());
      const std::size_t end = scalar_end(text, begin, *node);
      return {{{file->path, begin, end,
                fmt::format("{{{}: {}, {}: {{{}: {}}}}}", key("type"),
                            text.substr(begin, end - begin), key("params"), key(param), value)}},
              {}};
    }
    const Node* params = node->is_mapping() ? node->find("params") : nullptr;
    if (!params || !params->is_mapping()) {
      if (params) return {{}, fmt::format("the params of '{}' are not a mapping", behaviour)};
      return add_entry(*file, *node,
                       fmt::format("{}: {{{}: {}}}", key("params"), key(param), value));
    }
    const Node* current = params->find(param);
    if (!current) return add_entry(*file, *params, key(param) + ": " + value);
    const std::size_t begin = offset_at(*file, current->location());
    std::size_t end = begin;
    if (current->is_scalar()) {
      end = scalar_end(text, begin, *current);
    } else if (begin < text.size() && (text[begin] == '[' || text[begin] == '{')) {
      end = flow_close(text, begin);
      if (end == std::string::npos) return {{}, "the param's flow value has no closing bracket"};
      ++end;
    } else {
      return {{},
              fmt::format("param '{}' of '{}' is written as a block collection: edit its "
                          "lines instead",
                          param, behaviour)};
    }
    return {{{file->path, begin, end, value}}, {}};
  }
  return {{}, fmt::format("no behaviour '{}' in layer '{}'", behaviour, layer)};
}

}  // namespace arbiter

namespace arbiter {

namespace {

/// The edit removing entry `at` of the flow mapping `mapping` of `file`, with one comma.
TextEdit removed_flow_entry(const SourceFile& file, const Node& mapping, std::size_t at);

/// The edit adding `behaviours:` to `layer` of `file`, with its first entry `entry` (one line).
EditResult first_behaviour(const SourceFile& file, const Node& layer, const std::string& entry);

}  // namespace

EditResult add_behaviour(const Loaded& loaded, const std::string& layer, const std::string& name,
                         const std::string& type) {
  if (!is_identifier(name)) return {{}, name_error(name, "a valid name")};
  const std::vector<LayerSite> found = layers_named(loaded, layer);
  if (found.empty()) return {{}, fmt::format("no layer '{}'", layer)};
  for (const auto& site : found) {
    const Node* behaviours = site.layer->find("behaviours");
    if (behaviours && behaviours->is_mapping() && behaviours->find(name))
      return {{}, fmt::format("'{}' is already taken", name)};
  }
  const SourceFile& file = *found.front().file;
  const bool json = format_of(file.path) == DocumentFormat::kJson;
  auto quoted = [&](const std::string& word) { return json ? "\"" + word + "\"" : word; };
  const std::string value = fmt::format("{{{}: {}}}", quoted("type"), quoted(type));
  const Node* behaviours = found.front().layer->find("behaviours");
  if (!behaviours)
    return first_behaviour(file, *found.front().layer, fmt::format("{}: {}", quoted(name), value));
  if (!behaviours->is_mapping()) return {{}, "the layer's behaviours: is not a mapping"};
  return add_entry(file, *behaviours, fmt::format("{}: {}", quoted(name), value));
}

EditResult remove_behaviour(const Loaded& loaded, const std::string& layer,
                            const std::string& name) {
  EditResult result;
  for (const auto& [file, declaration] : layers_named(loaded, layer)) {
    const std::string& text = file->text;
    for (const auto& entry : declaration->entries()) {
      if (entry.key == "behaviours" && entry.value.is_mapping()) {
        const auto& items = entry.value.entries();
        const auto it = std::find_if(items.begin(), items.end(),
                                     [&](const Node::Entry& item) { return item.key == name; });
        if (it == items.end()) continue;
        if (const std::size_t open = offset_at(*file, entry.value.location());
            open < text.size() && text[open] == '{') {
          // A flow mapping (and every JSON one): its text and a comma, not its lines.
          result.edits.push_back(
              removed_flow_entry(*file, entry.value, static_cast<std::size_t>(it - items.begin())));
          continue;
        }
        const std::size_t key = offset_at(*file, it->key_location);
        const std::size_t start = line_start(text, key);
        if (text.find_first_not_of(' ', start) != key)
          return {
              {},
              fmt::format("'{}' is not written on a line of its own: remove it in the text", name)};
        // Its lines; with the key `behaviours:` when it was the only one.
        const bool only = items.size() == 1;
        const std::size_t from =
            only ? line_start(text, offset_at(*file, entry.key_location)) : start;
        // Its value: the lines indented deeper than its key.
        result.edits.push_back({file->path, from, block_end(text, key, key - start + 1), {}});
      } else if (entry.key == "inhibitions" && entry.value.is_sequence()) {
        // The inhibitions that name it go with it: all of them at once when none is left.
        std::vector<const Node*> naming;
        for (const auto& item : entry.value.items()) {
          const auto [inhibitor, inhibited] = endpoints(item);
          if (inhibitor == name || inhibited == name) naming.push_back(&item);
        }
        if (naming.empty()) continue;
        if (naming.size() == entry.value.items().size()) {
          result.edits.push_back(remove_item({file, &entry, naming.front()}));
          // remove_item takes the key with an only item; with more, the key and the block.
          if (naming.size() > 1) {
            const std::size_t key = offset_at(*file, entry.key_location);
            const std::size_t start = line_start(text, key);
            result.edits.back() = {file->path, start, block_end(text, key, key - start + 1), {}};
          }
          continue;
        }
        for (const Node* item : naming) result.edits.push_back(remove_item({file, &entry, item}));
      }
    }
  }
  if (result.edits.empty()) {
    result.refused = fmt::format("no behaviour '{}' in layer '{}'", name, layer);
    return result;
  }
  std::sort(result.edits.begin(), result.edits.end(), [](const TextEdit& a, const TextEdit& b) {
    return std::tie(a.file, a.begin) < std::tie(b.file, b.begin);
  });
  for (std::size_t i = 1; i < result.edits.size(); ++i) {
    const TextEdit& before = result.edits[i - 1];
    if (before.file == result.edits[i].file && before.end > result.edits[i].begin)
      return {{},
              fmt::format("the inhibitions naming '{}' are written too close together to be "
                          "removed one by one: remove them in the text",
                          name)};
  }
  return result;
}

}  // namespace arbiter

// Moving, actuators, ports and state queues: each an edit of one collection's items, as written.
namespace arbiter {

namespace {

/// The items of a mapping (its entries) or a sequence as written in `file`: in a block
/// collection, each item's lines (with the comment lines right above it, at its indentation)
/// without the last newline; in a flow one, the item's own text (a mapping entry's key through
/// its value). What lies between two items (blank lines, commas) belongs to neither.
struct Items {
  const SourceFile* file = nullptr;
  bool flow = false;
  std::size_t open = 0;  ///< a flow collection's opening bracket
  std::vector<std::pair<std::size_t, std::size_t>> spans;
  std::vector<std::string> prefixes;  ///< block: what starts the item's line (`      - `)
  std::string refused;
};

/// The end of the value `node` that starts at `begin` in a flow collection, or npos.
std::size_t flow_value_end(const std::string& text, std::size_t begin, const Node& node) {
  if (begin < text.size() && (text[begin] == '{' || text[begin] == '[')) {
    const std::size_t close = flow_close(text, begin);
    return close == std::string::npos ? close : close + 1;
  }
  if (!node.is_scalar() && !node.is_null()) return std::string::npos;
  return scalar_end(text, begin, node);
}

Items items_of(const SourceFile& file, const Node& node) {
  Items items;
  items.file = &file;
  const std::string& text = file.text;
  const std::size_t at = offset_at(file, node.location());
  items.flow = at < text.size() && (text[at] == '{' || text[at] == '[');
  items.open = at;
  const bool mapping = node.is_mapping();
  const std::size_t count = mapping ? node.entries().size() : node.items().size();
  for (std::size_t i = 0; i < count; ++i) {
    const Node& value = mapping ? node.entries()[i].value : node.items()[i];
    const std::size_t begin = mapping ? offset_at(file, node.entries()[i].key_location)
                                      : offset_at(file, value.location());
    if (items.flow) {
      const std::size_t end = flow_value_end(text, offset_at(file, value.location()), value);
      if (end == std::string::npos) {
        items.refused = "an item's end was not found in the text";
        return items;
      }
      items.spans.emplace_back(begin, end);
      continue;
    }
    const std::size_t start = line_start(text, begin);
    std::size_t first = text.find_first_not_of(' ', start);
    std::size_t column = begin - start;
    if (!mapping) {
      // `- item`: the dash first on its line, the item after it on the same line.
      std::size_t dash = begin;
      while (dash > start && text[dash - 1] == ' ') --dash;
      if (dash == start || text[dash - 1] != '-' || first != dash - 1) {
        items.refused = "an item is not a '- ' item on a line of its own";
        return items;
      }
      first = dash - 1;
    } else if (first != begin) {
      items.refused = "an entry does not start its line";
      return items;
    }
    // A mapping entry's value is indented deeper than its key; a sequence item's lines as deep
    // as its first.
    std::size_t end = block_end(text, begin, mapping ? column + 1 : column);
    if (end > begin && text[end - 1] == '\n') --end;
    std::size_t from = start;
    const std::size_t indent = first - start;
    while (from > 0) {
      const std::size_t above = line_start(text, from - 1);
      const std::size_t content = text.find_first_not_of(' ', above);
      if (content >= from - 1 || content - above != indent || text[content] != '#') break;
      from = above;
    }
    items.spans.emplace_back(from, end);
    items.prefixes.push_back(text.substr(start, column));
  }
  return items;
}

/// The edit that puts item `from` at position `to`, the others keeping their order; what lies
/// between the items stays where it was.
TextEdit moved_item(const Items& items, std::size_t from, std::size_t to) {
  const std::string& text = items.file->text;
  const std::size_t low = std::min(from, to), high = std::max(from, to);
  std::vector<std::size_t> order;
  for (std::size_t i = low; i <= high; ++i) {
    if (i != from) order.push_back(i);
  }
  order.insert(order.begin() + static_cast<std::ptrdiff_t>(to - low), from);
  std::string moved;
  for (std::size_t i = low; i <= high; ++i) {
    const auto [begin, end] = items.spans[order[i - low]];
    moved += text.substr(begin, end - begin);
    if (i < high) {
      moved += text.substr(items.spans[i].second, items.spans[i + 1].first - items.spans[i].second);
    }
  }
  return {items.file->path, items.spans[low].first, items.spans[high].second, moved};
}

/// The edit that inserts `item` (written on one line: `name: {type: x}`, `- a => b` without its
/// dash) before item `at` (after the last when `at` is their number): in a block collection a
/// line like its neighbour's, in a flow one with the separator its items have.
TextEdit inserted_item(const Items& items, std::size_t at, const std::string& item) {
  const std::string& path = items.file->path;
  const std::string& text = items.file->text;
  const std::size_t count = items.spans.size();
  if (items.flow) {
    if (count == 0) return {path, items.open + 1, items.open + 1, item};
    const std::string separator =
        count > 1 ? text.substr(items.spans[0].second, items.spans[1].first - items.spans[0].second)
                  : ", ";
    if (at < count) return {path, items.spans[at].first, items.spans[at].first, item + separator};
    return {path, items.spans.back().second, items.spans.back().second, separator + item};
  }
  if (at < count) {
    return {path, items.spans[at].first, items.spans[at].first, items.prefixes[at] + item + "\n"};
  }
  return {path, items.spans.back().second, items.spans.back().second,
          "\n" + items.prefixes.back() + item};
}

/// The edit that removes item `at`: its lines (with the comments above it), or in a flow
/// collection its text and the separator before it (after it, for the first).
TextEdit removed_item(const Items& items, std::size_t at) {
  const std::string& text = items.file->text;
  const auto [begin, end] = items.spans[at];
  if (!items.flow) return {items.file->path, begin, std::min(text.size(), end + 1), {}};
  if (at > 0) return {items.file->path, items.spans[at - 1].second, end, {}};
  if (items.spans.size() > 1) return {items.file->path, begin, items.spans[1].first, {}};
  return {items.file->path, begin, end, {}};
}

TextEdit removed_flow_entry(const SourceFile& file, const Node& mapping, std::size_t at) {
  return removed_item(items_of(file, mapping), at);
}

/// The entry `key` of `layer`'s mapping and its file, or a null entry.
struct EntrySite {
  const SourceFile* file = nullptr;
  const Node::Entry* entry = nullptr;
};

EntrySite entry_of(const SourceFile& file, const Node& mapping, const std::string& key) {
  for (const auto& entry : mapping.entries()) {
    if (entry.key == key) return {&file, &entry};
  }
  return {};
}

std::size_t index_of(const Node& mapping, const std::string& key) {
  const auto& entries = mapping.entries();
  const auto found = std::find_if(entries.begin(), entries.end(),
                                  [&](const Node::Entry& entry) { return entry.key == key; });
  return static_cast<std::size_t>(found - entries.begin());
}

std::string quoted_in(const std::string& path, const std::string& word) {
  return format_of(path) == DocumentFormat::kJson ? "\"" + word + "\"" : word;
}

/// The edit removing entry `at` of the mapping that `entry` (`actuators:`, `behaviours:`) holds:
/// with the key when it was the only one, since the key alone would be null.
TextEdit removed_entry(const Items& items, const Node::Entry& entry, std::size_t at) {
  if (items.flow || items.spans.size() > 1) return removed_item(items, at);
  const std::string& text = items.file->text;
  const std::size_t key = offset_of(text, entry.key_location.line(), entry.key_location.column());
  const std::size_t start = line_start(text, key);
  return {items.file->path, start, block_end(text, key, key - start + 1), {}};
}

/// The edit removing item `at` of the sequence that `entry` (`queue:`, `layers:`) holds: the
/// last one of a block sequence leaves `[]`, since the key alone would be null.
TextEdit removed_list_item(const Items& items, const Node::Entry& entry, std::size_t at) {
  if (items.flow || items.spans.size() > 1) return removed_item(items, at);
  const std::string& text = items.file->text;
  const std::size_t key = offset_of(text, entry.key_location.line(), entry.key_location.column());
  const std::size_t colon = text.find(':', key);
  return {items.file->path, colon + 1, std::min(text.size(), items.spans.front().second), " []"};
}

/// Whether `node` of `file` is written as a flow collection (and so is every JSON one).
bool flow_in(const SourceFile& file, const Node& node) {
  const std::size_t at = offset_at(file, node.location());
  return at < file.text.size() && (file.text[at] == '{' || file.text[at] == '[');
}

EditResult first_behaviour(const SourceFile& file, const Node& layer, const std::string& entry) {
  // As a person writes it: a block-style layer gets the key on a line of its own and the entry
  // under it, where the next behaviours will go; a flow-style one (and JSON) keeps one line.
  if (flow_in(file, layer))
    return add_entry(file, layer,
                     fmt::format("{}: {{{}}}", quoted_in(file.path, "behaviours"), entry));
  return add_entry(file, layer, "behaviours:\n  " + entry);
}

/// Where `index` finds uses (not the declaration) of `name` of `kind` in `scope`, as
/// `file:line:column, ...` ("" when none).
std::string uses_of(const Loaded& loaded, const ConfigIndex& index, SymbolKind kind,
                    const std::string& scope, const std::string& name) {
  std::string uses;
  for (const auto& use : index.occurrences) {
    if (use.definition || use.kind != kind || use.scope != scope || use.name != name) continue;
    const SourceFile* file = loaded.files.find(use.file);
    const std::string& text = file ? file->text : use.file;
    const std::size_t at = std::min(use.begin, text.size());
    const auto line =
        1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n');
    uses += fmt::format("{}{}:{}:{}", uses.empty() ? "" : ", ", use.file, line,
                        at - line_start(text, at) + 1);
  }
  return uses;
}

/// A state machine's declaration, in the config's file or an include.
struct MachineSite {
  const SourceFile* file = nullptr;
  const Node* machine = nullptr;
};

MachineSite machine_named(const Loaded& loaded, const std::string& machine) {
  for (const auto& file : loaded.files.files()) {
    const Node* machines =
        file->root && file->root->is_mapping() ? file->root->find("state_machines") : nullptr;
    const Node* found = machines && machines->is_mapping() ? machines->find(machine) : nullptr;
    if (found && found->is_mapping()) return {file.get(), found};
  }
  return {};
}

/// The lines of a block item `span` of `file`, indented by `shift` more columns.
std::string reindented(const std::string& text, std::pair<std::size_t, std::size_t> span,
                       std::ptrdiff_t shift) {
  std::string out;
  for (std::size_t at = span.first; at < span.second;) {
    std::size_t end = std::min(next_line(text, at), span.second);
    std::string line = text.substr(at, end - at);
    if (shift > 0) {
      line.insert(0, static_cast<std::size_t>(shift), ' ');
    } else {
      line.erase(0, std::min(line.find_first_not_of(' '), static_cast<std::size_t>(-shift)));
    }
    out += line;
    at = end;
  }
  return out;
}

}  // namespace

EditResult move_behaviour(const Loaded& loaded, const std::string& layer, const std::string& name,
                          const std::string& to_layer, std::size_t index) {
  const std::string target = to_layer.empty() ? layer : to_layer;
  const std::vector<LayerSite> from_sites = layers_named(loaded, layer);
  if (from_sites.empty()) return {{}, fmt::format("no layer '{}'", layer)};
  const LayerSite& from = from_sites.front();
  const Node* behaviours = from.layer->find("behaviours");
  if (!behaviours || !behaviours->is_mapping() || !behaviours->find(name))
    return {{}, fmt::format("no behaviour '{}' in layer '{}'", name, layer)};
  const Items source = items_of(*from.file, *behaviours);
  if (!source.refused.empty())
    return {{},
            fmt::format("the behaviours of layer '{}' are not written one to a line ({}): "
                        "move it in the text",
                        layer, source.refused)};
  const std::size_t at = index_of(*behaviours, name);
  const std::size_t count = source.spans.size();
  if (target == layer) {
    if (index >= count)
      return {{},
              fmt::format("position {} is past the end of layer '{}', which has {} "
                          "behaviour(s): positions count from 0",
                          index, layer, count)};
    if (index == at) return {{}, fmt::format("'{}' is at position {} already", name, index)};
    return {{moved_item(source, at, index)}, {}};
  }
  // To another layer: the inhibitions of its old layer cannot follow it (an inhibition joins two
  // behaviours of one layer), and are not dropped without the user's word.
  const Node* inhibitions = from.layer->find("inhibitions");
  for (std::size_t i = 0; inhibitions && inhibitions->is_sequence() && i < inhibitions->size();
       ++i) {
    const auto [inhibitor, inhibited] = endpoints(inhibitions->items()[i]);
    if (inhibitor == name || inhibited == name)
      return {{},
              fmt::format("'{}' is named by the inhibition '{} -> {}' of layer '{}', which "
                          "cannot follow it to another layer: remove it first",
                          name, inhibitor, inhibited, layer)};
  }
  const std::vector<LayerSite> to_sites = layers_named(loaded, target);
  if (to_sites.empty()) return {{}, fmt::format("no layer '{}'", target)};
  const LayerSite& to = to_sites.front();
  if (to.layer->find("interface"))
    return {{}, fmt::format("layer '{}' is an interface layer: it has no behaviours", target)};
  if (format_of(from.file->path) != format_of(to.file->path))
    return {{},
            fmt::format("layer '{}' is declared in {} and layer '{}' in {}, one JSON and one "
                        "YAML: move it in the text",
                        layer, from.file->path, target, to.file->path)};
  const Node* into = to.layer->find("behaviours");
  if (into && into->is_mapping() && into->find(name))
    return {{}, fmt::format("'{}' is already taken in layer '{}'", name, target)};
  const std::string& text = from.file->text;
  const auto span = source.spans[at];
  std::string entry = text.substr(span.first, span.second - span.first);
  EditResult result;
  result.edits.push_back(
      removed_entry(source, *entry_of(*from.file, *from.layer, "behaviours").entry, at));
  const std::size_t target_count = into && into->is_mapping() ? into->entries().size() : 0;
  if (index > target_count)
    return {{},
            fmt::format("position {} is past the end of layer '{}', which has {} "
                        "behaviour(s): positions count from 0",
                        index, target, target_count)};
  const bool one_line = entry.find('\n') == std::string::npos;
  if (!into) {
    if (!one_line)
      return {{},
              fmt::format("'{}' is written over several lines and layer '{}' has no "
                          "behaviours: yet: move it in the text",
                          name, target)};
    const std::string key = entry.substr(entry.find_first_not_of(' '));
    EditResult added = first_behaviour(*to.file, *to.layer, key);
    if (!added.ok()) return added;
    result.edits.push_back(added.edits.front());
    return result;
  }
  if (!into->is_mapping())
    return {{}, fmt::format("the behaviours: of layer '{}' are not a mapping", target)};
  const Items destination = items_of(*to.file, *into);
  if (!destination.refused.empty())
    return {{},
            fmt::format("the behaviours of layer '{}' are not written one to a line ({}): "
                        "move it in the text",
                        target, destination.refused)};
  if (destination.flow || source.flow) {
    if (!one_line)
      return {{},
              fmt::format("'{}' is written over several lines and layer '{}' declares its "
                          "behaviours on one: move it in the text",
                          name, destination.flow ? target : layer)};
    entry = entry.substr(entry.find_first_not_of(' '));
    result.edits.push_back(inserted_item(destination, index, entry));
    return result;
  }
  // Block to block: its lines, indented as the target's entries are.
  const std::size_t old_column = source.prefixes[at].size();
  const std::size_t new_column = destination.prefixes.front().size();
  entry =
      reindented(text, span,
                 static_cast<std::ptrdiff_t>(new_column) - static_cast<std::ptrdiff_t>(old_column));
  entry = entry.substr(new_column);  // inserted_item writes the first line's indentation
  result.edits.push_back(inserted_item(destination, index, entry));
  return result;
}

EditResult move_layer(const Loaded& loaded, const std::string& layer, std::size_t index) {
  if (!loaded.model) return {{}, "the config does not compile: its layers' order is not known"};
  const auto& layers = loaded.model->layers;
  const auto found = std::find_if(layers.begin(), layers.end(),
                                  [&](const LayerDecl& decl) { return decl.name.text == layer; });
  if (found == layers.end()) return {{}, fmt::format("no layer '{}'", layer)};
  if (index >= layers.size())
    return {{},
            fmt::format("position {} is past the last layer: the config has {} layer(s), "
                        "positions count from 0",
                        index, layers.size())};
  const std::size_t at = static_cast<std::size_t>(found - layers.begin());
  if (index == at) return {{}, fmt::format("layer '{}' is at position {} already", layer, index)};
  const std::vector<LayerSite> sites = layers_named(loaded, layer);
  const std::vector<LayerSite> others = layers_named(loaded, layers[index].name.text);
  if (sites.empty() || others.empty()) return {{}, fmt::format("no layer '{}' in the text", layer)};
  // An include's layers come before the including file's own: a layer moves among its file's.
  if (sites.front().file != others.front().file)
    return {{},
            fmt::format("position {} holds layer '{}' of {}, and layer '{}' is declared in {}: "
                        "a file's layers keep their place among the included ones, so move "
                        "it between the files in the text",
                        index, layers[index].name.text, others.front().file->path, layer,
                        sites.front().file->path)};
  const SourceFile& file = *sites.front().file;
  const Node& list = *file.root->find("layers");
  const Items items = items_of(file, list);
  if (!items.refused.empty())
    return {{},
            fmt::format("the layers of {} are not written one item after another ({}): move "
                        "it in the text",
                        file.path, items.refused)};
  auto position = [&](const Node* node) {
    return static_cast<std::size_t>(node - list.items().data());
  };
  return {{moved_item(items, position(sites.front().layer), position(others.front().layer))}, {}};
}

EditResult add_layer(const Loaded& loaded, const std::string& name, std::size_t index,
                     const std::string& interface) {
  if (!is_identifier(name)) return {{}, name_error(name, "a valid name")};
  if (!layers_named(loaded, name).empty())
    return {{}, fmt::format("'{}' is already taken: a layer of that name is declared", name)};
  const auto& files = loaded.files.files();
  if (files.empty() || !files.front()->root || !files.front()->root->is_mapping())
    return {{}, "the config's file is not a mapping: add the layer in the text"};
  const SourceFile& file = *files.front();
  // The config's own layers come after its includes' layers.
  std::size_t included = 0;
  for (std::size_t i = 1; i < files.size(); ++i) {
    const Node* layers =
        files[i]->root && files[i]->root->is_mapping() ? files[i]->root->find("layers") : nullptr;
    if (layers && layers->is_sequence()) included += layers->size();
  }
  const Node* layers = file.root->find("layers");
  if (layers && !layers->is_sequence()) return {{}, "the config's layers: is not a list"};
  const std::size_t own = layers ? layers->size() : 0;
  if (index == kAtEnd) index = included + own;
  if (index > included + own)
    return {{},
            fmt::format("position {} is past the end: the config has {} layer(s), positions "
                        "count from 0",
                        index, included + own)};
  if (index < included)
    return {{},
            fmt::format("position {} holds a layer of an included file: an included file's "
                        "layers come first, so the config's own start at position {}",
                        index, included)};
  auto quoted = [&](const std::string& word) { return quoted_in(file.path, word); };
  if (!layers || layers->size() == 0 || flow_in(file, *layers)) {
    const std::string flow =
        "{" + quoted("name") + ": " + quoted(name) +
        (interface.empty() ? "" : ", " + quoted("interface") + ": " + quoted(interface)) + "}";
    if (format_of(file.path) == DocumentFormat::kJson || (layers && layers->size() > 0)) {
      if (!layers) return add_entry(file, *file.root, quoted("layers") + ": [" + flow + "]");
      const Items items = items_of(file, *layers);
      if (!items.refused.empty()) return {{}, items.refused};
      return {{inserted_item(items, index - included, flow)}, {}};
    }
    // A YAML file's first layer starts a block list, the form the layers of a config take.
    std::string item = "  - name: " + name;
    if (!interface.empty()) item += "\n    interface: " + interface;
    if (!layers) return add_entry(file, *file.root, "layers:\n" + item);
    const std::string& text = file.text;
    const std::size_t open = offset_at(file, layers->location());
    const std::size_t close = flow_close(text, open);
    if (close == std::string::npos) return {{}, "the config's layers: [ has no closing bracket"};
    const std::size_t key = line_start(text, open);
    if (text.find_first_not_of(' ', key) != key)
      return {{}, "the config's layers: is not a top-level key: add the layer in the text"};
    std::size_t from = open;  // from the colon: `layers:` ends its line
    while (from > 0 && text[from - 1] == ' ') --from;
    return {{{file.path, from, close + 1, "\n" + item}}, {}};
  }
  const Items items = items_of(file, *layers);
  if (!items.refused.empty())
    return {{},
            fmt::format("the layers of {} are not written one item after another ({}): add "
                        "it in the text",
                        file.path, items.refused)};
  const std::size_t at = index - included;
  const std::string indent(items.prefixes[std::min(at, own - 1)].size(), ' ');
  std::string item = "name: " + name;
  if (!interface.empty()) item += "\n" + indent + "interface: " + interface;
  return {{inserted_item(items, at, item)}, {}};
}

EditResult remove_layer(const Loaded& loaded, const std::string& name) {
  const std::vector<LayerSite> found = layers_named(loaded, name);
  if (found.empty()) return {{}, fmt::format("no layer '{}'", name)};
  const SourceFile& file = *found.front().file;
  const Node* actuators = found.front().layer->find("actuators");
  // A layer that reads its actuators would read nothing: which sensor to drop is the user's call.
  std::string uses;
  for (const auto& other : loaded.files.files()) {
    const Node* layers =
        other->root && other->root->is_mapping() ? other->root->find("layers") : nullptr;
    for (std::size_t i = 0; actuators && actuators->is_mapping() && layers &&
                            layers->is_sequence() && i < layers->size();
         ++i) {
      const Node& layer = layers->items()[i];
      const Node* owner = layer.is_mapping() ? layer.find("name") : nullptr;
      const Node* sensors = layer.is_mapping() ? layer.find("sensors") : nullptr;
      if (!sensors || (owner && owner->is_scalar() && owner->text() == name)) continue;
      std::vector<std::string> read;
      if (sensors->is_sequence()) {
        for (const auto& sensor : sensors->items())
          if (sensor.is_scalar()) read.push_back(sensor.text());
      } else if (sensors->is_mapping()) {
        for (const auto& sensor : sensors->entries()) read.push_back(sensor.key);
      }
      for (const auto& sensor : read) {
        if (actuators->find(sensor))
          uses += fmt::format("{}layer '{}' reads its actuator '{}'", uses.empty() ? "" : "; ",
                              owner && owner->is_scalar() ? owner->text() : "?", sensor);
      }
    }
  }
  if (!uses.empty())
    return {{},
            fmt::format("layer '{}' is still used: {}. Remove those sensors first", name, uses)};
  const EntrySite list = entry_of(file, *file.root, "layers");
  const Items items = items_of(file, list.entry->value);
  if (!items.refused.empty())
    return {{},
            fmt::format("the layers of {} are not written one item after another ({}): remove "
                        "it in the text",
                        file.path, items.refused)};
  const auto at = static_cast<std::size_t>(found.front().layer - list.entry->value.items().data());
  return {{removed_list_item(items, *list.entry, at)}, {}};
}

EditResult add_actuator(const Loaded& loaded, const std::string& layer, const std::string& name,
                        const std::string& type) {
  if (!is_identifier(name)) return {{}, name_error(name, "a valid name")};
  const std::vector<LayerSite> found = layers_named(loaded, layer);
  if (found.empty()) return {{}, fmt::format("no layer '{}'", layer)};
  // Actuator names are the manager's: unique across its layers.
  for (const auto& file : loaded.files.files()) {
    const Node* layers =
        file->root && file->root->is_mapping() ? file->root->find("layers") : nullptr;
    for (std::size_t i = 0; layers && layers->is_sequence() && i < layers->size(); ++i) {
      const Node& other = layers->items()[i];
      const Node* actuators = other.is_mapping() ? other.find("actuators") : nullptr;
      const Node* owner = other.is_mapping() ? other.find("name") : nullptr;
      if (actuators && actuators->is_mapping() && actuators->find(name))
        return {{},
                fmt::format("'{}' is already taken: layer '{}' declares an actuator of that "
                            "name",
                            name, owner ? owner->text() : "?")};
    }
  }
  const SourceFile& file = *found.front().file;
  const Node& declaration = *found.front().layer;
  auto quoted = [&](const std::string& word) { return quoted_in(file.path, word); };
  const std::string value = fmt::format("{{{}: {}}}", quoted("type"), quoted(type));
  const Node* actuators = declaration.find("actuators");
  if (!actuators)
    return add_entry(file, declaration,
                     fmt::format("{}: {{{}: {}}}", quoted("actuators"), quoted(name), value));
  if (!actuators->is_mapping()) return {{}, "the layer's actuators: is not a mapping"};
  return add_entry(file, *actuators, fmt::format("{}: {}", quoted(name), value));
}

EditResult remove_actuator(const Loaded& loaded, const std::string& layer,
                           const std::string& name) {
  const std::vector<LayerSite> found = layers_named(loaded, layer);
  if (found.empty()) return {{}, fmt::format("no layer '{}'", layer)};
  const SourceFile& file = *found.front().file;
  const EntrySite list = entry_of(file, *found.front().layer, "actuators");
  if (!list.entry || !list.entry->value.is_mapping() || !list.entry->value.find(name))
    return {{}, fmt::format("no actuator '{}' in layer '{}'", name, layer)};
  // What reads or writes it would be left unbound, or bound to nothing: that is the user's
  // decision, so each use is named rather than followed.
  if (!loaded.model)
    return {{},
            "the config does not compile: what uses the actuator is not known; fix its "
            "errors first"};
  std::vector<std::string> uses;
  for (const auto& other : loaded.model->layers) {
    for (const auto& sensor : other.sensors) {
      if (sensor.text == name) uses.push_back(fmt::format("layer '{}' reads it", other.name.text));
    }
    for (const auto& binding : other.ports) {
      if (binding.port && binding.target == name)
        uses.push_back(fmt::format("port '{}' of the interface of layer '{}' is bound to it",
                                   binding.port->name, other.name.text));
    }
    for (const auto& behaviour : other.behaviours) {
      for (const auto& binding : behaviour.ports) {
        if (binding.port && binding.target == name)
          uses.push_back(fmt::format("port '{}' of '{}' is bound to it", binding.port->name,
                                     behaviour.name.text));
      }
    }
  }
  for (const auto& machine : loaded.model->state_machines) {
    for (const auto& state : machine.states) {
      for (std::size_t i = 0; state.cls && i < state.cls->ports.size(); ++i) {
        if (state.cls->ports[i].name == name)
          uses.push_back(fmt::format("state '{}' of state machine '{}' binds its port by name",
                                     state.name.text, machine.name.text));
      }
    }
  }
  if (!uses.empty()) {
    std::string all;
    for (const auto& use : uses) all += (all.empty() ? "" : "; ") + use;
    return {
        {},
        fmt::format("actuator '{}' is still used: {}. Remove or rebind those first", name, all)};
  }
  const Items items = items_of(file, list.entry->value);
  if (!items.refused.empty())
    return {{},
            fmt::format("the actuators of layer '{}' are not written one to a line ({}): "
                        "remove it in the text",
                        layer, items.refused)};
  return {{removed_entry(items, *list.entry, index_of(list.entry->value, name))}, {}};
}

EditResult wire_port(const Loaded& loaded, const std::string& layer, const std::string& behaviour,
                     const std::string& port, const std::string& target) {
  if (!is_identifier(port) || !is_identifier(target))
    return {{}, name_error(is_identifier(port) ? target : port, "a name in a port binding")};
  for (const LayerSite& site : layers_named(loaded, layer)) {
    // Named, not bound by a structured binding: a lambda below captures it.
    const SourceFile* file = site.file;
    const Node* declaration = site.layer;
    const Node* behaviours = declaration->find("behaviours");
    const Node* node =
        behaviours && behaviours->is_mapping() ? behaviours->find(behaviour) : nullptr;
    if (!node) continue;
    auto quoted = [&](const std::string& word) { return quoted_in(file->path, word); };
    const std::string entry = quoted(port) + ": " + quoted(target);
    const std::string& text = file->text;
    if (node->is_scalar()) {
      // `kick_ball: soccer.KickBall` becomes a mapping, to hold its ports.
      const std::size_t begin = offset_at(*file, node->location());
      const std::size_t end = scalar_end(text, begin, *node);
      return {{{file->path, begin, end,
                fmt::format("{{{}: {}, {}: {{{}}}}}", quoted("type"),
                            text.substr(begin, end - begin), quoted("ports"), entry)}},
              {}};
    }
    if (!node->is_mapping()) break;
    const Node* ports = node->find("ports");
    if (!ports) return add_entry(*file, *node, fmt::format("{}: {{{}}}", quoted("ports"), entry));
    if (!ports->is_mapping())
      return {{}, fmt::format("the ports: of '{}' are not a mapping", behaviour)};
    const Node* current = ports->find(port);
    if (!current) return add_entry(*file, *ports, entry);
    if (!current->is_scalar())
      return {{}, fmt::format("port '{}' of '{}' is not bound to a name", port, behaviour)};
    if (current->text() == target)
      return {{},
              fmt::format("port '{}' of '{}' is bound to '{}' already", port, behaviour, target)};
    const std::size_t begin = offset_at(*file, current->location());
    return {{{file->path, begin, scalar_end(text, begin, *current), quoted(target)}}, {}};
  }
  return {{}, fmt::format("no behaviour '{}' in layer '{}'", behaviour, layer)};
}

namespace {

/// The `queue:` of state machine `machine`, with its items as written; refused says why not.
struct QueueSite {
  MachineSite site;
  const Node::Entry* queue = nullptr;
  Items items;
  std::string refused;
};

QueueSite queue_of(const Loaded& loaded, const std::string& machine) {
  QueueSite found;
  found.site = machine_named(loaded, machine);
  if (!found.site.file) {
    found.refused = fmt::format("no state machine '{}'", machine);
    return found;
  }
  found.queue = entry_of(*found.site.file, *found.site.machine, "queue").entry;
  if (!found.queue || !found.queue->value.is_sequence()) {
    found.refused = fmt::format("state machine '{}' has no queue: list", machine);
    return found;
  }
  found.items = items_of(*found.site.file, found.queue->value);
  if (!found.items.refused.empty())
    found.refused = fmt::format(
        "the queue of state machine '{}' is not written one item after "
        "another ({}): edit it in the text",
        machine, found.items.refused);
  return found;
}

std::string past_the_end(const std::string& machine, std::size_t index, std::size_t count) {
  return fmt::format(
      "position {} is past the end of the queue of state machine '{}', which has "
      "{} state(s): positions count from 0",
      index, machine, count);
}

}  // namespace

EditResult add_queue_entry(const Loaded& loaded, const std::string& machine,
                           const std::string& state,
                           const std::vector<std::pair<std::string, std::string>>& params,
                           std::size_t index) {
  if (!is_identifier(state)) return {{}, name_error(state, "a valid name")};
  const QueueSite queue = queue_of(loaded, machine);
  if (!queue.refused.empty()) return {{}, queue.refused};
  const std::size_t count = queue.items.spans.size();
  if (index == kAtEnd) index = count;
  if (index > count) return {{}, past_the_end(machine, index, count)};
  const std::string& path = queue.site.file->path;
  std::string item = quoted_in(path, state);
  if (!params.empty()) {
    std::string values;
    for (const auto& [param, value] : params) {
      if (!is_identifier(param)) return {{}, name_error(param, "a param's name")};
      values += (values.empty() ? "" : ", ") + quoted_in(path, param) + ": " + value;
    }
    item += ": {" + values + "}";
    // In a flow sequence (and so in JSON) an item with params is a mapping of its own.
    if (queue.items.flow) item = "{" + item + "}";
  }
  return {{inserted_item(queue.items, index, item)}, {}};
}

EditResult remove_queue_entry(const Loaded& loaded, const std::string& machine, std::size_t index) {
  const QueueSite queue = queue_of(loaded, machine);
  if (!queue.refused.empty()) return {{}, queue.refused};
  const std::size_t count = queue.items.spans.size();
  if (index >= count) return {{}, past_the_end(machine, index, count)};
  // A block queue without items would be null; an empty plan is written `queue: []`.
  return {{removed_list_item(queue.items, *queue.queue, index)}, {}};
}

EditResult move_queue_entry(const Loaded& loaded, const std::string& machine, std::size_t from,
                            std::size_t to) {
  const QueueSite queue = queue_of(loaded, machine);
  if (!queue.refused.empty()) return {{}, queue.refused};
  const std::size_t count = queue.items.spans.size();
  if (from >= count) return {{}, past_the_end(machine, from, count)};
  if (to >= count) return {{}, past_the_end(machine, to, count)};
  if (from == to) return {{}, fmt::format("the state at position {} is there already", from)};
  return {{moved_item(queue.items, from, to)}, {}};
}

EditResult add_state(const Loaded& loaded, const std::string& machine, const std::string& name,
                     const std::string& type) {
  if (!is_identifier(name)) return {{}, name_error(name, "a valid name")};
  const MachineSite site = machine_named(loaded, machine);
  if (!site.file) return {{}, fmt::format("no state machine '{}'", machine)};
  const std::string& path = site.file->path;
  const std::string entry = fmt::format("{}: {{{}: {}}}", quoted_in(path, name),
                                        quoted_in(path, "type"), quoted_in(path, type));
  const Node* states = site.machine->find("states");
  if (!states)
    return add_entry(*site.file, *site.machine, quoted_in(path, "states") + ": {" + entry + "}");
  if (!states->is_mapping())
    return {{}, fmt::format("the states: of state machine '{}' are not a mapping", machine)};
  if (states->find(name))
    return {{}, fmt::format("'{}' is already taken in state machine '{}'", name, machine)};
  return add_entry(*site.file, *states, entry);
}

EditResult remove_state(const Loaded& loaded, const ConfigIndex& index, const std::string& machine,
                        const std::string& name) {
  const MachineSite site = machine_named(loaded, machine);
  if (!site.file) return {{}, fmt::format("no state machine '{}'", machine)};
  const EntrySite states = entry_of(*site.file, *site.machine, "states");
  if (!states.entry || !states.entry->value.is_mapping() || !states.entry->value.find(name))
    return {{}, fmt::format("no state '{}' in state machine '{}'", name, machine)};
  // Where it is named (the queue, a pre-emption, a state's append: or prepend:) a plan would
  // lose a step: which one to drop instead is the user's call.
  const std::string uses = uses_of(loaded, index, SymbolKind::kState, machine, name);
  if (!uses.empty())
    return {{},
            fmt::format("state '{}' of state machine '{}' is still named at {}: remove those "
                        "first",
                        name, machine, uses)};
  const Items items = items_of(*site.file, states.entry->value);
  if (!items.refused.empty())
    return {{},
            fmt::format("the states of state machine '{}' are not written one to a line ({}): "
                        "remove it in the text",
                        machine, items.refused)};
  return {{removed_entry(items, *states.entry, index_of(states.entry->value, name))}, {}};
}

namespace {

/// The edit appending `item` (a name) to the list `key` of `mapping` of `file`, or adding
/// `key: [item]` when it is missing; refused (with `named`) when the list names it already.
EditResult appended_name(const SourceFile& file, const Node& mapping, const std::string& key,
                         const std::string& item, const std::string& named) {
  const Node* list = mapping.find(key);
  if (!list)
    return add_entry(file, mapping,
                     quoted_in(file.path, key) + ": [" + quoted_in(file.path, item) + "]");
  if (!list->is_sequence()) return {{}, fmt::format("{}: is not a list", key)};
  for (const auto& named_item : list->items()) {
    if (named_item.is_scalar() && named_item.text() == item) return {{}, named};
  }
  const Items items = items_of(file, *list);
  if (!items.refused.empty())
    return {{},
            fmt::format("the {}: list is not written one item after another ({}): add it in the "
                        "text",
                        key, items.refused)};
  return {{inserted_item(items, items.spans.size(), quoted_in(file.path, item))}, {}};
}

}  // namespace

EditResult add_plugin(const Loaded& loaded, const std::string& plugin) {
  if (!is_identifier(plugin)) return {{}, name_error(plugin, "a plugin's name")};
  const auto& files = loaded.files.files();
  if (files.empty() || !files.front()->root || !files.front()->root->is_mapping())
    return {{}, "the config's file is not a mapping: add the plugin in the text"};
  return appended_name(*files.front(), *files.front()->root, "plugins", plugin,
                       fmt::format("plugin '{}' is named already", plugin));
}

EditResult add_sensor(const Loaded& loaded, const std::string& layer, const std::string& name) {
  if (!is_identifier(name)) return {{}, name_error(name, "a valid name")};
  const std::vector<LayerSite> found = layers_named(loaded, layer);
  if (found.empty()) return {{}, fmt::format("no layer '{}'", layer)};
  const Node* sensors = found.front().layer->find("sensors");
  if (sensors && sensors->is_mapping())
    return {{},
            fmt::format("the sensors of layer '{}' are written with their types: add it in "
                        "the text",
                        layer)};
  return appended_name(*found.front().file, *found.front().layer, "sensors", name,
                       fmt::format("layer '{}' reads '{}' already", layer, name));
}

EditResult remove_sensor(const Loaded& loaded, const std::string& layer, const std::string& name) {
  const std::vector<LayerSite> found = layers_named(loaded, layer);
  if (found.empty()) return {{}, fmt::format("no layer '{}'", layer)};
  const SourceFile& file = *found.front().file;
  const EntrySite list = entry_of(file, *found.front().layer, "sensors");
  if (!list.entry || !list.entry->value.is_sequence())
    return {{}, fmt::format("layer '{}' does not read '{}'", layer, name)};
  const auto& items = list.entry->value.items();
  const auto it = std::find_if(items.begin(), items.end(), [&](const Node& item) {
    return item.is_scalar() && item.text() == name;
  });
  if (it == items.end()) return {{}, fmt::format("layer '{}' does not read '{}'", layer, name)};
  const Items written = items_of(file, list.entry->value);
  if (!written.refused.empty())
    return {{},
            fmt::format("the sensors of layer '{}' are not written one item after another "
                        "({}): remove it in the text",
                        layer, written.refused)};
  return {{removed_list_item(written, *list.entry, static_cast<std::size_t>(it - items.begin()))},
          {}};
}

EditResult add_state_machine(const Loaded& loaded, const std::string& name) {
  if (!is_identifier(name)) return {{}, name_error(name, "a valid name")};
  if (machine_named(loaded, name).file)
    return {{},
            fmt::format("'{}' is already taken: a state machine of that name is declared", name)};
  const auto& files = loaded.files.files();
  if (files.empty() || !files.front()->root || !files.front()->root->is_mapping())
    return {{}, "the config's file is not a mapping: add the state machine in the text"};
  const SourceFile& file = *files.front();
  auto quoted = [&](const std::string& word) { return quoted_in(file.path, word); };
  const std::string flow =
      fmt::format("{}: {{{}: {{}}, {}: []}}", quoted(name), quoted("states"), quoted("queue"));
  const Node* machines = file.root->find("state_machines");
  // In a block mapping the machine's keys go on lines of their own, where its states and queue
  // will grow.
  const std::string block = name + ":\n  states: {}\n  queue: []";
  if (!machines) {
    if (flow_in(file, *file.root))
      return add_entry(file, *file.root, quoted("state_machines") + ": {" + flow + "}");
    return add_entry(file, *file.root,
                     fmt::format("state_machines:\n  {}:\n    states: {{}}\n    queue: []", name));
  }
  if (!machines->is_mapping()) return {{}, "the config's state_machines: is not a mapping"};
  return add_entry(file, *machines, flow_in(file, *machines) ? flow : block);
}

EditResult remove_state_machine(const Loaded& loaded, const ConfigIndex& index,
                                const std::string& name) {
  const MachineSite site = machine_named(loaded, name);
  if (!site.file) return {{}, fmt::format("no state machine '{}'", name)};
  // An owner would step nothing: whether to remove it too is the user's call.
  const std::string uses = uses_of(loaded, index, SymbolKind::kMachine, {}, name);
  if (!uses.empty())
    return {{},
            fmt::format("state machine '{}' is still named at {}: remove those first", name, uses)};
  const EntrySite machines = entry_of(*site.file, *site.file->root, "state_machines");
  const Items items = items_of(*site.file, machines.entry->value);
  if (!items.refused.empty())
    return {{},
            fmt::format("the state machines of {} are not written one to a line ({}): remove "
                        "it in the text",
                        site.file->path, items.refused)};
  return {{removed_entry(items, *machines.entry, index_of(machines.entry->value, name))}, {}};
}

}  // namespace arbiter
