#include "layer_items.hpp"

#include <fmt/format.h>

#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <utility>

#include "arbiter/document.hpp"

namespace arbiter::dds {
namespace {

struct Declared {
  std::uint32_t index = 0;
  std::string type;
};

/// Walks a config and the files it includes as the engine's model does: a file's includes
/// (depth first, each file once) before its own layers.
class Walk {
 public:
  explicit Walk(std::string layer) : layer_(std::move(layer)) {}

  void enter_root(const Node& root) {
    included_.insert(canonical(root.location().file));
    visit(root);
  }

  void visit(const Node& root) {
    if (!root.is_mapping()) return;
    if (const Node* includes = root.find("include"); includes != nullptr) {
      for (const auto& item : includes->items()) {
        if (item.is_scalar()) include(item.text(), root.location().file);
      }
    }
    if (const Node* layers = root.find("layers"); layers != nullptr) {
      for (const auto& layer : layers->items()) visit_layer(layer);
    }
  }

  const std::map<std::string, Declared>& actuators() const { return actuators_; }
  const Node* layer() const { return layer_node_; }
  std::vector<LayerItem>& own_actuators() { return own_; }

 private:
  static std::string canonical(const std::string& path) {
    std::error_code error;
    return std::filesystem::weakly_canonical(path, error).string();
  }

  void include(const std::string& relative, const std::string& from) {
    const std::string path =
        (std::filesystem::path(from).parent_path() / relative).lexically_normal().string();
    if (!included_.insert(canonical(path)).second) return;
    Diagnostics ignored;  // the engine has read this file already and found it valid
    auto document = read_document(path, ignored);
    if (!document) return;
    documents_.push_back(std::make_unique<Node>(std::move(*document)));
    visit(*documents_.back());
  }

  void visit_layer(const Node& layer) {
    if (!layer.is_mapping()) return;
    const Node* name = layer.find("name");
    const bool target = name != nullptr && name->text() == layer_;
    if (target) layer_node_ = &layer;
    const Node* actuators = layer.find("actuators");
    if (actuators == nullptr) return;
    for (const auto& entry : actuators->entries()) {
      Declared declared;
      declared.index = next_++;
      if (entry.value.is_scalar()) {
        declared.type = entry.value.text();
      } else if (const Node* type = entry.value.find("type"); type != nullptr) {
        declared.type = type->text();
      }
      if (target) own_.push_back({entry.key, declared.type, entry.key_location, declared.index});
      actuators_.emplace(entry.key, std::move(declared));
    }
  }

  std::string layer_;
  std::set<std::string> included_;
  std::vector<std::unique_ptr<Node>> documents_;  // included files, alive for layer_node_
  std::map<std::string, Declared> actuators_;
  std::vector<LayerItem> own_;
  const Node* layer_node_ = nullptr;
  std::uint32_t next_ = 0;
};

}  // namespace

bool read_layer_items(const std::string& file, const std::string& layer,
                      const SourceLocation& where, LayerItems& out, Diagnostics& diagnostics) {
  constexpr const char* kWhy =
      "the DDS bridge reads its layer's actuators and sensors from the config file (the engine "
      "does not list them to interface classes yet)";
  Diagnostics reading;
  const auto root = read_document(file, reading);
  if (!root) {
    diagnostics.error(where, "class-error", fmt::format("cannot read '{}' again: {}", file, kWhy));
    return false;
  }
  if (!root->is_mapping() || root->find("name") == nullptr) {
    diagnostics.error(where, "class-error",
                      fmt::format("a dds.Bridge layer must be declared in the top-level config, "
                                  "not in an included file: {}",
                                  kWhy));
    return false;
  }
  Walk walk(layer);
  walk.enter_root(*root);
  if (walk.layer() == nullptr) {
    diagnostics.error(where, "class-error",
                      fmt::format("layer '{}' is not in '{}': {}", layer, file, kWhy));
    return false;
  }
  out.actuators = std::move(walk.own_actuators());
  out.sensors.clear();
  const auto add_sensor = [&](const std::string& name, const SourceLocation& at) {
    const auto found = walk.actuators().find(name);
    if (found == walk.actuators().end()) return;  // the engine has reported it
    out.sensors.push_back({name, found->second.type, at, found->second.index});
  };
  if (const Node* sensors = walk.layer()->find("sensors"); sensors != nullptr) {
    for (const auto& item : sensors->items()) {
      if (item.is_scalar()) add_sensor(item.text(), item.location());
    }
    for (const auto& entry : sensors->entries()) add_sensor(entry.key, entry.key_location);
  }
  return true;
}

bool read_layer_items(InitContext& ctx, LayerItems& out) {
  Diagnostics diagnostics;
  const bool ok =
      read_layer_items(ctx.location().file, ctx.name(), ctx.location(), out, diagnostics);
  for (const auto& item : diagnostics.items()) ctx.error(item.location, item.message);
  return ok;
}

}  // namespace arbiter::dds
