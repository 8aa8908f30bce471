#include "arbiter/model.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include "fields.hpp"

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
  if (text.empty()) return false;
  if (!(text[0] == '_' || (text[0] >= 'a' && text[0] <= 'z'))) return false;
  for (char c : text) {
    if (!(c == '_' || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9'))) return false;
  }
  return true;
}

namespace {

using detail::Fields;

class ModelBuilder {
 public:
  ModelBuilder(const Registry& registry, Diagnostics& diagnostics, SourceFiles& files)
      : registry_(registry), diagnostics_(diagnostics), files_(files) {}

  Model build(const Node& root) {
    model_.location = root.location();
    read_file(root, /*is_root=*/true);
    check_layers();
    for (auto& machine : model_.state_machines) check_state_machine(machine);
    check_machine_ownership();
    return std::move(model_);
  }

 private:
  // Raw per-layer parts kept until every actuator of every file is known.
  // The keys written beside a behaviour's `params:` while its params are read.
  const std::vector<std::pair<std::string, std::size_t>>* misplaced_ = nullptr;

  struct PendingLayer {
    const Node* sensors = nullptr;
    const Node* behaviours = nullptr;
    const Node* inhibitions = nullptr;
    const Node* ports = nullptr;
    const Node* params = nullptr;
    SourceLocation location;
    std::vector<std::string> behaviour_names;  // every key of `behaviours:`, valid or not
    // A sensor that names no actuator but is close to one: the actuator meant and the error
    // reported, so that ports reading the actuator meant are notes of that one error.
    std::vector<std::pair<std::string, std::size_t>> misspelt_sensors;
  };
  struct PendingMachine {
    const Node* node = nullptr;
  };

  // --- files and includes --------------------------------------------------------------------

  void read_file(const Node& root, bool is_root) {
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
    if (is_root) {
      for (auto key :
           {"name", "rate_hz", "steps", "plugins", "normalise", "lint", "on_exception"}) {
        allowed.emplace_back(key);
      }
    }
    static constexpr std::string_view kRootOnly[] = {
        "name", "rate_hz", "steps", "plugins", "normalise", "lint", "on_exception"};
    if (!is_root) allowed.insert(allowed.end(), std::begin(kRootOnly), std::end(kRootOnly));
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
                             fmt::format("'steps' must be an integer in [1, {}], found {}",
                                         kMaxSteps, steps->describe()));
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
          if (auto text = read_string(item, "a plugin name or path")) {
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

  void include(const std::string& relative, const SourceLocation& where) {
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

 public:
  void enter_root(const std::string& file) {
    std::error_code error;
    const std::string canonical = std::filesystem::weakly_canonical(file, error).string();
    include_stack_.push_back(canonical);
    include_names_.push_back(file);
    included_.insert(canonical);
  }

 private:
  // --- scalar readers --------------------------------------------------------------------------

  template <typename F>
  void for_each_item(const Node& node, std::string_view what, F&& visit) {
    if (node.reads_as_null()) return;  // `key:` with nothing after it: no items
    if (!node.is_sequence()) {
      auto& error =
          diagnostics_.error(node.location(), "wrong-type",
                             fmt::format("'{}' must be a list, found {}", what, node.describe()));
      if (node.is_scalar()) {
        error.notes.push_back(fmt::format("write [{}] for a list of one", node.text()));
      }
      return;
    }
    for (const auto& item : node.items()) visit(item);
  }

  /// Explains why a quoted scalar is not the number or boolean it looks like.
  static void add_quote_hint(Diagnostic& diagnostic, const Node& node) {
    if (!node.is_scalar() || !node.quoted()) return;
    Node unquoted = node;
    unquoted.set_scalar(node.text(), /*quoted=*/false);
    if (unquoted.as_double() || unquoted.as_bool()) {
      diagnostic.notes.push_back(
          fmt::format("quotes make '{}' a string; write it without quotes", node.text()));
    }
  }

  std::optional<std::string> read_string(const Node& node, std::string_view expected) {
    if (!node.is_scalar() || (!node.quoted() && node.reads_as_null())) {
      diagnostics_.error(node.location(), "wrong-type",
                         fmt::format("expected {}, found {}", expected, node.describe()));
      return std::nullopt;
    }
    return node.text();
  }

  std::optional<std::string> read_identifier(const Node& node, std::string_view what) {
    auto text = read_string(node, fmt::format("{} (an identifier)", what));
    if (!text) return std::nullopt;
    if (!check_identifier(*text, node.location(), what)) return std::nullopt;
    return text;
  }

  /// A name that is reported when it is not an identifier but still returned, so that the rest
  /// of its item is checked (and named in messages) as written.
  std::optional<std::string> read_name(const Node& node, std::string_view what) {
    auto text = read_string(node, fmt::format("{} (an identifier)", what));
    if (text) check_identifier(*text, node.location(), what);
    return text;
  }

  /// `KickBall`, `head-angle`, `2fast` → `kick_ball`, `head_angle`, `_2fast`.
  static std::string to_identifier(std::string_view text) {
    std::string out;
    for (char c : text) {
      if ((static_cast<unsigned char>(c) & 0x80) != 0) return {};  // no ASCII spelling to offer
    }
    for (std::size_t i = 0; i < text.size(); ++i) {
      const auto c = static_cast<unsigned char>(text[i]);
      if (std::isupper(c) != 0) {
        const bool after_word =
            i > 0 && (std::islower(static_cast<unsigned char>(text[i - 1])) != 0 ||
                      std::isdigit(static_cast<unsigned char>(text[i - 1])) != 0);
        if (after_word && !out.empty() && out.back() != '_') out += '_';
        out += static_cast<char>(std::tolower(c));
      } else if (std::islower(c) != 0 || std::isdigit(c) != 0) {
        out += static_cast<char>(c);
      } else if (!out.empty() && out.back() != '_') {
        out += '_';
      }
    }
    while (!out.empty() && out.back() == '_') out.pop_back();
    if (!out.empty() && std::isdigit(static_cast<unsigned char>(out[0])) != 0) out.insert(0, "_");
    return out;
  }

  bool check_identifier(const std::string& text, const SourceLocation& where,
                        std::string_view what) {
    if (is_identifier(text)) return true;
    auto& error = diagnostics_.error(
        where, "bad-identifier",
        fmt::format("'{}' is not a valid name for {}: names are lower-case identifiers "
                    "([a-z_][a-z0-9_]*)",
                    text, what));
    if (const auto fixed = to_identifier(text); !fixed.empty() && fixed != text) {
      error.notes.push_back(fmt::format("did you mean '{}'?", fixed));
    }
    return false;
  }

  std::optional<FaultPolicy> read_fault_policy(const Node& node) {
    static const std::vector<std::string> kChoices = {"inactive", "disable", "stop"};
    if (node.is_scalar() && !node.reads_as_null()) {
      for (std::size_t i = 0; i < kChoices.size(); ++i) {
        if (node.text() == kChoices[i]) return static_cast<FaultPolicy>(i);
      }
    }
    auto& error = diagnostics_.error(
        node.location(), node.is_scalar() ? "out-of-range" : "wrong-type",
        fmt::format("'on_exception' must be inactive, disable or stop, found {}", node.describe()));
    if (node.is_scalar()) error.notes.push_back(suggest(node.text(), kChoices, "allowed"));
    return std::nullopt;
  }

  std::optional<bool> read_bool(const Node& node, std::string_view what) {
    auto value = node.as_bool();
    if (!value) {
      auto& error = diagnostics_.error(
          node.location(), "wrong-type",
          fmt::format("'{}' must be true or false, found {}", what, node.describe()));
      add_quote_hint(error, node);
      static const std::vector<std::string> kYaml11 = {"yes", "no", "on", "off", "y", "n"};
      std::string lower = node.is_scalar() ? node.text() : std::string();
      for (auto& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      if (!node.quoted() && std::find(kYaml11.begin(), kYaml11.end(), lower) != kYaml11.end()) {
        error.notes.push_back(
            fmt::format("'{}' is a string in YAML 1.2; write true or false", node.text()));
      }
    }
    return value;
  }

  /// `lint: {ignore: [code, ...]}`. The codes are checked by the lint stage, which defines them.
  void read_lint(const Node& node, std::vector<Name>& ignore) {
    Fields fields(node, "'lint'", {"ignore"}, diagnostics_);
    if (const Node* codes = fields.optional("ignore")) {
      for_each_item(*codes, "ignore", [&](const Node& item) {
        if (auto text = read_string(item, "a lint code")) {
          ignore.push_back({*text, item.location()});
        }
      });
    }
  }

  /// Whether `name` (`soccer.KickBall`) belongs to a plugin the config lists (by name or as a
  /// path to `arbiter_soccer.so`) but that registered no class: it was not found or not loaded.
  bool from_unloaded_plugin(const std::string& name) const {
    const auto dot = name.find('.');
    if (dot == std::string::npos) return false;
    const std::string plugin = name.substr(0, dot);
    bool listed = false;
    for (const auto& entry : model_.plugins) {
      const std::string stem = std::filesystem::path(entry.text).stem().string();
      listed = listed || entry.text == plugin || stem == "arbiter_" + plugin;
    }
    if (!listed) return false;
    // A loaded plugin's classes name its library in their origin.
    const std::string library = fmt::format("arbiter_{}.so)", plugin);
    for (const auto& [key, info] : registry_.classes()) {
      if (info.origin.size() >= library.size() &&
          info.origin.compare(info.origin.size() - library.size(), library.size(), library) == 0) {
        return false;
      }
    }
    return true;
  }

  /// "a behaviour class", "an interface class".
  static std::string a_class(ClassKind kind) {
    return fmt::format("{} {} class", kind == ClassKind::kInterface ? "an" : "a", to_string(kind));
  }

  const ClassInfo* read_class(const Node& node, ClassKind kind, std::string_view what) {
    auto text = read_string(node, fmt::format("the class of {}", what));
    if (!text) return nullptr;
    const ClassInfo* cls = registry_.find_class(kind, *text);
    if (cls == nullptr) cls = registry_.find_any_class(*text);
    if (cls == nullptr) {
      // A class of a listed plugin that did not load: the plugin's error is the one mistake.
      if (from_unloaded_plugin(*text) && diagnostics_.has_errors()) return nullptr;
      const auto known = registry_.class_names(kind);
      auto& error =
          diagnostics_.error(node.location(), "unknown-class",
                             fmt::format("unknown {} class '{}'", to_string(kind), *text));
      const auto hint = suggest(*text, known);
      error.notes.push_back(
          hint.empty() ? fmt::format("no {} classes are registered", to_string(kind)) : hint);
      // `soccer.KickBall` that is not a typo of a known class probably lives in a plugin.
      if (!closest(*text, known) && text->find('.') != std::string::npos) {
        error.notes.push_back(
            "a plugin's classes are known once the plugin is listed under 'plugins:'");
      }
      return nullptr;
    }
    if (cls->kind != kind) {
      auto& error = diagnostics_.error(
          node.location(), "wrong-class-kind",
          fmt::format("'{}' is {}; {} needs {}", *text, a_class(cls->kind), what, a_class(kind)));
      const auto hint = suggest(*text, registry_.class_names(kind), "known");
      if (!hint.empty()) error.notes.push_back(hint);
      return nullptr;
    }
    return cls;
  }

  // --- params --------------------------------------------------------------------------------

  std::optional<ParamValue> read_param(const ParamSpec& spec, const Node& node,
                                       std::string_view owner) {
    // Reports at `at`: the whole value, or the one item of a list that is wrong.
    auto fail = [&](std::string_view expected, const Node& at) -> std::optional<ParamValue> {
      const std::string found = &at == &node ? fmt::format(", found {}", node.describe())
                                             : fmt::format("; found {} in it", at.describe());
      add_quote_hint(diagnostics_.error(at.location(), "wrong-type",
                                        fmt::format("param '{}' of {} must be {}{}", spec.name,
                                                    owner, expected, found)),
                     at);
      return std::nullopt;
    };
    // "a number in [0, 5]": what is allowed, bounds and all.
    auto bounded = [&](std::string_view noun) {
      const std::string bounds = describe_range(spec);
      return bounds.empty() ? std::string(noun) : fmt::format("{} {}", noun, bounds);
    };
    // Checks a number against the spec; `item` is a number in a list.
    auto in_range = [&](double value, const Node& at, bool item) {
      const bool finite = std::isfinite(value);
      if (finite && !(spec.minimum && value < *spec.minimum) &&
          !(spec.maximum && value > *spec.maximum)) {
        return true;
      }
      const std::string required = bounded(!finite                        ? "a finite number"
                                           : spec.kind == ParamKind::kInt ? "an integer"
                                                                          : "a number");
      diagnostics_.error(at.location(), "out-of-range",
                         item ? fmt::format("param '{}' of {} has an item {}; items must be {}",
                                            spec.name, owner, at.text(), required)
                              : fmt::format("param '{}' of {} is {}; it must be {}", spec.name,
                                            owner, at.text(), required));
      return false;
    };
    switch (spec.kind) {
      case ParamKind::kBool:
        if (auto value = node.as_bool()) return ParamValue{*value};
        return fail("true or false", node);
      case ParamKind::kInt: {
        auto value = node.as_int();
        if (!value) return fail(bounded("an integer"), node);
        if (!in_range(static_cast<double>(*value), node, false)) return std::nullopt;
        return ParamValue{static_cast<std::int64_t>(*value)};
      }
      case ParamKind::kDouble: {
        auto value = node.as_double();
        if (!value) return fail(bounded("a number"), node);
        if (!in_range(*value, node, false)) return std::nullopt;
        return ParamValue{*value};
      }
      case ParamKind::kString: {
        if (!node.is_scalar() || (!node.quoted() && node.reads_as_null())) {
          return fail("a string", node);
        }
        if (!spec.choices.empty()) {
          bool allowed = false;
          for (const auto& choice : spec.choices) allowed = allowed || choice == node.text();
          if (!allowed) {
            auto& error = diagnostics_.error(
                node.location(), "out-of-range",
                fmt::format("param '{}' of {} is '{}', not one of the allowed values", spec.name,
                            owner, node.text()));
            error.notes.push_back(suggest(node.text(), spec.choices, "allowed"));
            return std::nullopt;
          }
        }
        return ParamValue{node.text()};
      }
      case ParamKind::kVec2:
      case ParamKind::kVec3: {
        const std::size_t count = spec.kind == ParamKind::kVec2 ? 2 : 3;
        const std::string expected = fmt::format("a list of {} finite numbers", count);
        if (!node.is_sequence() || node.items().size() != count) return fail(expected, node);
        double xyz[3] = {0, 0, 0};
        for (std::size_t i = 0; i < count; ++i) {
          if (!detail::read_finite(node.items()[i], xyz[i])) return fail(expected, node.items()[i]);
        }
        if (count == 2) return ParamValue{Vec2{xyz[0], xyz[1]}};
        return ParamValue{Vec3{xyz[0], xyz[1], xyz[2]}};
      }
      case ParamKind::kDoubleList: {
        constexpr std::string_view kExpected = "a number or a non-empty list of numbers";
        if (!node.is_sequence()) {  // a single number stands for a list of one
          auto value = node.as_double();
          if (!value) return fail(kExpected, node);
          if (!in_range(*value, node, false)) return std::nullopt;
          return ParamValue{std::vector<double>{*value}};
        }
        if (node.items().empty()) return fail(kExpected, node);
        std::vector<double> values;
        bool ok = true;
        for (const auto& item : node.items()) {
          const auto value = item.as_double();
          if (!value) {
            fail(kExpected, item);
            ok = false;
          } else if (!in_range(*value, item, true)) {
            ok = false;
          } else {
            values.push_back(*value);
          }
        }
        if (!ok) return std::nullopt;
        return ParamValue{std::move(values)};
      }
      case ParamKind::kStringList: {
        constexpr std::string_view kExpected = "a list of strings";
        if (!node.is_sequence()) return fail(kExpected, node);
        std::vector<std::string> values;
        for (const auto& item : node.items()) {
          if (!item.is_scalar() || (!item.quoted() && item.reads_as_null())) {
            return fail(kExpected, item);
          }
          values.push_back(item.text());
        }
        return ParamValue{std::move(values)};
      }
      case ParamKind::kAny:
        return ParamValue{node};
    }
    return std::nullopt;
  }

  /// "in [0, 1]", "at least 0", "at most 5", or empty when unbounded.
  static std::string describe_range(const ParamSpec& spec) {
    if (spec.minimum && spec.maximum) {
      return fmt::format("in [{}, {}]", *spec.minimum, *spec.maximum);
    }
    if (spec.minimum) return fmt::format("at least {}", *spec.minimum);
    if (spec.maximum) return fmt::format("at most {}", *spec.maximum);
    return {};
  }

  /// Validates `params` (may be null) against the class; fills in defaults.
  ParamSet read_params(const ClassInfo& cls, const Node* params, const SourceLocation& owner_at,
                       std::string_view owner, bool fill_defaults = true) {
    ParamSet set;
    std::vector<std::string> declared;
    for (const auto& spec : cls.params) declared.push_back(spec.name);
    if (params != nullptr && !params->is_mapping() && !params->reads_as_null()) {
      diagnostics_.error(
          params->location(), "wrong-type",
          fmt::format("params of {} must be a mapping, found {}", owner, params->describe()));
      params = nullptr;
    }
    if (params != nullptr && params->is_mapping()) {
      for (const auto& entry : params->entries()) {
        if (cls.find_param(entry.key) == nullptr) {
          auto& error = diagnostics_.error(
              entry.key_location, "unknown-param",
              fmt::format("unknown param '{}' for {} ({})", entry.key, owner, cls.name));
          const auto hint = suggest(entry.key, declared);
          error.notes.push_back(hint.empty() ? fmt::format("{} declares no params", cls.name)
                                             : hint);
        }
      }
    }
    for (const auto& spec : cls.params) {
      const Node* value =
          params != nullptr && params->is_mapping() ? params->find(spec.name) : nullptr;
      if (value != nullptr) {
        if (auto read = read_param(spec, *value, owner)) {
          set.items.push_back({spec.name, std::move(*read), value->location(), false});
        }
      } else if (spec.default_value) {
        if (fill_defaults) set.items.push_back({spec.name, *spec.default_value, owner_at, true});
      } else if (fill_defaults && !misplaced(spec.name)) {
        diagnostics_.error(owner_at, "missing-param",
                           fmt::format("{} is missing the required param '{}' ({}) of class {}",
                                       owner, spec.name, to_string(spec.kind), cls.name));
      }
    }
    return set;
  }

  // --- layers ----------------------------------------------------------------------------------

  void read_layer(const Node& node) {
    Fields fields(node, "a layer",
                  {"name", "interface", "params", "ports", "actuators", "sensors", "behaviours",
                   "inhibitions", "normalise", "lint"},
                  diagnostics_);
    if (!fields.ok()) return;
    LayerDecl layer;
    PendingLayer pending;
    pending.location = node.location();
    layer.name.location = node.location();
    if (const Node* name = fields.required("name")) {
      layer.name.location = name->location();
      if (auto text = read_name(*name, "a layer")) layer.name.text = *text;
    }
    if (!layer.name.text.empty()) {
      for (const auto& other : model_.layers) {
        if (other.name.text == layer.name.text) {
          auto& error = diagnostics_.error(layer.name.location, "duplicate-name",
                                           fmt::format("duplicate layer '{}'", layer.name.text));
          error.notes.push_back(
              fmt::format("first declared at {}", to_string(other.name.location)));
        }
      }
    }
    const std::string owner = layer_label(layer);
    if (const Node* interface = fields.optional("interface")) {
      layer.interface = read_class(*interface, ClassKind::kInterface, owner);
      pending.params = fields.optional("params");
      pending.ports = fields.optional("ports");
      for (auto key : {"behaviours", "inhibitions"}) {
        if (fields.optional(key) == nullptr) continue;
        diagnostics_.error(fields.key_location(key), "interface-with-behaviours",
                           fmt::format("interface layer '{}' cannot have {}: its data comes from "
                                       "its interface class",
                                       layer.name.text, key));
      }
    } else {
      for (auto key : {"params", "ports"}) {
        if (fields.optional(key) == nullptr) continue;
        diagnostics_.error(fields.key_location(key), "unknown-key",
                           fmt::format("'{}' belongs to an interface layer; layer '{}' has no "
                                       "'interface:'",
                                       key, layer.name.text));
      }
      pending.behaviours = fields.optional("behaviours");
      pending.inhibitions = fields.optional("inhibitions");
    }
    if (const Node* normalise = fields.optional("normalise")) {
      layer.normalise = read_bool(*normalise, "normalise");
    }
    if (const Node* lint = fields.optional("lint")) read_lint(*lint, layer.lint_ignore);
    if (const Node* actuators = fields.optional("actuators")) read_actuators(*actuators, layer);
    pending.sensors = fields.optional("sensors");
    model_.layers.push_back(std::move(layer));
    pending_layers_.push_back(pending);
  }

  /// "layer 'control'", or where a layer without a (usable) name was declared.
  static std::string layer_label(const LayerDecl& layer) {
    if (!layer.name.text.empty()) return fmt::format("layer '{}'", layer.name.text);
    const auto& where = layer.name.location;
    return fmt::format("the unnamed layer at {}", to_string(where));
  }

  void read_actuators(const Node& node, LayerDecl& layer) {
    if (node.reads_as_null()) return;
    if (!node.is_mapping()) {
      diagnostics_.error(node.location(), "wrong-type",
                         fmt::format("'actuators' must be a mapping from names to "
                                     "{{type: ...}}, found {}",
                                     node.describe()));
      return;
    }
    for (const auto& entry : node.entries()) {
      // An actuator with a bad name or body is still declared, so that the sensors and ports
      // naming it report nothing more.
      check_identifier(entry.key, entry.key_location, "an actuator");
      ActuatorDecl actuator;
      actuator.name = {entry.key, entry.key_location};
      actuator.layer = layer.name.text;
      const Node* type = nullptr;
      const Node* aggregate = nullptr;
      if (entry.value.is_scalar() && !entry.value.reads_as_null()) {
        type = &entry.value;  // short form `name: vec2`
      } else {
        Fields fields(entry.value, fmt::format("actuator '{}'", entry.key),
                      {"type", "aggregate", "default", "safe"}, diagnostics_,
                      "a value type or a mapping {type: ..., aggregate: ..., default: ..., "
                      "safe: ...}");
        type = fields.required("type");
        aggregate = fields.optional("aggregate");
        if (aggregate != nullptr) {
          actuator.aggregate = read_bool(*aggregate, "aggregate").value_or(false);
        }
        if (const Node* fallback = fields.optional("default")) actuator.default_value = *fallback;
        if (const Node* safe = fields.optional("safe")) actuator.safe_value = *safe;
      }
      if (type != nullptr) {
        if (auto text = read_string(*type, "a value type")) {
          actuator.type = registry_.find_value_type(*text);
          // A value type of a listed plugin that did not load: the plugin's error says it.
          if (actuator.type == nullptr &&
              !(from_unloaded_plugin(*text) && diagnostics_.has_errors())) {
            auto& error = diagnostics_.error(type->location(), "unknown-type",
                                             fmt::format("unknown value type '{}'", *text));
            error.notes.push_back(suggest(*text, registry_.value_type_names()));
          }
        }
      }
      if (actuator.type != nullptr && actuator.aggregate && !actuator.type->aggregatable()) {
        std::vector<std::string> averaged;
        for (const auto& value_type : registry_.value_types()) {
          if (value_type->aggregatable()) averaged.push_back(value_type->name);
        }
        auto& error = diagnostics_.error(
            aggregate->location(), "not-aggregatable",
            fmt::format("actuator '{}' cannot be 'aggregate: true': values of type '{}' cannot "
                        "be averaged",
                        entry.key, actuator.type->name));
        std::sort(averaged.begin(), averaged.end());
        std::string list;
        for (const auto& name : averaged) list += (list.empty() ? "" : ", ") + name;
        error.notes.push_back("types that can be averaged: " + list);
        error.notes.push_back(
            "without 'aggregate', the writer with the highest activation level wins");
      }
      for (const auto& [what, value] : {std::pair{"default", &actuator.default_value},
                                        std::pair{"safe value", &actuator.safe_value}}) {
        if (actuator.type == nullptr || !*value) continue;
        ValueBox scratch(*actuator.type);
        std::string expected;
        if (!actuator.type->from_node(**value, scratch.data(), expected)) {
          add_quote_hint(
              diagnostics_.error(
                  (*value)->location(), "wrong-type",
                  fmt::format("{} of actuator '{}' must be {} ({}), found {}", what, entry.key,
                              expected, actuator.type->name, (*value)->describe())),
              **value);
        }
      }
      if (auto found = actuator_index_.find(entry.key); found != actuator_index_.end()) {
        auto& error = diagnostics_.error(
            entry.key_location, "duplicate-name",
            fmt::format("duplicate actuator '{}': actuator names are unique in the manager",
                        entry.key));
        const auto& first = found->second;
        error.notes.push_back(fmt::format("first declared in layer '{}' at {}", first.layer,
                                          to_string(first.location)));
        continue;
      }
      actuator_index_[entry.key] = {actuator.layer, entry.key_location, actuator.type};
      layer.actuators.push_back(std::move(actuator));
    }
  }

  void check_layers() {
    for (std::size_t i = 0; i < model_.layers.size(); ++i) {
      LayerDecl& layer = model_.layers[i];
      PendingLayer& pending = pending_layers_[i];
      if (pending.sensors != nullptr) read_sensors(*pending.sensors, layer, pending);
      if (layer.interface != nullptr) {
        const std::string owner = layer.name.text.empty()
                                      ? layer_label(layer)
                                      : fmt::format("interface layer '{}'", layer.name.text);
        layer.params = read_params(*layer.interface, pending.params, layer.name.location, owner);
        layer.ports =
            bind_ports(*layer.interface, pending.ports, layer, owner, layer.name.location);
      }
      if (pending.behaviours != nullptr) read_behaviours(*pending.behaviours, layer, pending);
    }
    // Inhibitions last: naming a behaviour of another layer is told apart from a typo only once
    // every layer's behaviours are known.
    for (std::size_t i = 0; i < model_.layers.size(); ++i) {
      if (const Node* inhibitions = pending_layers_[i].inhibitions) {
        read_inhibitions(*inhibitions, model_.layers[i], pending_layers_[i]);
      }
    }
  }

  void read_sensors(const Node& node, LayerDecl& layer, PendingLayer& pending) {
    auto add = [&](const std::string& name, const SourceLocation& where, const Node* type) {
      if (!check_identifier(name, where, "a sensor")) return;
      for (const auto& existing : layer.sensors) {
        if (existing.text == name) {
          diagnostics_
              .error(where, "duplicate-name",
                     fmt::format("sensor '{}' listed twice in {}", name, layer_label(layer)))
              .notes.push_back(fmt::format("first listed at {}", to_string(existing.location)));
          return;
        }
      }
      const auto found = actuator_index_.find(name);
      if (found == actuator_index_.end()) {
        auto& error = diagnostics_.error(
            where, "unknown-actuator",
            fmt::format("sensor '{}' of {} names no actuator", name, layer_label(layer)));
        const auto names = actuator_names();
        const auto hint = suggest(name, names);
        error.notes.push_back(hint.empty() ? "the config declares no actuators" : hint);
        if (auto meant = closest(name, names)) {
          pending.misspelt_sensors.emplace_back(std::move(*meant), diagnostics_.items().size() - 1);
        }
        return;
      }
      const ActuatorInfo& actuator = found->second;
      if (type != nullptr && !type->is_scalar()) {
        diagnostics_.error(type->location(), "wrong-type",
                           fmt::format("sensor '{}' must map to its value type, such as "
                                       "'{}: double', found {}",
                                       name, name, type->describe()));
      } else if (type != nullptr) {
        auto text = read_string(*type, fmt::format("the value type of sensor '{}'", name));
        if (text && actuator.type != nullptr && *text != actuator.type->name) {
          diagnostics_
              .error(type->location(), "type-mismatch",
                     fmt::format("sensor '{}' expects type '{}' but actuator '{}' is '{}'", name,
                                 *text, name, actuator.type->name))
              .notes.push_back(fmt::format("'{}' is declared in layer '{}' at {}", name,
                                           actuator.layer, to_string(actuator.location)));
        }
      }
      layer.sensors.push_back({name, where});
    };
    if (node.reads_as_null()) return;
    if (node.is_sequence()) {
      for (const auto& item : node.items()) {
        if (auto text = read_string(item, "a sensor name")) add(*text, item.location(), nullptr);
      }
    } else if (node.is_mapping()) {
      for (const auto& entry : node.entries()) add(entry.key, entry.key_location, &entry.value);
    } else {
      auto& error = diagnostics_.error(
          node.location(), "wrong-type",
          fmt::format("'sensors' must be a list of actuator names or a mapping from actuator "
                      "names to their types, found {}",
                      node.describe()));
      if (node.is_scalar()) {
        error.notes.push_back(fmt::format("write [{}] for a list of one", node.text()));
      }
    }
  }

  std::vector<std::string> actuator_names() const {
    std::vector<std::string> names;
    for (const auto& [name, info] : actuator_index_) names.push_back(name);
    return names;
  }

  std::vector<PortBinding> bind_ports(const ClassInfo& cls, const Node* ports,
                                      const LayerDecl& layer, const std::string& owner,
                                      const SourceLocation& owner_at) {
    std::vector<PortBinding> bindings;
    if (ports != nullptr && ports->reads_as_null()) ports = nullptr;
    if (ports != nullptr && !ports->is_mapping()) {
      diagnostics_.error(ports->location(), "wrong-type",
                         fmt::format("'ports' must map port names to sensors or actuators, "
                                     "found {}",
                                     ports->describe()));
      ports = nullptr;
    }
    if (ports != nullptr) {
      std::vector<std::string> declared;
      for (const auto& spec : cls.ports) declared.push_back(spec.name);
      for (const auto& entry : ports->entries()) {
        if (cls.find_port(entry.key) == nullptr) {
          auto& error = diagnostics_.error(
              entry.key_location, "unknown-port",
              fmt::format("unknown port '{}' for {} ({})", entry.key, owner, cls.name));
          const auto hint = suggest(entry.key, declared);
          error.notes.push_back(hint.empty() ? fmt::format("{} declares no ports", cls.name)
                                             : hint);
        }
      }
    }
    for (const auto& spec : cls.ports) {
      PortBinding binding;
      binding.port = &spec;
      binding.location = owner_at;
      const Node* explicit_target = ports != nullptr ? ports->find(spec.name) : nullptr;
      std::string target = spec.name;
      if (explicit_target != nullptr) {
        auto text = read_string(*explicit_target, "a sensor or actuator name");
        if (!text) continue;
        target = *text;
        binding.location = explicit_target->location();
      }
      const bool input = spec.direction == PortDirection::kInput;
      bool found = false;
      if (input) {
        for (const auto& sensor : layer.sensors) found = found || sensor.text == target;
      } else {
        for (const auto& actuator : layer.actuators) found = found || actuator.name.text == target;
      }
      if (!found) {
        if (spec.optional && explicit_target == nullptr) {
          bindings.push_back(binding);  // unbound
          continue;
        }
        // Declared but rejected (a bad sensor entry, a duplicate actuator): already reported.
        if (declared_but_invalid(target, input, layer)) continue;
        // A misspelt sensor is the one mistake: the ports that read what it meant are notes.
        if (input && fold_into_misspelt_sensor(target, layer, owner, spec.name)) continue;
        std::vector<std::string> candidates;
        if (input) {
          for (const auto& sensor : layer.sensors) candidates.push_back(sensor.text);
        } else {
          for (const auto& actuator : layer.actuators) candidates.push_back(actuator.name.text);
        }
        auto& error = diagnostics_.error(
            binding.location, "unbound-port",
            fmt::format("{} port '{}' of {} ({}) binds to '{}', which is not {} of {}",
                        input ? "input" : "output", spec.name, owner, cls.name, target,
                        input ? "a sensor" : "an actuator", layer_label(layer)));
        if (const auto other = actuator_index_.find(target); other != actuator_index_.end()) {
          error.notes.push_back(
              input ? fmt::format("'{}' is an actuator of layer '{}': list it under this "
                                  "layer's 'sensors:' to read it",
                                  target, other->second.layer)
                    : fmt::format("'{}' is an actuator of layer '{}'; a behaviour writes only to "
                                  "actuators of its own layer",
                                  target, other->second.layer));
        } else {
          const auto hint = suggest(target, candidates);
          if (!hint.empty()) error.notes.push_back(hint);
        }
        if (explicit_target == nullptr) {
          error.notes.push_back(fmt::format("bind it with 'ports: {{{}: NAME}}'", spec.name));
        }
        continue;
      }
      const auto& actuator = actuator_index_.at(target);
      const ValueType* port_type = registry_.value_type_of(*spec.cpp_type);
      if (actuator.type != nullptr && port_type != actuator.type) {
        diagnostics_.error(
            binding.location, "type-mismatch",
            fmt::format("port '{}' of {} ({}) has type '{}' but {} '{}' is '{}'", spec.name, owner,
                        cls.name, registry_.value_type_name(*spec.cpp_type),
                        input ? "sensor" : "actuator", target, actuator.type->name));
        continue;
      }
      binding.target = target;
      bindings.push_back(binding);
    }
    return bindings;
  }

  /// Whether `name` was written in the layer's sensors (input) or actuators (output) but
  /// rejected there, with an error already reported.
  bool fold_into_misspelt_sensor(const std::string& target, const LayerDecl& layer,
                                 const std::string& owner, const std::string& port) {
    const PendingLayer& pending =
        pending_layers_[static_cast<std::size_t>(&layer - model_.layers.data())];
    for (const auto& [meant, index] : pending.misspelt_sensors) {
      if (meant != target) continue;
      diagnostics_.at(index).notes.push_back(
          fmt::format("{} reads '{}' through its port '{}'", owner, target, port));
      return true;
    }
    return false;
  }

  bool declared_but_invalid(const std::string& name, bool input, const LayerDecl& layer) const {
    const PendingLayer& pending =
        pending_layers_[static_cast<std::size_t>(&layer - model_.layers.data())];
    const Node* list = input ? pending.sensors : nullptr;
    if (list == nullptr) return false;
    for (const auto& item : list->items()) {
      if (item.is_scalar() && item.text() == name) return true;
    }
    for (const auto& entry : list->entries()) {
      if (entry.key == name) return true;
    }
    return false;
  }

  /// Whether `key` was written beside `params:` (and so reported already, not missing).
  bool misplaced(const std::string& key) const {
    if (misplaced_ == nullptr) return false;
    for (const auto& entry : *misplaced_) {
      if (entry.first == key) return true;
    }
    return false;
  }

  /// A param or port written beside `params:` or `ports:` instead of under it.
  void note_misplaced_keys(const ClassInfo& cls,
                           const std::vector<std::pair<std::string, std::size_t>>& keys) {
    for (const auto& [key, index] : keys) {
      for (const auto& param : cls.params) {
        if (param.name != key) continue;
        diagnostics_.at(index).notes.push_back(
            fmt::format("'{}' is a param of {}: write it under 'params:', as in "
                        "'params: {{{}: ...}}'",
                        key, cls.name, key));
      }
      for (const auto& port : cls.ports) {
        if (port.name != key) continue;
        diagnostics_.at(index).notes.push_back(
            fmt::format("'{}' is a port of {}: bind it under 'ports:', as in 'ports: {{{}: ...}}'",
                        key, cls.name, key));
      }
    }
  }

  void read_behaviours(const Node& node, LayerDecl& layer, PendingLayer& pending) {
    if (node.reads_as_null()) return;
    if (!node.is_mapping()) {
      diagnostics_.error(node.location(), "wrong-type",
                         fmt::format("'behaviours' must be a mapping from names to "
                                     "{{type: ...}}, found {}",
                                     node.describe()));
      return;
    }
    for (const auto& entry : node.entries()) {
      pending.behaviour_names.push_back(entry.key);
      // The Document hands out a location as a new SourceLocation each time: once here.
      const SourceLocation where = entry.key_location;
      check_identifier(entry.key, where, "a behaviour");
      BehaviourDecl behaviour;
      behaviour.name = {entry.key, where};
      behaviour.location = where;
      const std::string owner = fmt::format("behaviour '{}'", entry.key);
      const Node* type = nullptr;
      const Node* params = nullptr;
      const Node* ports = nullptr;
      std::vector<std::pair<std::string, std::size_t>> misplaced;
      if (entry.value.is_scalar() && !entry.value.reads_as_null()) {
        type = &entry.value;  // short form `name: Class`
      } else {
        Fields fields(entry.value, owner, {"type", "params", "ports", "on_exception"}, diagnostics_,
                      "a class name or a mapping {type: ..., params: ..., ports: ...}");
        if (!fields.ok()) continue;
        type = fields.required("type");
        params = fields.optional("params");
        ports = fields.optional("ports");
        misplaced = fields.unknown();
        if (const Node* policy = fields.optional("on_exception")) {
          behaviour.on_exception = read_fault_policy(*policy);
        }
      }
      if (type == nullptr) continue;
      behaviour.cls = read_class(*type, ClassKind::kBehaviour, owner);
      if (behaviour.cls == nullptr) continue;
      note_misplaced_keys(*behaviour.cls, misplaced);
      misplaced_ = &misplaced;
      behaviour.params = read_params(*behaviour.cls, params, where, owner);
      misplaced_ = nullptr;
      behaviour.ports = bind_ports(*behaviour.cls, ports, layer, owner, where);
      layer.behaviours.push_back(std::move(behaviour));
    }
  }

  // --- inhibitions -----------------------------------------------------------------------------

  // Lookups for add_inhibition, so that a layer's inhibitions are read in linear time.
  struct InhibitionIndex {
    std::unordered_set<std::string_view> behaviours;        // valid ones of the layer
    std::unordered_map<std::string, std::size_t> declared;  // "inhibitor inhibited" → index
  };

  void read_inhibitions(const Node& node, LayerDecl& layer, const PendingLayer& pending) {
    if (node.reads_as_null()) return;
    InhibitionIndex index;
    index.behaviours.reserve(layer.behaviours.size());
    for (const auto& behaviour : layer.behaviours) index.behaviours.insert(behaviour.name.text);
    if (!node.is_sequence()) {
      diagnostics_.error(node.location(), "wrong-type",
                         fmt::format("'inhibitions' must be a list such as [a => b, b -> c], "
                                     "found {}",
                                     node.describe()));
      return;
    }
    index.declared.reserve(node.items().size());
    layer.inhibitions.reserve(layer.inhibitions.size() + node.items().size());
    for (const auto& item : node.items()) {
      InhibitionDecl inhibition;
      inhibition.location = entry_location(item);
      if (item.is_scalar()) {
        if (!parse_inhibition(item, inhibition)) continue;
      } else {
        Fields fields(item, "an inhibition", {"inhibitor", "inhibited", "chaining"}, diagnostics_,
                      "'a => b', 'a -> b' or a mapping {inhibitor: a, inhibited: b, chaining: "
                      "true}");
        if (!fields.ok()) continue;
        const Node* inhibitor = fields.required("inhibitor");
        const Node* inhibited = fields.required("inhibited");
        if (inhibitor == nullptr || inhibited == nullptr) continue;
        auto a = read_string(*inhibitor, "a behaviour name");
        auto b = read_string(*inhibited, "a behaviour name");
        if (!a || !b) continue;
        inhibition.inhibitor = {*a, inhibitor->location()};
        inhibition.inhibited = {*b, inhibited->location()};
        if (const Node* chaining = fields.optional("chaining")) {
          inhibition.chaining = read_bool(*chaining, "chaining").value_or(false);
        }
      }
      add_inhibition(std::move(inhibition), layer, pending, index);
    }
  }

  /// Where an inhibition is written: an unquoted `a => b` spans its whole text, so that errors
  /// about the inhibition underline all of it, not only its first name.
  static SourceLocation entry_location(const Node& item) {
    SourceLocation where = item.location();
    if (item.is_scalar() && !item.quoted()) {
      int characters = 0;
      for (const char c : item.text()) characters += (static_cast<unsigned char>(c) & 0xC0) != 0x80;
      where.length = characters;
    }
    return where;
  }

  bool parse_inhibition(const Node& item, InhibitionDecl& inhibition) {
    const std::string& text = item.text();
    // Every arrow, in order: `a => b => c` is two inhibitions written as one.
    std::vector<std::size_t> arrows;
    for (std::size_t i = 0; i + 1 < text.size(); ++i) {
      if ((text[i] == '=' || text[i] == '-') && text[i + 1] == '>') arrows.push_back(i++);
    }
    auto trimmed = [&](std::size_t begin, std::size_t end) {
      while (begin < end && text[begin] == ' ') ++begin;
      while (end > begin && text[end - 1] == ' ') --end;
      return std::pair{begin, end};
    };
    if (arrows.empty()) {
      auto& error = diagnostics_.error(
          inhibition.location, "bad-inhibition",
          fmt::format("cannot read inhibition '{}': write 'a => b' (chaining) or 'a -> b' "
                      "(non-chaining)",
                      text));
      for (const char* backwards : {"<=", "<-"}) {
        const auto at = text.find(backwards);
        if (at == std::string::npos) continue;
        const auto [lb, le] = trimmed(0, at);
        const auto [rb, re] = trimmed(at + 2, text.size());
        error.notes.push_back(fmt::format(
            "an inhibition points from the inhibitor to the inhibited: did you mean "
            "'{} {}> {}'?",
            text.substr(rb, re - rb), backwards[1] == '=' ? '=' : '-', text.substr(lb, le - lb)));
      }
      return false;
    }
    // `- a => b` with the next item's `- ` indented deeper: YAML folds that line into this
    // item as `a => b - c -> d`.
    const auto folded = text.find(" - ");
    if (arrows.size() > 1 && folded != std::string::npos && !item.quoted() &&
        folded > arrows.front()) {
      diagnostics_
          .error(inhibition.location, "bad-inhibition",
                 fmt::format("inhibition '{}' runs on into the next item", text))
          .notes.push_back(fmt::format(
              "the '- {}' after it is indented deeper than this item's '- ', so YAML reads it "
              "as more of this item's text; line up the '- ' of every item",
              text.substr(folded + 3)));
      return false;
    }
    if (arrows.size() > 1) {
      std::vector<std::string> parts;
      std::size_t begin = 0;
      for (std::size_t k = 0; k <= arrows.size(); ++k) {
        const auto [b, e] = trimmed(begin, k < arrows.size() ? arrows[k] : text.size());
        parts.push_back(text.substr(b, e - b));
        if (k < arrows.size()) begin = arrows[k] + 2;
      }
      std::string split;
      for (std::size_t k = 0; k < arrows.size(); ++k) {
        const char* separator = k == 0 ? "" : k + 1 == arrows.size() ? " and " : ", ";
        split += fmt::format("{}'{} {} {}'", separator, parts[k], text.substr(arrows[k], 2),
                             parts[k + 1]);
      }
      diagnostics_
          .error(item.text_location(arrows[1]), "bad-inhibition",
                 fmt::format("inhibition '{}' has more than one arrow; write one inhibition per "
                             "item",
                             text))
          .notes.push_back(fmt::format("did you mean {}?", split));
      return false;
    }
    const std::size_t arrow = arrows.front();
    const std::string_view symbol = std::string_view(text).substr(arrow, 2);
    inhibition.chaining = symbol == "=>";
    auto side = [&](std::size_t from, std::size_t to, Name& name, const char* which) {
      const auto [begin, end] = trimmed(from, to);
      name.text = text.substr(begin, end - begin);
      name.location = item.text_location(begin);
      if (name.text.empty()) {
        diagnostics_.error(name.location, "bad-inhibition",
                           fmt::format("inhibition '{}' is missing the {} behaviour {} '{}'", text,
                                       which, from == 0 ? "before" : "after", symbol));
        return false;
      }
      return true;
    };
    const bool left = side(0, arrow, inhibition.inhibitor, "inhibiting");
    const bool right = side(arrow + 2, text.size(), inhibition.inhibited, "inhibited");
    return left && right;
  }

  void add_inhibition(InhibitionDecl inhibition, LayerDecl& layer, const PendingLayer& pending,
                      InhibitionIndex& index) {
    bool ok = true;
    for (const Name* end : {&inhibition.inhibitor, &inhibition.inhibited}) {
      if (index.behaviours.count(end->text) != 0) continue;
      ok = false;
      const auto& declared = pending.behaviour_names;
      if (std::find(declared.begin(), declared.end(), end->text) != declared.end()) {
        continue;  // declared but invalid: already reported
      }
      const LayerDecl* elsewhere = nullptr;
      for (std::size_t i = 0; i < model_.layers.size() && elsewhere == nullptr; ++i) {
        const auto& names = pending_layers_[i].behaviour_names;
        if (&model_.layers[i] != &layer &&
            std::find(names.begin(), names.end(), end->text) != names.end()) {
          elsewhere = &model_.layers[i];
        }
      }
      if (elsewhere != nullptr) {
        diagnostics_
            .error(end->location, "cross-layer-inhibition",
                   fmt::format("inhibition across layers: '{}' is a behaviour of {}, not of {}",
                               end->text, layer_label(*elsewhere), layer_label(layer)))
            .notes.push_back(
                "a behaviour inhibits only behaviours of its own layer; layers "
                "above influence layers below through actuators and sensors");
        continue;
      }
      auto& error = diagnostics_.error(end->location, "unknown-behaviour",
                                       fmt::format("inhibition names unknown behaviour '{}' in {}",
                                                   end->text, layer_label(layer)));
      const auto hint = suggest(end->text, declared);
      error.notes.push_back(
          hint.empty() ? fmt::format("{} declares no behaviours", layer_label(layer)) : hint);
    }
    if (!ok) return;
    if (inhibition.inhibitor.text == inhibition.inhibited.text) {
      diagnostics_.error(
          inhibition.location, "self-inhibition",
          fmt::format("behaviour '{}' cannot inhibit itself", inhibition.inhibitor.text));
      return;
    }
    // A config holds no NUL byte, so it separates the two names unambiguously.
    const auto [found, added] = index.declared.emplace(
        inhibition.inhibitor.text + '\0' + inhibition.inhibited.text, layer.inhibitions.size());
    if (!added) {
      auto& existing = layer.inhibitions[found->second];
      auto& warning = diagnostics_.warning(
          inhibition.location, "duplicate-inhibition",
          fmt::format("duplicate inhibition {} {} {}: applied once", inhibition.inhibitor.text,
                      inhibition.chaining ? "=>" : "->", inhibition.inhibited.text));
      warning.notes.push_back(fmt::format("first declared at {}", to_string(existing.location)));
      if (inhibition.chaining != existing.chaining) {
        existing.chaining = true;
        warning.notes.push_back(
            "declared both chaining (=>) and non-chaining (->): it counts as chaining");
      }
      return;
    }
    layer.inhibitions.push_back(std::move(inhibition));
  }

  // --- state machines --------------------------------------------------------------------------

  void read_state_machines(const Node& node) {
    if (!node.is_mapping()) {
      diagnostics_.error(node.location(), "wrong-type",
                         fmt::format("'state_machines' must be a mapping from names to "
                                     "{{states: ..., queue: ...}}, found {}",
                                     node.describe()));
      return;
    }
    for (const auto& entry : node.entries()) {
      if (!check_identifier(entry.key, entry.key_location, "a state machine")) continue;
      for (const auto& other : model_.state_machines) {
        if (other.name.text == entry.key) {
          diagnostics_
              .error(entry.key_location, "duplicate-name",
                     fmt::format("duplicate state machine '{}'", entry.key))
              .notes.push_back(fmt::format("first declared at {}", to_string(other.location)));
        }
      }
      StateMachineDecl machine;
      machine.name = {entry.key, entry.key_location};
      machine.location = entry.key_location;
      pending_machines_.push_back(&entry.value);
      model_.state_machines.push_back(std::move(machine));
    }
  }

  /// `state` or `{state: {param: value}}`, naming a state of `machine`.
  std::optional<QueueEntry> read_queue_entry(const Node& item, const StateMachineDecl& machine,
                                             std::string_view what) {
    QueueEntry entry;
    const Node* overrides = nullptr;
    if (item.is_mapping() && item.entries().size() == 1) {
      entry.state = {item.entries()[0].key, item.entries()[0].key_location};
      overrides = &item.entries()[0].value;
    } else if (item.is_mapping()) {
      diagnostics_.error(
          item.location(), "wrong-type",
          fmt::format("a {} entry names one state, as 'name' or {{name: {{params}}}}; "
                      "found a mapping with {} keys",
                      what, item.entries().size()));
      return std::nullopt;
    } else if (auto text = read_string(item, "a state name or {state: {params}}")) {
      entry.state = {*text, item.location()};
    } else {
      return std::nullopt;
    }
    const StateDecl* state = nullptr;
    std::vector<std::string> state_names;
    for (const auto& candidate : machine.states) {
      if (candidate.name.text == entry.state.text) state = &candidate;
      state_names.push_back(candidate.name.text);
    }
    if (state == nullptr) {
      // A state declared with an error (an unknown class, ...) was reported already.
      const Node* declared =
          pending_machines_[static_cast<std::size_t>(&machine - model_.state_machines.data())];
      if (declared->is_mapping() && declared->find("states") != nullptr &&
          declared->find("states")->find(entry.state.text) != nullptr) {
        return std::nullopt;
      }
      auto& error =
          diagnostics_.error(entry.state.location, "unknown-state",
                             fmt::format("{} of state machine '{}' names unknown state '{}'", what,
                                         machine.name.text, entry.state.text));
      const auto hint = suggest(entry.state.text, state_names);
      if (!hint.empty()) error.notes.push_back(hint);
      return std::nullopt;
    }
    entry.overrides = check_instance_params(*state, overrides, entry.state.location);
    return entry;
  }

  /// Child controllers: each named machine exists, is owned once, and ownership has no cycle.
  void check_machine_ownership() {
    std::map<std::string, const Name*> owner_of;
    std::map<std::string, std::vector<std::string>> children;
    std::vector<std::string> names;
    for (const auto& machine : model_.state_machines) names.push_back(machine.name.text);
    for (const auto& machine : model_.state_machines) {
      for (const auto& state : machine.states) {
        if (!state.machine) continue;
        const Name& child = *state.machine;
        if (std::find(names.begin(), names.end(), child.text) == names.end()) {
          auto& error =
              diagnostics_.error(child.location, "unknown-machine",
                                 fmt::format("state '{}' names unknown state machine '{}'",
                                             state.name.text, child.text));
          const auto hint = suggest(child.text, names);
          if (!hint.empty()) error.notes.push_back(hint);
          continue;
        }
        if (auto [it, fresh] = owner_of.emplace(child.text, &child); !fresh) {
          diagnostics_
              .error(child.location, "machine-owned-twice",
                     fmt::format("state machine '{}' already has an owner; a controller is "
                                 "stepped by one owner only",
                                 child.text))
              .notes.push_back(fmt::format("first claimed at {}", to_string(it->second->location)));
          continue;
        }
        children[machine.name.text].push_back(child.text);
      }
    }
    // A machine that owns itself, directly or through its children, could never be stepped.
    for (const auto& machine : model_.state_machines) {
      std::vector<std::string> stack = children[machine.name.text];
      std::set<std::string> seen;
      while (!stack.empty()) {
        const std::string next = stack.back();
        stack.pop_back();
        if (next == machine.name.text) {
          diagnostics_.error(machine.location, "machine-cycle",
                             fmt::format("state machine '{}' owns itself through its states' "
                                         "'machine:' children",
                                         machine.name.text));
          break;
        }
        if (!seen.insert(next).second) continue;
        for (const auto& grandchild : children[next]) stack.push_back(grandchild);
      }
    }
  }

  void check_state_machine(StateMachineDecl& machine) {
    const std::size_t index = static_cast<std::size_t>(&machine - model_.state_machines.data());
    const Node& node = *pending_machines_[index];
    const std::string owner = fmt::format("state machine '{}'", machine.name.text);
    Fields fields(node, owner, {"states", "queue", "capacity", "preempt"}, diagnostics_);
    if (!fields.ok()) return;
    if (const Node* states = fields.required("states")) {
      if (!states->is_mapping()) {
        diagnostics_.error(states->location(), "wrong-type",
                           fmt::format("'states' must be a mapping from state names to classes, "
                                       "found {}",
                                       states->describe()));
      } else {
        for (const auto& entry : states->entries()) {
          if (!check_identifier(entry.key, entry.key_location, "a state")) continue;
          StateDecl state;
          state.name = {entry.key, entry.key_location};
          const std::string state_owner = fmt::format("state '{}'", entry.key);
          state.location = entry.key_location;
          const Node* type = nullptr;
          const Node* params = nullptr;
          if (entry.value.is_scalar() && !entry.value.reads_as_null()) {
            type = &entry.value;
          } else {
            Fields state_fields(entry.value, state_owner, {"type", "params", "machine"},
                                diagnostics_);
            if (!state_fields.ok()) continue;
            type = state_fields.required("type");
            params = state_fields.optional("params");
            if (const Node* child = state_fields.optional("machine")) {
              if (auto text = read_identifier(*child, "a state machine")) {
                state.machine = Name{*text, child->location()};
              }
            }
          }
          if (type == nullptr) continue;
          state.cls = read_class(*type, ClassKind::kState, state_owner);
          if (state.cls == nullptr) continue;
          // Required params may come per queue entry, so they are checked per instance.
          state.params = read_params(*state.cls, params, entry.key_location, state_owner,
                                     /*fill_defaults=*/false);
          machine.states.push_back(std::move(state));
        }
      }
    }
    std::vector<std::string> state_names;
    for (const auto& state : machine.states) state_names.push_back(state.name.text);
    if (const Node* queue = fields.optional("queue")) {
      for_each_item(*queue, "queue", [&](const Node& item) {
        if (auto entry = read_queue_entry(item, machine, "queue")) {
          machine.queue.push_back(std::move(*entry));
        }
      });
    }
    if (const Node* preempt = fields.optional("preempt")) {
      for_each_item(*preempt, "preempt", [&](const Node& item) {
        Fields entry_fields(item, "a pre-emption", {"cycle", "go_to"}, diagnostics_);
        if (!entry_fields.ok()) return;
        const Node* cycle = entry_fields.required("cycle");
        const Node* go_to = entry_fields.required("go_to");
        if (cycle == nullptr || go_to == nullptr) return;
        const auto value = cycle->as_int();
        if (!value || *value < 1) {
          diagnostics_.error(cycle->location(), value ? "out-of-range" : "wrong-type",
                             fmt::format("'cycle' must be a controller cycle (an integer >= 1), "
                                         "found {}",
                                         cycle->describe()));
          return;
        }
        if (auto entry = read_queue_entry(*go_to, machine, "pre-emption")) {
          machine.preempt.push_back(
              {static_cast<std::uint64_t>(*value), std::move(*entry), item.location()});
        }
      });
    }
    machine.capacity = 16 + machine.queue.size();
    if (const Node* capacity = fields.optional("capacity")) {
      const auto value = capacity->as_int();
      if (!value || *value < 1 || *value > 1'000'000) {
        diagnostics_.error(capacity->location(), value ? "out-of-range" : "wrong-type",
                           fmt::format("capacity of {} must be an integer in [1, 1000000], "
                                       "found {}",
                                       owner, capacity->describe()));
      } else if (static_cast<std::size_t>(*value) < machine.queue.size() + 1) {
        diagnostics_.error(capacity->location(), "out-of-range",
                           fmt::format("capacity {} of {} is too small for its initial queue of "
                                       "{} states (plus the current one)",
                                       *value, owner, machine.queue.size()));
      } else {
        machine.capacity = static_cast<std::size_t>(*value);
      }
    }
  }

 public:
  /// Validates per-instance params of a queued state: the overrides must fit the class and,
  /// together with the state's defaults, supply every required param.
  std::vector<Param> check_instance_params(const StateDecl& state, const Node* overrides,
                                           const SourceLocation& where) {
    const std::string owner = fmt::format("state '{}'", state.name.text);
    ParamSet given = read_params(*state.cls, overrides, where, owner, /*fill_defaults=*/false);
    for (const auto& param : given.items) {
      const ParamSpec* spec = state.cls->find_param(param.name);
      if (spec != nullptr && !spec->per_instance) {
        diagnostics_.error(param.location, "state-level-param",
                           fmt::format("param '{}' of class {} is set on the state ('params:' "
                                       "of state '{}'), not per planned instance",
                                       param.name, state.cls->name, state.name.text));
      }
    }
    for (const auto& spec : state.cls->params) {
      if (!spec.required()) continue;
      if (given.find(spec.name) == nullptr && state.params.find(spec.name) == nullptr) {
        diagnostics_
            .error(where, "missing-param",
                   fmt::format("{} is missing the required param '{}' ({}) of class {}", owner,
                               spec.name, to_string(spec.kind), state.cls->name))
            .notes.push_back("give it in the state's 'params:' or per queue entry");
      }
    }
    return std::move(given.items);
  }

  /// Takes a built model's layers and actuators, so that redeclare() binds ports as build()
  /// did.
  void seed(const Model& model) {
    model_.layers = model.layers;
    pending_layers_.resize(model_.layers.size());
    for (const auto& layer : model_.layers) {
      for (const auto& actuator : layer.actuators) {
        actuator_index_[actuator.name.text] = {layer.name.text, actuator.name.location,
                                               actuator.type};
      }
    }
  }

  std::optional<Declaration> redeclare(ClassKind kind, const Node& type, const Node* params,
                                       const Node* ports, std::optional<std::size_t> layer,
                                       const std::string& owner, const SourceLocation& owner_at) {
    const std::size_t errors = diagnostics_.error_count();
    Declaration declaration;
    declaration.cls = read_class(type, kind, owner);
    if (declaration.cls == nullptr) return std::nullopt;
    // A state's required params may come per queue entry; a replacement has none of those.
    declaration.params = read_params(*declaration.cls, params, owner_at, owner);
    if (layer) {
      declaration.ports =
          bind_ports(*declaration.cls, ports, model_.layers[*layer], owner, owner_at);
    } else if (ports != nullptr) {
      diagnostics_.error(ports->location(), "unknown-key",
                         fmt::format("{} has no ports: a state reads and writes through the "
                                     "behaviour that steps its machine",
                                     owner));
    }
    if (diagnostics_.error_count() != errors) return std::nullopt;
    return declaration;
  }

 private:
  struct ActuatorInfo {
    std::string layer;
    SourceLocation location;
    const ValueType* type = nullptr;
  };

  const Registry& registry_;
  Diagnostics& diagnostics_;
  SourceFiles& files_;  // the included files, alive while pending
  Model model_;
  std::vector<PendingLayer> pending_layers_;
  std::vector<const Node*> pending_machines_;
  std::map<std::string, ActuatorInfo> actuator_index_;
  std::vector<std::string> include_stack_;  // canonical paths of the files being read
  std::vector<std::string> include_names_;  // the same files as diagnostics name them
  std::vector<std::string> include_chain_;
  std::set<std::string> included_;
};

}  // namespace

std::vector<Param> check_state_params(const StateDecl& state, const Node* overrides,
                                      const SourceLocation& where, const Registry& registry,
                                      Diagnostics& diagnostics) {
  SourceFiles no_files;
  return ModelBuilder(registry, diagnostics, no_files)
      .check_instance_params(state, overrides, where);
}

std::optional<Declaration> redeclare(const Model& model, ClassKind kind, const Node& type,
                                     const Node* params, const Node* ports,
                                     std::optional<std::size_t> layer, const std::string& owner,
                                     const SourceLocation& owner_at, const Registry& registry,
                                     Diagnostics& diagnostics) {
  SourceFiles no_files;
  ModelBuilder builder(registry, diagnostics, no_files);
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
  ModelBuilder builder(registry, diagnostics, files);
  builder.enter_root(root.location().file);
  return builder.build(root);
}

}  // namespace arbiter
