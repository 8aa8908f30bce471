#include "arbiter/registry.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace arbiter {

const char* to_string(ClassKind kind) {
  switch (kind) {
    case ClassKind::kBehaviour:
      return "behaviour";
    case ClassKind::kState:
      return "state";
    case ClassKind::kInterface:
      return "interface";
  }
  return "?";
}

const char* to_string(ParamKind kind) {
  switch (kind) {
    case ParamKind::kBool:
      return "bool";
    case ParamKind::kInt:
      return "int";
    case ParamKind::kDouble:
      return "double";
    case ParamKind::kString:
      return "string";
    case ParamKind::kVec2:
      return "vec2";
    case ParamKind::kVec3:
      return "vec3";
    case ParamKind::kDoubleList:
      return "list of double";
    case ParamKind::kStringList:
      return "list of string";
    case ParamKind::kAny:
      return "any";
  }
  return "?";
}

ParamSpec& ParamSpec::defaults_to(ParamValue value) {
  if (kind == ParamKind::kDouble && std::holds_alternative<std::int64_t>(value)) {
    value = static_cast<double>(std::get<std::int64_t>(value));
  }
  if (value.index() != static_cast<std::size_t>(kind)) {
    throw std::logic_error(fmt::format("param '{}' is of kind {}, but its default is of kind {}",
                                       name, to_string(kind),
                                       to_string(static_cast<ParamKind>(value.index()))));
  }
  default_value = std::move(value);
  return *this;
}

const Param* ParamSet::find(std::string_view name) const {
  for (const auto& item : items) {
    if (item.name == name) return &item;
  }
  return nullptr;
}

ClassInfo::~ClassInfo() = default;

ParamSpec& ClassInfo::add_param(std::string param_name, ParamKind param_kind, MemberKey member,
                                std::function<void(void*, const ParamValue&, std::uint32_t)> bind) {
  for (const auto& existing : params) {
    if (existing.name == param_name) {
      throw std::logic_error(fmt::format("class '{}' declares param '{}' twice", name, param_name));
    }
    if (!member.empty() && existing.member == member) {
      throw std::logic_error(
          fmt::format("class '{}' binds param '{}' to the member that param "
                      "'{}' is already bound to",
                      name, param_name, existing.name));
    }
  }
  auto& spec = params.emplace_back();
  spec.name = std::move(param_name);
  spec.kind = param_kind;
  spec.member = member;
  spec.bind = std::move(bind);
  return spec;
}

PortSpec& ClassInfo::add_port(std::string port_name, PortDirection direction,
                              const std::type_info& type, MemberKey member,
                              std::function<void(void*, std::uint32_t)> bind) {
  for (const auto& existing : ports) {
    if (existing.name == port_name) {
      throw std::logic_error(fmt::format("class '{}' declares port '{}' twice", name, port_name));
    }
    if (!member.empty() && existing.member == member) {
      throw std::logic_error(
          fmt::format("class '{}' binds port '{}' to the member that port "
                      "'{}' is already bound to",
                      name, port_name, existing.name));
    }
  }
  auto& spec = ports.emplace_back();
  spec.name = std::move(port_name);
  spec.direction = direction;
  spec.cpp_type = &type;
  spec.member = member;
  spec.bind = std::move(bind);
  return spec;
}

const ParamSpec* ClassInfo::find_param(std::string_view param_name) const {
  for (const auto& spec : params) {
    if (spec.name == param_name) return &spec;
  }
  return nullptr;
}

const PortSpec* ClassInfo::find_port(std::string_view port_name) const {
  for (const auto& spec : ports) {
    if (spec.name == port_name) return &spec;
  }
  return nullptr;
}

Registry::Registry() {
  add_value_type<bool>("bool");
  add_value_type<std::int64_t>("int");
  add_value_type<double>("double");
  add_value_type<Vec2>("vec2");
  add_value_type<Vec3>("vec3");
  add_value_type<std::string>("string");
}

ValueType& Registry::add_value_type(ValueType type) {
  if (find_value_type(type.name) != nullptr) {
    throw std::logic_error(fmt::format("value type '{}' registered twice", type.name));
  }
  if (type.cpp_type != nullptr && value_type_of(*type.cpp_type) != nullptr) {
    throw std::logic_error(fmt::format("C++ type of value type '{}' is already registered as '{}'",
                                       type.name, value_type_of(*type.cpp_type)->name));
  }
  type.origin = origin_;
  return *value_types_.emplace_back(std::make_unique<ValueType>(std::move(type)));
}

ClassInfo& Registry::add_class(std::string name, ClassKind kind) {
  auto info = std::make_unique<ClassInfo>();
  ClassInfo& added = *info;
  add_class(std::move(info), std::move(name), kind);
  return added;
}

void Registry::add_class(std::unique_ptr<ClassInfo> info, std::string name, ClassKind kind) {
  if (find_class(kind, name) != nullptr) {
    throw std::logic_error(fmt::format("{} class '{}' registered twice", to_string(kind), name));
  }
  info->name = name;
  info->kind = kind;
  info->origin = origin_;
  classes_.emplace(std::make_pair(std::move(name), kind), std::move(info));
}

const ClassInfo* Registry::find_class(ClassKind kind, std::string_view name) const {
  const auto found = classes_.find(std::make_pair(std::string(name), kind));
  return found == classes_.end() ? nullptr : found->second.get();
}

const ClassInfo* Registry::find_any_class(std::string_view name) const {
  const auto found = classes_.lower_bound(std::make_pair(std::string(name), ClassKind{}));
  return found != classes_.end() && found->first.first == name ? found->second.get() : nullptr;
}

const ValueType* Registry::find_value_type(std::string_view name) const {
  for (const auto& type : value_types_) {
    if (type->name == name) return type.get();
  }
  return nullptr;
}

const ValueType* Registry::value_type_of(const std::type_info& type) const {
  for (const auto& candidate : value_types_) {
    if (candidate->cpp_type != nullptr && *candidate->cpp_type == type) return candidate.get();
  }
  return nullptr;
}

std::string Registry::value_type_name(const std::type_info& type) const {
  const ValueType* found = value_type_of(type);
  return found != nullptr ? found->name : fmt::format("<unregistered C++ type {}>", type.name());
}

std::vector<std::string> Registry::class_names(ClassKind kind) const {
  std::vector<std::string> names;
  for (const auto& [key, info] : classes_) {
    if (info->kind == kind) names.push_back(info->name);
  }
  return names;
}

std::vector<std::string> Registry::value_type_names() const {
  std::vector<std::string> names;
  for (const auto& type : value_types_) names.push_back(type->name);
  return names;
}

void Registry::merge(Registry&& other, const SourceLocation& where, Diagnostics& diagnostics) {
  for (auto& [key, info] : other.classes_) {
    if (const ClassInfo* existing = find_class(info->kind, info->name)) {
      diagnostics.error(
          where, "class-clash",
          fmt::format("{} class '{}' from {} clashes with the one from {}", to_string(info->kind),
                      info->name, info->origin, existing->origin));
      continue;
    }
    classes_.emplace(key, std::move(info));
  }
  for (auto& type : other.value_types_) {
    if (type->origin == "built-in") continue;  // every registry starts with these
    if (const ValueType* existing = find_value_type(type->name)) {
      diagnostics.error(where, "class-clash",
                        fmt::format("value type '{}' from {} clashes with the one from {}",
                                    type->name, type->origin, existing->origin));
      continue;
    }
    value_types_.push_back(std::move(type));
  }
}

}  // namespace arbiter
