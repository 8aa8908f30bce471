// Classes and their params: the class a declaration names, each param value against its spec
// (kind, range, choices), and the scalar values (strings, names, booleans, lists) that the rest of
// the model is read from.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>

#include "arbiter/fields.hpp"
#include "core/model/builder.hpp"

namespace arbiter::detail {

namespace {

/// `KickBall`, `head-angle`, `2fast` → `kick_ball`, `head_angle`, `_2fast`.
std::string to_identifier(std::string_view text) {
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

/// "a behaviour class", "an interface class".
std::string a_class(ClassKind kind) {
  return fmt::format("{} {} class", kind == ClassKind::kInterface ? "an" : "a", to_string(kind));
}

/// "in [0, 1]", "at least 0", "at most 5", or empty when unbounded.
std::string describe_range(const ParamSpec& spec) {
  if (spec.minimum && spec.maximum) {
    return fmt::format("in [{}, {}]", *spec.minimum, *spec.maximum);
  }
  if (spec.minimum) return fmt::format("at least {}", *spec.minimum);
  if (spec.maximum) return fmt::format("at most {}", *spec.maximum);
  return {};
}

}  // namespace

void ModelBuilder::add_quote_hint(Diagnostic& diagnostic, const Node& node) {
  if (!node.is_scalar() || !node.quoted()) return;
  Node unquoted = node;
  unquoted.set_scalar(node.text(), /*quoted=*/false);
  if (unquoted.as_double() || unquoted.as_bool()) {
    diagnostic.notes.push_back(
        fmt::format("quotes make '{}' a string; write it without quotes", node.text()));
  }
}

std::optional<std::string> ModelBuilder::read_string(const Node& node, std::string_view expected) {
  if (!node.is_scalar() || (!node.quoted() && node.reads_as_null())) {
    diagnostics_.error(node.location(), "wrong-type",
                       fmt::format("expected {}, found {}", expected, node.describe()));
    return std::nullopt;
  }
  return node.text();
}

std::optional<std::string> ModelBuilder::read_identifier(const Node& node, std::string_view what) {
  auto text = read_string(node, fmt::format("{} (an identifier)", what));
  if (!text) return std::nullopt;
  if (!check_identifier(*text, node.location(), what)) return std::nullopt;
  return text;
}

std::optional<std::string> ModelBuilder::read_name(const Node& node, std::string_view what) {
  auto text = read_string(node, fmt::format("{} (an identifier)", what));
  if (text) check_identifier(*text, node.location(), what);
  return text;
}

bool ModelBuilder::check_identifier(const std::string& text, const SourceLocation& where,
                                    std::string_view what) {
  if (is_identifier(text)) return true;
  auto& error = diagnostics_.error(where, "bad-identifier",
                                   name_error(text, fmt::format("a valid name for {}", what)));
  if (text.size() > kMaxNameLength) return false;
  if (const auto fixed = to_identifier(text); !fixed.empty() && fixed != text) {
    error.notes.push_back(fmt::format("did you mean '{}'?", fixed));
  }
  return false;
}

std::optional<FaultPolicy> ModelBuilder::read_fault_policy(const Node& node) {
  static const std::vector<std::string> kChoices = {"inactive", "disable", "stop"};
  if (node.is_scalar() && !node.reads_as_null()) {
    for (std::size_t i = 0; i < kChoices.size(); ++i) {
      if (node.text() == kChoices[i]) return static_cast<FaultPolicy>(i);
    }
  }
  auto& error = diagnostics_.error(
      node.location(), node.is_scalar() ? "out-of-range" : "wrong-type",
      fmt::format("'on_exception' must be inactive, disable or stop, found {}", node.describe()));
  if (node.is_scalar()) error.unknown_name(node.text(), kChoices, {}, "allowed");
  return std::nullopt;
}

std::optional<bool> ModelBuilder::read_bool(const Node& node, std::string_view what) {
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

void ModelBuilder::read_lint(const Node& node, std::vector<Name>& ignore) {
  Fields fields(node, "'lint'", {"ignore"}, diagnostics_);
  if (const Node* codes = fields.optional("ignore")) {
    for_each_item(*codes, "ignore", [&](const Node& item) {
      if (auto text = read_string(item, "a lint code")) {
        ignore.push_back({*text, item.location()});
      }
    });
  }
}

bool ModelBuilder::from_unloaded_plugin(const std::string& name) const {
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
    if (info->origin.size() >= library.size() &&
        info->origin.compare(info->origin.size() - library.size(), library.size(), library) == 0) {
      return false;
    }
  }
  return true;
}

const ClassInfo* ModelBuilder::read_class(const Node& node, ClassKind kind, std::string_view what) {
  auto text = read_string(node, fmt::format("the class of {}", what));
  if (!text) return nullptr;
  const ClassInfo* cls = registry_.find_class(kind, *text);
  if (cls == nullptr) cls = registry_.find_any_class(*text);
  if (cls == nullptr) {
    // A class of a listed plugin that did not load: the plugin's error is the one mistake.
    if (from_unloaded_plugin(*text) && diagnostics_.has_errors()) return nullptr;
    const auto known = registry_.class_names(kind);
    auto& error = diagnostics_.error(node.location(), "unknown-class",
                                     fmt::format("unknown {} class '{}'", to_string(kind), *text));
    error.unknown_name(*text, known, fmt::format("no {} classes are registered", to_string(kind)));
    // `soccer.KickBall` that is not a typo of a known class probably lives in a plugin.
    if (!closest(*text, known) && text->find('.') != std::string::npos) {
      error.notes.push_back(
          "a plugin's classes are known once the plugin is listed under 'plugins:'");
    }
    return nullptr;
  }
  if (cls->kind != kind) {
    diagnostics_
        .error(
            node.location(), "wrong-class-kind",
            fmt::format("'{}' is {}; {} needs {}", *text, a_class(cls->kind), what, a_class(kind)))
        .unknown_name(*text, registry_.class_names(kind));
    return nullptr;
  }
  return cls;
}

std::optional<ParamValue> ModelBuilder::read_param(const ParamSpec& spec, const Node& node,
                                                   std::string_view owner) {
  // Reports at `at`: the whole value, or the one item of a list that is wrong.
  auto fail = [&](std::string_view expected, const Node& at) -> std::optional<ParamValue> {
    const std::string found = &at == &node ? fmt::format(", found {}", node.describe())
                                           : fmt::format("; found {} in it", at.describe());
    add_quote_hint(diagnostics_.error(at.location(), "wrong-type",
                                      fmt::format("param '{}' of {} must be {}{}", spec.name, owner,
                                                  expected, found)),
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
                            : fmt::format("param '{}' of {} is {}; it must be {}", spec.name, owner,
                                          at.text(), required));
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
          diagnostics_
              .error(node.location(), "out-of-range",
                     fmt::format("param '{}' of {} is '{}', not one of the allowed values",
                                 spec.name, owner, node.text()))
              .unknown_name(node.text(), spec.choices, {}, "allowed");
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
      if (spec.by_step && node.items().front().is_mapping()) return read_by_step(spec, node, owner);
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

std::optional<ParamValue> ModelBuilder::read_by_step(const ParamSpec& spec, const Node& node,
                                                     std::string_view owner) {
  // The expanded list holds a number per step up to the last `from`: a bound keeps a hostile
  // step number from taking the memory of a list that long.
  constexpr long long kLastStep = 1 << 20;
  constexpr std::string_view kExpected = "a mapping {from: STEP, level: LEVEL}";
  std::vector<double> values;
  bool ok = true;
  long long last = 0;
  for (const auto& item : node.items()) {
    Fields fields(item, fmt::format("an item of param '{}' of {}", spec.name, owner),
                  {"from", "level"}, diagnostics_, kExpected);
    const Node* from = fields.required("from");
    const Node* level = fields.required("level");
    if (!fields.ok() || from == nullptr || level == nullptr) {
      ok = false;
      continue;
    }
    const auto step = from->as_int();
    if (!step || *step <= last || *step > kLastStep) {
      diagnostics_.error(
          from->location(), "out-of-range",
          step && *step <= last && last > 0
              ? fmt::format("'from' of param '{}' of {} is {}; the steps must increase (the item "
                            "before is from step {})",
                            spec.name, owner, from->text(), last)
              : fmt::format("'from' of param '{}' of {} must be a step from 1 to {}, found {}",
                            spec.name, owner, kLastStep, from->describe()));
      ok = false;
      continue;
    }
    last = *step;
    ParamSpec number = spec;
    number.kind = ParamKind::kDouble;
    const auto value = read_param(number, *level, owner);
    if (!value) {
      ok = false;
      continue;
    }
    // The level before holds up to this step; before the first item, 0.
    values.resize(static_cast<std::size_t>(*step - 1), values.empty() ? 0.0 : values.back());
    values.push_back(std::get<double>(*value));
  }
  if (!ok) return std::nullopt;
  return ParamValue{std::move(values)};
}

ParamSet ModelBuilder::read_params(const ClassInfo& cls, const Node* params,
                                   const SourceLocation& owner_at, std::string_view owner,
                                   bool fill_defaults) {
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
        diagnostics_
            .error(entry.key_location, "unknown-param",
                   fmt::format("unknown param '{}' for {} ({})", entry.key, owner, cls.name))
            .unknown_name(entry.key, declared, fmt::format("{} declares no params", cls.name));
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

bool ModelBuilder::misplaced(const std::string& key) const {
  if (misplaced_ == nullptr) return false;
  for (const auto& entry : *misplaced_) {
    if (entry.first == key) return true;
  }
  return false;
}

}  // namespace arbiter::detail
