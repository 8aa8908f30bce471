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
  const std::string line = std::string(column, ' ') + entry;
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
  if (!is_identifier(name))
    return {{}, fmt::format("'{}' is not a valid name: names are [a-z_][a-z0-9_]*", name)};
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

EditResult add_behaviour(const Loaded& loaded, const std::string& layer, const std::string& name,
                         const std::string& type) {
  if (!is_identifier(name))
    return {{}, fmt::format("'{}' is not a valid name: names are [a-z_][a-z0-9_]*", name)};
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
    return add_entry(file, *found.front().layer,
                     fmt::format("{}: {{{}: {}}}", quoted("behaviours"), quoted(name), value));
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
        const std::size_t key = offset_at(*file, it->key_location);
        const std::size_t start = line_start(text, key);
        if (text.find_first_not_of(' ', start) != key)
          return {{},
                  fmt::format("'{}' is declared in a flow mapping: remove it in the text", name)};
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
          std::string inhibitor, inhibited;
          if (item.is_scalar()) {
            const Arrow arrow = read_arrow(item.text());
            inhibitor = arrow.inhibitor;
            inhibited = arrow.inhibited;
          } else if (const Node* a = item.find("inhibitor"), *b = item.find("inhibited");
                     item.is_mapping() && a && b && a->is_scalar() && b->is_scalar()) {
            inhibitor = a->text();
            inhibited = b->text();
          }
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
