// Going from a name to its declaration and uses: definition, references, rename and the
// document's symbols.

#include <fmt/format.h>

#include <algorithm>

#include "lsp/analysis.hpp"
#include "lsp/server.hpp"

namespace arbiter::lsp {

namespace {

/// The edits that keep the ports bound by name to actuator `old` bound to it as `name`: a
/// `ports:` entry for each, as a person would add it.
std::vector<TextEdit> follow_ports(const Analysis& analysis, const std::string& old,
                                   const std::string& name) {
  const auto& model = analysis.loaded.model;
  std::vector<TextEdit> edits;
  // Which ports bind by name is known only from the classes: while a behaviour's or an
  // interface's class is unknown (misspelt, or its plugin not found), it is not.
  static const std::vector<LayerDecl> kNoLayers;
  const auto& layers = model ? model->layers : kNoLayers;
  for (const auto& owner : analysis.port_owners) {
    bool known = false;
    for (const auto& layer : layers) {
      if (layer.name.text != owner.layer) continue;
      if (owner.behaviour.empty()) known = known || layer.interface != nullptr;
      for (const auto& behaviour : layer.behaviours) {
        if (behaviour.name.text == owner.behaviour) known = known || behaviour.cls != nullptr;
      }
    }
    if (!known) {
      throw RequestError{
          kRequestFailed,
          fmt::format("the class of {} is not known, so whether a port of it binds to '{}' by "
                      "name is not: fix the config's errors first",
                      owner.behaviour.empty() ? "the interface of layer '" + owner.layer + "'"
                                              : "'" + owner.behaviour + "'",
                      old)};
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
          analysis.port_owners.begin(), analysis.port_owners.end(), [&](const PortOwner& item) {
            return item.layer == layer.name.text && item.behaviour == owner;
          });
      const std::string who =
          owner.empty() ? "the interface of layer '" + layer.name.text + "'" : "'" + owner + "'";
      if (found == analysis.port_owners.end() || !found->node)
        throw RequestError{kRequestFailed, fmt::format("{} binds port '{}' by name, and its text "
                                                       "was not found to add a ports: entry",
                                                       who, old)};
      const Node& node = *found->node;
      const Node* ports = node.is_mapping() ? node.find("ports") : nullptr;
      if (ports && ports->is_mapping() && ports->find(old)) continue;  // bound explicitly
      const SourceFile* file = analysis.loaded.files.find(found->file);
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
        const Lines* lines = analysis.lines_of(found->file);
        const std::size_t end = lines ? lines->token_end(begin) : begin;
        added = {{{found->file, begin, end,
                   fmt::format("{{{}: {}, {}: {{{}}}}}", quote("type"),
                               file->text.substr(begin, end - begin), quote("ports"), entry)}},
                 {}};
      }
      if (!added.ok())
        throw RequestError{kRequestFailed,
                           fmt::format("{} binds port '{}' by name, and no ports: entry could "
                                       "be added to its text: {}",
                                       who, old, added.refused)};
      edits.insert(edits.end(), added.edits.begin(), added.edits.end());
    }
  }
  return edits;
}

}  // namespace

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
  const std::string name = params.at("newName");
  if (!is_identifier(name)) {
    throw RequestError{kRequestFailed,
                       fmt::format("'{}' is not a valid name: names are [a-z_][a-z0-9_]*", name)};
  }
  for (const auto& other : analysis->occurrences) {
    if (other.definition && other.kind == item->kind && other.scope == item->scope &&
        other.name == name) {
      throw RequestError{kRequestFailed, fmt::format("'{}' is already taken", name)};
    }
  }
  json changes = json::object();
  for (const auto& other : analysis->occurrences) {
    if (other.kind != item->kind || other.scope != item->scope || other.name != item->name)
      continue;
    const Lines* lines = analysis->lines_of(other.file);
    if (!lines) continue;
    changes[path_to_uri(other.file)].push_back(
        {{"range", lines->range(other.begin, other.end)}, {"newText", name}});
  }
  if (item->kind == Kind::kActuator)
    add_changes(*analysis, follow_ports(*analysis, item->name, name), changes);
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
