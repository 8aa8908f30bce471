// Diagnostics as the client sees them: each config's problems published per file (an included
// file's errors also on the include that leads to them), and the quick fixes offered for them.

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <utility>

#include "arbiter/catalog.hpp"
#include "lsp/analysis.hpp"
#include "lsp/server.hpp"

namespace arbiter::lsp {

namespace {

json diagnostic_json(const Diagnostic& item, const Lines* lines) {
  json range = {{"start", {{"line", 0}, {"character", 0}}},
                {"end", {{"line", 0}, {"character", 0}}}};
  if (lines && item.location.line > 0) {
    const std::size_t begin = lines->offset(item.location.line, std::max(1, item.location.column));
    range = lines->range(begin, lines->token_end(begin));
  }
  json result = {{"range", range},
                 {"severity", item.severity == Severity::kError ? 1 : 2},
                 {"code", item.code},
                 {"source", "arbiter"},
                 {"message", item.message}};
  return result;
}

std::optional<std::string> suggestion_of(const json& diagnostic) {
  static const std::regex pattern(R"(did you mean '([^']+)'\?)");
  std::smatch match;
  const std::string message = diagnostic.value("message", "");
  if (std::regex_search(message, match, pattern)) return match[1].str();
  for (const auto& info : diagnostic.value("relatedInformation", json::array())) {
    const std::string text = info.value("message", "");
    if (std::regex_search(text, match, pattern)) return match[1].str();
  }
  return std::nullopt;
}

/// A behaviour's name for a class: its last part in snake case (`soccer.KickBall`: `kick_ball`).
std::string behaviour_name_of(const std::string& cls) {
  const auto dot = cls.rfind('.');
  std::string name;
  for (const char c : cls.substr(dot == std::string::npos ? 0 : dot + 1)) {
    if (std::isupper(static_cast<unsigned char>(c))) {
      if (!name.empty() && name.back() != '_') name += '_';
      name += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    } else {
      name += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
    }
  }
  if (name.empty() || std::isdigit(static_cast<unsigned char>(name.front()))) name = "b_" + name;
  return name;
}

/// `name`, or `name_2`, `name_3`... : the first that `taken` does not hold.
std::string unused_name(const std::string& name, const std::set<std::string>& taken) {
  std::string candidate = name;
  for (int n = 2; taken.count(candidate) != 0; ++n) candidate = fmt::format("{}_{}", name, n);
  return candidate;
}

/// A queue item is named by its position, as the engine's queue operations take it, and by the
/// state it held when the action was offered: an edit between the offer and the resolve that
/// moved the queue's items must not make the action move or remove another one.
void check_queue_item(const Loaded& loaded, const json& data, std::size_t index) {
  if (!loaded.model) return;  // the operation reports the config that does not load
  const std::string machine = data.value("machine", std::string());
  const std::string state = data.value("state", std::string());
  for (const auto& declared : loaded.model->state_machines) {
    if (declared.name.text != machine) continue;
    if (index < declared.queue.size() && declared.queue[index].state.text == state) return;
    throw RequestError{kRequestFailed,
                       fmt::format("the queue of state machine '{}' changed since the action "
                                   "was offered (item {} is no longer '{}'): ask for the code "
                                   "actions again",
                                   machine, index + 1, state)};
  }
}

/// The root of `path`'s text as `analysis` parsed it, or nullptr.
const Node* root_of(const Analysis& analysis, const std::string& path) {
  const SourceFile* file = analysis.loaded.files.find(path);
  return file && file->root ? &*file->root : nullptr;
}

/// Bytes of the token at `where` (a quoted string with its quotes) in `lines`' text.
std::pair<std::size_t, std::size_t> token_at(const Lines& lines, const SourceLocation& where) {
  const std::size_t begin = lines.offset(where.line, std::max(1, where.column));
  return {begin, lines.token_end(begin)};
}

/// The layer whose `sensors:` list holds `sensor` (a use of an actuator there), or "".
std::string layer_reading(const Analysis& analysis, const Lines& lines, const Occurrence& sensor) {
  const Node* root = root_of(analysis, sensor.file);
  const Node* layers = root && root->is_mapping() ? root->find("layers") : nullptr;
  if (!layers || !layers->is_sequence()) return {};
  for (const auto& layer : layers->items()) {
    const Node* name = layer.is_mapping() ? layer.find("name") : nullptr;
    const Node* sensors = layer.is_mapping() ? layer.find("sensors") : nullptr;
    if (!name || !name->is_scalar() || !sensors || !sensors->is_sequence()) continue;
    for (const auto& item : sensors->items()) {
      const auto [begin, end] = token_at(lines, item.location());
      if (begin <= sensor.begin && sensor.end <= end) return name->text();
    }
  }
  return {};
}

/// Whether `offset` of `path` is on a key of its root mapping (`layers:`, `plugins:`, ...).
bool on_top_level_key(const Analysis& analysis, const std::string& path, const Lines& lines,
                      std::size_t offset) {
  const Node* root = root_of(analysis, path);
  if (!root || !root->is_mapping()) return false;
  return std::any_of(root->entries().begin(), root->entries().end(), [&](const Node::Entry& entry) {
    const auto [begin, end] = token_at(lines, entry.key_location);
    return begin <= offset && offset <= end;
  });
}

/// The engine's operation a code action offered without an edit names in its `data`, in the
/// studio's words (apply_operation): the one place both the offer (the operation alone, cheap:
/// no load) and the resolve (checked) compute it.
EditResult operation_of(const Analysis& analysis, const json& data) {
  const std::string op = data.value("op", "");
  if (op == "move_queue_entry") {
    check_queue_item(analysis.loaded, data, data.value("from", std::size_t{0}));
  } else if (op == "remove_queue_entry") {
    check_queue_item(analysis.loaded, data, data.value("index", std::size_t{0}));
  }
  OperationResult operation =
      apply_operation(analysis.loaded, data.dump(-1, ' ', false, json::error_handler_t::replace),
                      analysis.registry.get(), &analysis);
  if (!operation.invalid.empty()) {
    throw RequestError{kRequestFailed,
                       "not a code action of this server to resolve: " + operation.invalid};
  }
  return std::move(operation.result);
}

}  // namespace

void Server::report_plugin_path(Analysis& analysis) const {
  const Node* root = analysis.loaded.document();
  const Node* plugins = root && root->is_mapping() ? root->find("plugins") : nullptr;
  if (!plugins) return;
  for (const auto& dir : options_.plugins.path) {
    std::error_code error;
    if (std::filesystem::is_directory(dir, error)) continue;
    analysis.loaded.diagnostics
        .warning(plugins->location(), "plugin-path-not-found",
                 fmt::format("plugin directory '{}' (--plugin-path) does not exist", dir))
        .notes.push_back("the server was started with it: correct the editor's arbiter command");
  }
  analysis.loaded.diagnostics.sort();
}

void Server::publish(const std::set<std::string>& touched, const std::set<std::string>& gone,
                     std::vector<json>& out) {
  std::set<std::string> files = gone;
  for (const auto& root : touched) {
    const auto found = analyses_.find(root);
    if (found == analyses_.end()) continue;
    files.insert(root);
    for (const auto& file : found->second->loaded.files.files()) files.insert(file->path);
  }
  // Each file's diagnostics from every config that reaches it (a file two configs include
  // gets its problems once).
  std::map<std::string, json> by_file;
  std::set<std::string> seen;
  auto add = [&](const std::string& file, json diagnostic) {
    if (seen.insert(file + diagnostic.dump()).second)
      by_file[file].push_back(std::move(diagnostic));
  };
  for (const auto& [root, analysis] : analyses_) {
    const auto& loaded = analysis->loaded;
    bool relevant = touched.count(root) > 0;
    for (const auto& file : loaded.files.files()) relevant = relevant || files.count(file->path);
    if (!relevant) continue;
    // The files each of the root's includes reaches, for problems in files that are not open.
    std::map<std::string, std::vector<std::string>> includes;
    for (const auto& item : analysis->occurrences) {
      if (item.kind == Kind::kInclude) includes[item.file].push_back(item.name);
    }
    auto reaches = [&](const std::string& from, const std::string& to) {
      std::set<std::string> visited{from};
      std::vector<std::string> stack{from};
      while (!stack.empty()) {
        const std::string at = stack.back();
        stack.pop_back();
        if (at == to) return true;
        for (const auto& next : includes[at]) {
          if (visited.insert(next).second) stack.push_back(next);
        }
      }
      return false;
    };
    for (const auto& item : loaded.diagnostics.items()) {
      if (!files.count(item.location.file)) continue;
      json diagnostic = diagnostic_json(item, analysis->lines_of(item.location.file));
      json related = json::array();
      for (const auto& note : item.notes) {
        // A note without a place of its own is about the diagnostic's.
        json location = {{"uri", path_to_uri(item.location.file)}, {"range", diagnostic["range"]}};
        if (note.location) {
          const std::string path =
              std::filesystem::path(note.location->file).lexically_normal().string();
          const int line = std::max(1, note.location->line);
          const int column = std::max(1, note.location->column);
          json range = range_json(line - 1, column - 1);
          if (const Lines* lines = analysis->lines_of(path); lines && note.location->line > 0) {
            const std::size_t begin = lines->offset(line, column);
            range = lines->range(begin, lines->token_end(begin));
          }
          location = {{"uri", path_to_uri(path)}, {"range", range}};
        }
        related.push_back({{"location", location}, {"message", note.text}});
      }
      if (!related.empty()) diagnostic["relatedInformation"] = related;
      // An error in an included file that is not open shows on the root's include that leads
      // to it, or an editor that shows open files only would show nothing wrong.
      if (item.severity == Severity::kError && item.location.file != root &&
          !is_open(item.location.file)) {
        for (const auto& include : analysis->occurrences) {
          if (include.kind != Kind::kInclude || include.file != root ||
              !reaches(include.name, item.location.file))
            continue;
          json copy = diagnostic;
          const Lines* lines = analysis->lines_of(root);
          copy["range"] = lines ? lines->range(include.begin, include.end) : range_json(0, 0);
          copy["message"] =
              fmt::format("in included file {}: {}",
                          std::filesystem::path(item.location.file)
                              .lexically_relative(std::filesystem::path(root).parent_path())
                              .string(),
                          item.message);
          copy["relatedInformation"] = json::array(
              {{{"location",
                 {{"uri", path_to_uri(item.location.file)}, {"range", diagnostic["range"]}}},
                {"message", item.message}}});
          add(root, std::move(copy));
          break;
        }
      }
      add(item.location.file, std::move(diagnostic));
    }
  }
  for (const auto& file : files) {
    auto found = by_file.find(file);
    const bool any = found != by_file.end();
    // A config, and an open file checked through one, get their (empty) list too, so that an
    // editor knows they were checked.
    if (!any && !published_.count(file) && !analyses_.count(file) &&
        !(is_open(file) && analysis_of(file)))
      continue;
    out.push_back({{"jsonrpc", "2.0"},
                   {"method", "textDocument/publishDiagnostics"},
                   {"params",
                    {{"uri", path_to_uri(file)},
                     {"diagnostics", any ? std::move(found->second) : json::array()}}}});
    if (any) {
      published_.insert(file);
    } else {
      published_.erase(file);
    }
  }
}

json Server::code_actions(const json& params) const {
  const std::string uri = params.at("textDocument").at("uri");
  const std::string path = uri_to_path(uri);
  const std::string* text = text_of(path);
  json actions = json::array();
  if (!text) return actions;
  const Lines lines(*text);
  // The analysis holds the text the edits are computed on: it must be the buffer's.
  const Analysis* analysis = analysis_of(path);
  const Lines* analysed = analysis ? analysis->lines_of(path) : nullptr;
  if (analysed && analysed->text() != *text) analysis = nullptr;
  auto site_at = [&](std::size_t offset) -> const InhibitionSite* {
    for (const auto& site : analysis->inhibitions) {
      if (site.file == path && site.begin <= offset && offset <= std::max(site.begin, site.end))
        return &site;
    }
    return nullptr;
  };
  for (const auto& diagnostic :
       params.value("context", json::object()).value("diagnostics", json::array())) {
    if (diagnostic.value("source", "") != "arbiter") continue;
    if (auto name = suggestion_of(diagnostic)) {
      actions.push_back(
          {{"title", fmt::format("Change to '{}'", *name)},
           {"kind", "quickfix"},
           {"diagnostics", json::array({diagnostic})},
           {"isPreferred", true},
           {"edit",
            {{"changes",
              {{uri, json::array({{{"range", diagnostic["range"]}, {"newText", *name}}})}}}}}});
    }
    if (diagnostic.value("code", "") == "redundant-inhibition" && analysis) {
      const InhibitionSite* site = site_at(lines.offset(diagnostic["range"]["start"]));
      if (!site) continue;
      const EditResult removed =
          remove_inhibition(analysis->loaded, {site->layer, site->inhibitor, site->inhibited});
      if (!removed.ok()) continue;
      json changes = json::object();
      add_changes(*analysis, removed.edits, changes);
      actions.push_back({{"title", "Remove the inhibition: chaining already implies it"},
                         {"kind", "quickfix"},
                         {"diagnostics", json::array({diagnostic})},
                         {"edit", {{"changes", changes}}}});
    }
  }
  // The graph operations on the inhibition at the cursor, from the engine's edit operations.
  const InhibitionSite* site =
      analysis ? site_at(lines.offset(
                     params.value("range", json::object()).value("start", json::object())))
               : nullptr;
  if (site) {
    const InhibitionRef which{site->layer, site->inhibitor, site->inhibited};
    auto offer = [&](const std::string& title, const EditResult& result) {
      if (!result.ok()) return;
      json changes = json::object();
      add_changes(*analysis, result.edits, changes);
      actions.push_back(
          {{"title", title}, {"kind", "refactor.rewrite"}, {"edit", {{"changes", changes}}}});
    };
    offer(site->chaining
              ? fmt::format("Make '{} => {}' non-chaining (->)", which.inhibitor, which.inhibited)
              : fmt::format("Make '{} -> {}' chaining (=>)", which.inhibitor, which.inhibited),
          flip_chaining(analysis->loaded, which));
    offer(fmt::format("Remove the inhibition '{} {} {}'", which.inhibitor,
                      site->chaining ? "=>" : "->", which.inhibited),
          remove_inhibition(analysis->loaded, which));
  }
  const json range = params.value("range", json::object());
  // A selection over behaviours of one layer: an inhibition between its first and its last,
  // either way, as the studio's drag from one onto the other.
  if (analysis) {
    const std::size_t from = lines.offset(range.value("start", json::object()));
    const std::size_t to = lines.offset(range.value("end", json::object()));
    std::vector<const Occurrence*> selected;
    for (const auto& other : analysis->occurrences) {
      if (other.file == path && other.definition && other.kind == SymbolKind::kBehaviour &&
          from <= other.begin && other.end <= to)
        selected.push_back(&other);
    }
    if (selected.size() >= 2 && selected.front()->scope == selected.back()->scope) {
      Registry registry = make_registry_();
      for (const auto& [a, b] :
           {std::pair{selected.front(), selected.back()}, {selected.back(), selected.front()}}) {
        for (const bool chaining : {true, false}) {
          const InhibitionRef which{a->scope, a->name, b->name};
          const EditResult added =
              checked(analysis->loaded, add_inhibition(analysis->loaded, which, chaining), registry,
                      options_);
          if (!added.ok()) continue;
          json changes = json::object();
          add_changes(*analysis, added.edits, changes);
          actions.push_back({{"title", fmt::format("Add the inhibition '{} {} {}'", a->name,
                                                   chaining ? "=>" : "->", b->name)},
                             {"kind", "refactor.rewrite"},
                             {"edit", {{"changes", changes}}}});
        }
      }
    }
  }
  const Occurrence* item =
      analysis && !site ? analysis->at(path, lines.offset(range.value("start", json::object())))
                        : nullptr;
  // The operations whose edits are computed when one is chosen, as adding a behaviour's are (a
  // checked edit loads the config again): offered when the operation alone gives edits.
  const std::size_t at = lines.offset(range.value("start", json::object()));
  // The names declared of a kind, for a new element's name.
  auto defined = [&](SymbolKind kind) {
    std::set<std::string> names;
    for (const auto& other : analysis->occurrences) {
      if (other.definition && other.kind == kind) names.insert(other.name);
    }
    return names;
  };
  auto offer_lazily = [&](const std::string& title, json data) {
    data["uri"] = uri;
    try {
      if (!operation_of(*analysis, data).ok()) return;
    } catch (const RequestError&) {
      return;  // the index and the model disagree about the item: nothing sure to offer
    }
    actions.push_back({{"title", title}, {"kind", "refactor.rewrite"}, {"data", std::move(data)}});
  };
  // On a behaviour's declaration: remove it, as the studio does, with the inhibitions that name
  // it; up or down among its layer's behaviours.
  if (item && item->definition && item->kind == SymbolKind::kBehaviour) {
    offer_lazily(
        fmt::format("Remove the behaviour '{}' and the inhibitions that name it", item->name),
        {{"op", "remove_behaviour"}, {"layer", item->scope}, {"name", item->name}});
    std::size_t position = 0;
    for (const auto& other : analysis->occurrences) {
      if (&other == item) break;
      if (other.definition && other.kind == SymbolKind::kBehaviour && other.scope == item->scope &&
          other.file == item->file)
        ++position;
    }
    json move = {{"op", "move_behaviour"}, {"layer", item->scope}, {"name", item->name}};
    if (position > 0) {
      move["index"] = position - 1;
      offer_lazily(fmt::format("Move the behaviour '{}' up", item->name), move);
    }
    move["index"] = position + 1;
    offer_lazily(fmt::format("Move the behaviour '{}' down", item->name), move);
  }
  // On a layer's name: up or down in the layer order, among the layers of its file.
  if (item && item->definition && item->kind == SymbolKind::kLayer && analysis->loaded.model) {
    const auto& layers = analysis->loaded.model->layers;
    for (std::size_t index = 0; index < layers.size(); ++index) {
      if (layers[index].name.text != item->name) continue;
      json move = {{"op", "move_layer"}, {"layer", item->name}};
      if (index > 0) {
        move["index"] = index - 1;
        offer_lazily(fmt::format("Move the layer '{}' up", item->name), move);
      }
      move["index"] = index + 1;
      offer_lazily(fmt::format("Move the layer '{}' down", item->name), move);
      // Removed when no other layer reads its actuators (the operation names the readers
      // otherwise); a new layer below it, named for a rename to follow.
      offer_lazily(fmt::format("Remove the layer '{}'", item->name),
                   {{"op", "remove_layer"}, {"name", item->name}});
      offer_lazily(fmt::format("Add a layer after '{}'", item->name),
                   {{"op", "add_layer"},
                    {"name", unused_name("layer", defined(SymbolKind::kLayer))},
                    {"index", index + 1}});
      // Each actuator of another layer that it does not read yet, as a sensor.
      for (const auto& other : layers) {
        if (other.name.text == item->name) continue;
        for (const auto& actuator : other.actuators) {
          offer_lazily(
              fmt::format("Add the sensor '{}' to layer '{}'", actuator.name.text, item->name),
              {{"op", "add_sensor"}, {"layer", item->name}, {"name", actuator.name.text}});
        }
      }
      break;
    }
  }
  // On a sensor in a layer's `sensors:` list: remove it from the list.
  if (item && !item->definition && item->kind == SymbolKind::kActuator &&
      item->detail == "sensor") {
    if (const std::string layer = layer_reading(*analysis, lines, *item); !layer.empty()) {
      offer_lazily(fmt::format("Remove the sensor '{}' from layer '{}'", item->name, layer),
                   {{"op", "remove_sensor"}, {"layer", layer}, {"name", item->name}});
    }
  }
  // On a state machine's name: remove it when nothing names it (the operation gives the places
  // otherwise), or add another, empty, named for a rename to follow.
  if (item && item->definition && item->kind == SymbolKind::kMachine) {
    offer_lazily(fmt::format("Remove the state machine '{}'", item->name),
                 {{"op", "remove_state_machine"}, {"name", item->name}});
    offer_lazily("Add a state machine",
                 {{"op", "add_state_machine"},
                  {"name", unused_name("machine", defined(SymbolKind::kMachine))}});
  }
  // On a top-level key of the config's own file, where the additions to the whole config go:
  // a layer at the end, a state machine, each plugin on the plugin path that it does not name.
  if (analysis && path == analysis->root && on_top_level_key(*analysis, path, lines, at)) {
    offer_lazily(
        "Add a layer at the end",
        {{"op", "add_layer"}, {"name", unused_name("layer", defined(SymbolKind::kLayer))}});
    offer_lazily("Add a state machine",
                 {{"op", "add_state_machine"},
                  {"name", unused_name("machine", defined(SymbolKind::kMachine))}});
    for (const auto& plugin : plugins_on_path(options_.plugins))
      offer_lazily(fmt::format("Add the plugin '{}'", plugin),
                   {{"op", "add_plugin"}, {"name", plugin}});
  }
  // On an actuator's declaration: remove it, offered when nothing uses it (the operation names
  // the uses otherwise).
  if (item && item->definition && item->kind == SymbolKind::kActuator && analysis->loaded.model) {
    for (const auto& layer : analysis->loaded.model->layers) {
      const bool declares = std::any_of(
          layer.actuators.begin(), layer.actuators.end(),
          [&](const ActuatorDecl& actuator) { return actuator.name.text == item->name; });
      if (!declares) continue;
      offer_lazily(fmt::format("Remove the actuator '{}'", item->name),
                   {{"op", "remove_actuator"}, {"layer", layer.name.text}, {"name", item->name}});
      break;
    }
  }
  // On an item of a state machine's queue: up, down, or out of the queue.
  for (std::size_t i = 0; analysis && i < analysis->queue_items.size(); ++i) {
    const QueueItemSite& queued = analysis->queue_items[i];
    if (queued.file != path || at < queued.begin || at > queued.end) continue;
    json move = {{"op", "move_queue_entry"},
                 {"machine", queued.machine},
                 {"state", queued.state},
                 {"from", queued.index}};
    if (queued.index > 0) {
      move["to"] = queued.index - 1;
      offer_lazily(fmt::format("Move '{}' up in the queue", queued.state), move);
    }
    move["to"] = queued.index + 1;
    offer_lazily(fmt::format("Move '{}' down in the queue", queued.state), move);
    offer_lazily(fmt::format("Remove '{}' from the queue", queued.state),
                 {{"op", "remove_queue_entry"},
                  {"machine", queued.machine},
                  {"state", queued.state},
                  {"index", queued.index}});
    break;
  }
  // On a layer's name: a behaviour of each class the config can use, as the studio's palette
  // adds one. Its edit is computed when one is chosen (codeAction/resolve): checking every
  // class's here would load the config once per class at each move of the cursor.
  if (item && item->definition && item->kind == SymbolKind::kLayer) {
    std::set<std::string> taken;
    for (const auto& other : analysis->occurrences) {
      if (other.definition && other.kind == SymbolKind::kBehaviour && other.scope == item->name)
        taken.insert(other.name);
    }
    for (const auto& name : analysis->registry->class_names(ClassKind::kBehaviour)) {
      const std::string behaviour = unused_name(behaviour_name_of(name), taken);
      actions.push_back(
          {{"title", fmt::format("Add a behaviour of class '{}' to layer '{}'", name, item->name)},
           {"kind", "refactor.rewrite"},
           {"data",
            {{"op", "add_behaviour"},
             {"uri", uri},
             {"layer", item->name},
             {"name", behaviour},
             {"type", name}}}});
    }
  }
  return actions;
}

json Server::resolve_code_action(const json& action) const {
  const json& data = action.at("data");
  // Another server's action (an unknown op is refused by operation_of).
  if (!data.is_object() || !data.contains("uri") || !data.contains("op"))
    throw RequestError{kRequestFailed, "not a code action of this server to resolve"};
  const std::string uri = data.at("uri");
  const std::string path = uri_to_path(uri);
  const std::string* text = text_of(path);
  const Analysis* analysis = text ? analysis_of(path) : nullptr;
  const Lines* analysed = analysis ? analysis->lines_of(path) : nullptr;
  if (!analysed || analysed->text() != *text)
    throw RequestError{kRequestFailed, "the file is not open, or not a config"};
  Registry registry = make_registry_();
  const EditResult result =
      checked(analysis->loaded, operation_of(*analysis, data), registry, options_);
  if (!result.ok()) throw RequestError{kRequestFailed, result.refused};
  json changes = json::object();
  add_changes(*analysis, result.edits, changes);
  json resolved = action;
  resolved["edit"] = {{"changes", changes}};
  return resolved;
}

}  // namespace arbiter::lsp
