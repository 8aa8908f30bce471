// Going from a name to its declaration and uses: definition, references, rename and the
// document's symbols.

#include <fmt/format.h>

#include "lsp/analysis.hpp"
#include "lsp/server.hpp"

namespace arbiter::lsp {

json Server::definition(const json& params) const {
  const std::string path = uri_to_path(params.at("textDocument").at("uri"));
  const Analysis* analysis = good_analysis_of(path);
  if (!analysis) return nullptr;
  const Cursor cursor = cursor_of(params, analysis);
  const Occurrence* item = analysis->at(path, cursor.offset);
  if (!item) return nullptr;
  if (item->kind == Kind::kInclude)
    return {{"uri", path_to_uri(item->name)}, {"range", range_json(0, 0)}};
  const Occurrence* definition = analysis->definition_of(*item);
  if (!definition) return nullptr;
  return location_json(*analysis, definition->file, definition->begin, definition->end);
}

json Server::references(const json& params) const {
  const std::string path = uri_to_path(params.at("textDocument").at("uri"));
  const Analysis* analysis = good_analysis_of(path);
  json result = json::array();
  if (!analysis) return result;
  const Cursor cursor = cursor_of(params, analysis);
  const Occurrence* item = analysis->at(path, cursor.offset);
  if (!item || item->kind == Kind::kInclude) return result;
  const bool declaration =
      params.value("context", json::object()).value("includeDeclaration", true);
  for (const auto& other : analysis->occurrences) {
    if (other.kind != item->kind || other.scope != item->scope || other.name != item->name)
      continue;
    if (other.definition && !declaration) continue;
    result.push_back(location_json(*analysis, other.file, other.begin, other.end));
  }
  return result;
}

json Server::rename(const json& params) const {
  const std::string path = uri_to_path(params.at("textDocument").at("uri"));
  const Analysis* analysis = analysis_of(path);
  if (!analysis) throw RequestError{kRequestFailed, "the file is not open"};
  const Cursor cursor = cursor_of(params, analysis);
  const Occurrence* item = analysis->at(path, cursor.offset);
  if (!item || item->kind == Kind::kClass || item->kind == Kind::kInclude) {
    throw RequestError{kRequestFailed,
                       "only a behaviour, actuator, layer, state or state machine can be renamed"};
  }
  // Checked on a fresh registry, into which the config's plugins are loaded again.
  Registry registry = make_registry_();
  const EditResult renamed = checked(
      analysis->loaded, rename_symbol(analysis->loaded, *analysis, *item, params.at("newName")),
      registry, options_);
  if (!renamed.ok()) throw RequestError{kRequestFailed, renamed.refused};
  json changes = json::object();
  add_changes(*analysis, renamed.edits, changes);
  return {{"changes", changes}};
}

json Server::symbols(const json& params) const {
  const std::string path = uri_to_path(params.at("textDocument").at("uri"));
  const Analysis* analysis = good_analysis_of(path);
  json result = json::array();
  if (!analysis) return result;
  const Lines* lines = analysis->lines_of(path);
  if (!lines) return result;
  auto symbol = [&](const Occurrence& item, int kind, const std::string& detail) {
    json range = lines->range(item.begin, item.end);
    return json{{"name", item.name},       {"kind", kind},
                {"detail", detail},        {"range", range},
                {"selectionRange", range}, {"children", json::array()}};
  };
  json* layer = nullptr;
  json* machine = nullptr;
  std::string machine_name;
  for (const auto& item : analysis->occurrences) {
    if (item.file != path) continue;
    if (item.kind == Kind::kLayer) {
      result.push_back(symbol(item, 3, "layer"));
      layer = &result.back();
      machine = nullptr;
    } else if (item.kind == Kind::kMachine && item.definition) {
      result.push_back(symbol(item, 23, "state machine"));
      machine = &result.back();
      machine_name = item.name;
      layer = nullptr;
    } else if (item.kind == Kind::kBehaviour && item.definition && layer) {
      (*layer)["children"].push_back(symbol(item, 5, item.detail));
    } else if (item.kind == Kind::kActuator && item.definition && layer) {
      (*layer)["children"].push_back(symbol(item, 8, "actuator " + item.detail));
    } else if (item.kind == Kind::kActuator && item.detail == "sensor" && layer) {
      (*layer)["children"].push_back(symbol(item, 13, "sensor"));
    } else if (item.kind == Kind::kState && item.definition && machine &&
               item.scope == machine_name) {
      (*machine)["children"].push_back(symbol(item, 12, item.detail));
    }
  }
  return result;
}

}  // namespace arbiter::lsp
