#include "arbiter/catalog.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <string_view>

#include "tools/dump/param_json.hpp"

namespace arbiter {

namespace {

using Json = nlohmann::ordered_json;

constexpr ClassKind kKinds[] = {ClassKind::kBehaviour, ClassKind::kInterface, ClassKind::kState};

/// "in [0, 1]", "at least 1", "at most 5", or empty.
std::string range_of(const ParamSpec& spec) {
  if (spec.minimum && spec.maximum) return fmt::format("in [{}, {}]", *spec.minimum, *spec.maximum);
  if (spec.minimum) return fmt::format("at least {}", *spec.minimum);
  if (spec.maximum) return fmt::format("at most {}", *spec.maximum);
  return {};
}

std::string param_line(const ParamSpec& spec) {
  std::string line = fmt::format("{}: {}", spec.name, to_string(spec.kind));
  if (spec.required()) {
    line += ", required";
  } else if (const Json json = detail::param_json(*spec.default_value); json.is_null()) {
    line += ", optional";
  } else {
    line += ", default " + json.dump();
  }
  if (const auto range = range_of(spec); !range.empty()) line += ", " + range;
  if (!spec.choices.empty()) {
    std::string choices;
    for (const auto& choice : spec.choices) choices += (choices.empty() ? "" : " | ") + choice;
    line += ", one of " + choices;
  }
  if (!spec.per_instance) line += ", set on the state only";
  return line;
}

std::string port_line(const PortSpec& spec, const Registry& registry) {
  return fmt::format("{}: {} {}{}", spec.name,
                     spec.direction == PortDirection::kInput ? "input" : "output",
                     registry.value_type_name(*spec.cpp_type), spec.optional ? ", optional" : "");
}

}  // namespace

std::string catalog_text(const Registry& registry) {
  std::string out;
  for (const ClassKind kind : kKinds) {
    out += fmt::format("{}{} classes\n", out.empty() ? "" : "\n", to_string(kind));
    bool any = false;
    for (const auto& [key, info] : registry.classes()) {
      const ClassInfo& cls = *info;
      if (cls.kind != kind) continue;
      if (any) out += "\n";
      any = true;
      out += fmt::format("  {} ({})\n", cls.name, cls.origin);
      if (!cls.description.empty()) out += fmt::format("    {}\n", cls.description);
      out += cls.params.empty() ? "    params: none\n" : "    params:\n";
      for (const auto& spec : cls.params) {
        out += fmt::format("      {}\n", param_line(spec));
        if (!spec.description.empty()) out += fmt::format("        {}\n", spec.description);
      }
      out += cls.ports.empty() ? "    ports: none\n" : "    ports:\n";
      for (const auto& spec : cls.ports) {
        out += fmt::format("      {}\n", port_line(spec, registry));
        if (!spec.description.empty()) out += fmt::format("        {}\n", spec.description);
      }
    }
    if (!any) out += "  (none)\n";
  }
  out += "\nvalue types\n";
  for (const auto& type : registry.value_types()) {
    out += fmt::format("  {} ({}{})\n", type->name, type->origin,
                       type->aggregatable() ? ", can be averaged" : "");
  }
  return out;
}

std::string catalog_json(const Registry& registry) {
  Json classes = Json::array();
  for (const ClassKind kind : kKinds) {
    for (const auto& [key, info] : registry.classes()) {
      const ClassInfo& cls = *info;
      if (cls.kind != kind) continue;
      Json params = Json::array();
      for (const auto& spec : cls.params) {
        Json param = {
            {"name", spec.name},
            {"type", to_string(spec.kind)},
            {"required", spec.required()},
            {"default", spec.default_value ? detail::param_json(*spec.default_value) : Json()},
            {"minimum", spec.minimum ? Json(*spec.minimum) : Json()},
            {"maximum", spec.maximum ? Json(*spec.maximum) : Json()},
            {"choices", spec.choices},
            {"description", spec.description}};
        if (kind == ClassKind::kState) param["per_instance"] = spec.per_instance;
        params.push_back(std::move(param));
      }
      Json ports = Json::array();
      for (const auto& spec : cls.ports) {
        ports.push_back(
            {{"name", spec.name},
             {"direction", spec.direction == PortDirection::kInput ? "input" : "output"},
             {"type", registry.value_type_name(*spec.cpp_type)},
             {"optional", spec.optional},
             {"description", spec.description}});
      }
      classes.push_back({{"name", cls.name},
                         {"kind", to_string(cls.kind)},
                         {"origin", cls.origin},
                         {"description", cls.description},
                         {"params", std::move(params)},
                         {"ports", std::move(ports)}});
    }
  }
  Json types = Json::array();
  for (const auto& type : registry.value_types()) {
    types.push_back(
        {{"name", type->name}, {"origin", type->origin}, {"aggregatable", type->aggregatable()}});
  }
  const Json out = {{"classes", std::move(classes)}, {"value_types", std::move(types)}};
  return out.dump(2) + "\n";
}

std::vector<std::string> plugins_on_path(const PluginOptions& options) {
  namespace fs = std::filesystem;
  std::vector<std::string> names;
  std::set<std::string> seen;
  for (const auto& dir : plugin_search_path(options)) {
    std::error_code error;
    std::vector<std::string> here;
    for (const auto& entry : fs::directory_iterator(dir, error)) {
      const std::string file = entry.path().filename().string();
      constexpr std::string_view kPrefix = "arbiter_";
      constexpr std::string_view kSuffix = ".so";
      if (!entry.is_regular_file(error) || file.size() <= kPrefix.size() + kSuffix.size() ||
          file.compare(0, kPrefix.size(), kPrefix) != 0 ||
          file.compare(file.size() - kSuffix.size(), kSuffix.size(), kSuffix) != 0) {
        continue;
      }
      here.push_back(file.substr(kPrefix.size(), file.size() - kPrefix.size() - kSuffix.size()));
    }
    std::sort(here.begin(), here.end());
    for (auto& name : here) {
      if (seen.insert(name).second) names.push_back(std::move(name));
    }
  }
  return names;
}

}  // namespace arbiter
