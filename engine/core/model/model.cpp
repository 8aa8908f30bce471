// The model stage's top level: the entry points of arbiter/model.hpp, the keys at the top of the
// config and of each file it includes, and the includes themselves (cycles, files merged once).
#include <cmath>
#include <filesystem>

#include <fmt/format.h>

#include "arbiter/fields.hpp"
#include "arbiter/model.hpp"
#include "core/model/builder.hpp"

namespace arbiter {

const LayerDecl* Model::find_layer(std::string_view name) const {
  for (const auto& layer : layers) {
    if (layer.name.text == name) return &layer;
  }
  return nullptr;
}

const ActuatorDecl* Model::find_actuator(std::string_view name) const {
  for (const auto& layer : layers) {
    for (const auto& actuator : layer.actuators) {
      if (actuator.name.text == name) return &actuator;
    }
  }
  return nullptr;
}

const char* to_string(FaultPolicy policy) {
  switch (policy) {
    case FaultPolicy::kInactive:
      return "inactive";
    case FaultPolicy::kDisable:
      return "disable";
    case FaultPolicy::kStop:
      return "stop";
  }
  return "?";
}

bool is_identifier(std::string_view text) {
  if (text.empty() || text.size() > kMaxNameLength) return false;
  if (!(text[0] == '_' || (text[0] >= 'a' && text[0] <= 'z'))) return false;
  for (char c : text) {
    if (!(c == '_' || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9'))) return false;
  }
  return true;
}

std::string name_error(std::string_view text, std::string_view what) {
  if (text.size() > kMaxNameLength) {
    constexpr std::size_t kShown = 32;
    std::size_t cut = kShown;
    // Not inside a UTF-8 character: back to the start of the one at the cut.
    while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;
    return fmt::format("'{}…' ({} characters) is not {}: names are at most {} characters",
                       text.substr(0, cut), text.size(), what, kMaxNameLength);
  }
  return fmt::format("'{}' is not {}: names are lower-case identifiers ([a-z_][a-z0-9_]*)", text,
                     what);
}

namespace detail {

Model ModelBuilder::build(const Node& root) {
  model_.location = root.location();
  read_file(root, /*is_root=*/true);
  check_layers();
  for (auto& machine : model_.state_machines) check_state_machine(machine);
  check_machine_ownership();
  return std::move(model_);
}

void ModelBuilder::read_file(const Node& root, bool is_root) {
  const std::string file = root.location().file;  // a copy: location() returns by value
  model_.files.push_back(file);
  if (!root.is_mapping()) {
    diagnostics_.error(root.location(), "wrong-type",
                       fmt::format("a config must be a mapping{}, found {}",
                                   is_root ? " starting with 'arbiter: 1'" : "",
                                   root.is_null() ? "an empty document" : root.describe()));
    return;
  }
  // `$schema` lets JSON editors find the schema, as the yaml-language-server comment does.
  std::vector<std::string_view> allowed = {"arbiter", "include", "layers", "state_machines",
                                           "$schema"};
  // An included file may not set them, but they are known there too: setting one is reported
  // below as what it is, not as an unknown key.
  static constexpr std::string_view kRootOnly[] = {"name",      "rate_hz", "steps",       "plugins",
                                                   "normalise", "lint",    "on_exception"};
  allowed.insert(allowed.end(), std::begin(kRootOnly), std::end(kRootOnly));
  Fields fields(root, is_root ? "the config" : "an included file", allowed, diagnostics_);
  if (!is_root) {
    for (auto key : kRootOnly) {
      if (fields.optional(key) == nullptr) continue;
      diagnostics_.error(fields.key_location(key), "unknown-key",
                         fmt::format("'{}' can only be set by the top-level config, not by an "
                                     "included file",
                                     key));
    }
  }

  const Node* version = fields.optional("arbiter");
  if (version == nullptr && is_root && fields.ok()) {
    diagnostics_.error(root.location(), "missing-key", "the config is missing its format version")
        .notes.push_back("a config starts with 'arbiter: 1'");
  }
  if (version != nullptr && version->as_int() != 1) {
    if (const auto number = version->as_int()) {
      diagnostics_.error(version->location(), "bad-version",
                         fmt::format("unsupported format version {}; this Arbiter reads "
                                     "version 1",
                                     *number));
    } else {
      add_quote_hint(diagnostics_.error(version->location(), "wrong-type",
                                        fmt::format("the format version 'arbiter' must be the "
                                                    "integer 1, found {}",
                                                    version->describe())),
                     *version);
    }
  }
  if (is_root) {
    if (const Node* name = fields.required("name")) {
      if (auto text = read_name(*name, "the config")) model_.name = *text;
    }
    if (const Node* rate = fields.optional("rate_hz")) {
      const auto value = rate->as_double();
      if (!value || !std::isfinite(*value) || *value <= 0.0) {
        // 1e999999 is positive, but not a number a loop can run at.
        diagnostics_.error(
            rate->location(), value ? "out-of-range" : "wrong-type",
            fmt::format("'rate_hz' must be a {}positive number, found {}",
                        value && !std::isfinite(*value) ? "finite " : "", rate->describe()));
      } else {
        model_.rate_hz = *value;
      }
    }
    if (const Node* steps = fields.optional("steps")) {
      // The same bound as `arbiter run --steps`.
      constexpr long long kMaxSteps = 1LL << 40;
      const auto value = steps->as_int();
      if (!value || *value < 1 || *value > kMaxSteps) {
        diagnostics_.error(steps->location(), value ? "out-of-range" : "wrong-type",
                           fmt::format("'steps' must be an integer in [1, {}], found {}", kMaxSteps,
                                       steps->describe()));
      } else {
        model_.steps = static_cast<std::uint64_t>(*value);
      }
    }
    if (const Node* normalise = fields.optional("normalise")) {
      if (auto value = read_bool(*normalise, "normalise")) model_.normalise = *value;
    }
    if (const Node* lint = fields.optional("lint")) read_lint(*lint, model_.lint_ignore);
    if (const Node* policy = fields.optional("on_exception")) {
      if (auto value = read_fault_policy(*policy)) model_.on_exception = *value;
    }
    if (const Node* plugins = fields.optional("plugins")) {
      for_each_item(*plugins, "plugins", [&](const Node& item) {
        // `{python: MODULE}`: a Python module's classes, which the Python module `arbiter`
        // registers before the load (load_plugins() reports it anywhere else).
        if (item.is_mapping()) {
          const Node* module = item.find("python");
          if (module == nullptr || item.size() != 1) {
            diagnostics_.error(item.location(), "wrong-type",
                               fmt::format("expected a plugin name or path, or {{python: MODULE}}, "
                                           "found {}",
                                           item.describe()));
          } else {
            read_string(*module, "a Python module name");
          }
          return;
        }
        if (auto text = read_string(item, "a plugin name or path, or {python: MODULE}")) {
          model_.plugins.push_back({*text, item.location()});
        }
      });
    }
  }
  if (const Node* includes = fields.optional("include")) {
    for_each_item(*includes, "include", [&](const Node& item) {
      if (auto text = read_string(item, "a file path")) include(*text, item.location());
    });
  }
  if (const Node* layers = fields.optional("layers")) {
    for_each_item(*layers, "layers", [&](const Node& item) { read_layer(item); });
  }
  if (const Node* machines = fields.optional("state_machines")) {
    read_state_machines(*machines);
  }
}

void ModelBuilder::include(const std::string& relative, const SourceLocation& where) {
  namespace fs = std::filesystem;
  const fs::path base = fs::path(where.file).parent_path();
  const std::string path = (base / relative).lexically_normal().string();
  std::error_code error;
  std::string canonical = fs::weakly_canonical(path, error).string();
  // Unresolvable (a symbolic link loop): its own name, so that reading it reports why.
  if (error) canonical = path;
  for (std::size_t i = 0; i < include_stack_.size(); ++i) {
    if (include_stack_[i] != canonical) continue;
    std::string cycle;
    for (std::size_t k = i; k < include_names_.size(); ++k) cycle += include_names_[k] + " -> ";
    auto& diagnostic = diagnostics_.error(
        where, "include-cycle", fmt::format("include cycle: {}{}", cycle, include_names_[i]));
    for (auto file = include_chain_.rbegin(); file != include_chain_.rend(); ++file) {
      diagnostic.notes.push_back("included from " + *file);
    }
    return;
  }
  if (!included_.insert(canonical).second) return;  // each file is merged once
  Diagnostics reading;
  const Node* document = files_.read(path, reading);
  for (const auto& item : reading.items()) {
    // A missing include is the including line's problem; report it there.
    if (item.location.line == 0) {
      auto& error = diagnostics_.error(
          where, item.code, fmt::format("cannot include '{}': {}", relative, item.message));
      if (path != relative) error.notes.push_back(fmt::format("looked for '{}'", path));
    } else {
      diagnostics_.error(item.location, item.code, item.message).notes = item.notes;
    }
  }
  if (!document) return;
  include_stack_.push_back(canonical);
  include_names_.push_back(path);
  include_chain_.push_back(fmt::format("{}", to_string(where)));
  read_file(*document, /*is_root=*/false);
  include_chain_.pop_back();
  include_names_.pop_back();
  include_stack_.pop_back();
}

void ModelBuilder::enter_root(const std::string& file) {
  std::error_code error;
  const std::string canonical = std::filesystem::weakly_canonical(file, error).string();
  include_stack_.push_back(canonical);
  include_names_.push_back(file);
  included_.insert(canonical);
}

void ModelBuilder::seed(const Model& model) {
  model_.layers = model.layers;
  pending_layers_.resize(model_.layers.size());
  for (const auto& layer : model_.layers) {
    for (const auto& actuator : layer.actuators) {
      actuator_index_[actuator.name.text] = {layer.name.text, actuator.name.location,
                                             actuator.type};
    }
  }
}

std::optional<Declaration> ModelBuilder::redeclare(ClassKind kind, const Node& type,
                                                   const Node* params, const Node* ports,
                                                   std::optional<std::size_t> layer,
                                                   const std::string& owner,
                                                   const SourceLocation& owner_at) {
  const std::size_t errors = diagnostics_.error_count();
  Declaration declaration;
  declaration.cls = read_class(type, kind, owner);
  if (declaration.cls == nullptr) return std::nullopt;
  // A state's required params may come per queue entry; a replacement has none of those.
  declaration.params = read_params(*declaration.cls, params, owner_at, owner);
  if (layer) {
    declaration.ports = bind_ports(*declaration.cls, ports, model_.layers[*layer], owner, owner_at);
  } else if (ports != nullptr) {
    diagnostics_.error(ports->location(), "unknown-key",
                       fmt::format("{} has no ports: a state reads and writes through the "
                                   "behaviour that steps its machine",
                                   owner));
  }
  if (diagnostics_.error_count() != errors) return std::nullopt;
  return declaration;
}

}  // namespace detail

std::vector<Param> check_state_params(const StateDecl& state, const Node* overrides,
                                      const SourceLocation& where, const Registry& registry,
                                      Diagnostics& diagnostics) {
  SourceFiles no_files;
  return detail::ModelBuilder(registry, diagnostics, no_files)
      .check_instance_params(state, overrides, where);
}

std::optional<Declaration> redeclare(const Model& model, ClassKind kind, const Node& type,
                                     const Node* params, const Node* ports,
                                     std::optional<std::size_t> layer, const std::string& owner,
                                     const SourceLocation& owner_at, const Registry& registry,
                                     Diagnostics& diagnostics) {
  SourceFiles no_files;
  detail::ModelBuilder builder(registry, diagnostics, no_files);
  builder.seed(model);
  return builder.redeclare(kind, type, params, ports, layer, owner, owner_at);
}

Model build_model(const Node& root, const Registry& registry, Diagnostics& diagnostics,
                  const ReadLimits& limits) {
  SourceFiles files(disk(), limits);
  return build_model(root, registry, diagnostics, files);
}

Model build_model(const Node& root, const Registry& registry, Diagnostics& diagnostics,
                  SourceFiles& files) {
  detail::ModelBuilder builder(registry, diagnostics, files);
  builder.enter_root(root.location().file);
  return builder.build(root);
}

}  // namespace arbiter
