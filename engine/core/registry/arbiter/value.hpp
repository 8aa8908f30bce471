#pragma once
// Value types carried by actuators, sensors and ports. Storage is type-erased (one flat buffer,
// sized at compile); each type brings the handful of operations the engine needs.

#include <cmath>
#include <cstdint>
#include <new>
#include <string>
#include <typeinfo>

#include "arbiter/document.hpp"

namespace arbiter {

struct Vec2 {
  double x = 0.0;
  double y = 0.0;
  friend bool operator==(const Vec2& a, const Vec2& b) { return a.x == b.x && a.y == b.y; }
};

struct Vec3 {
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
  friend bool operator==(const Vec3& a, const Vec3& b) {
    return a.x == b.x && a.y == b.y && a.z == b.z;
  }
};

/// The operations of one value type. `mean` is null for types that cannot be averaged (such
/// actuators cannot be `aggregate: true`).
struct ValueType {
  std::string name;
  std::string origin = "built-in";
  const std::type_info* cpp_type = nullptr;
  std::size_t size = 0;
  std::size_t alignment = 0;
  void (*construct)(void* at) = nullptr;  ///< the type's zero value
  void (*destroy)(void* at) = nullptr;
  void (*assign)(void* to, const void* from) = nullptr;
  /// Reads a config value; on failure returns false and sets `expected` ("a number", ...).
  bool (*from_node)(const Node& node, void* to, std::string& expected) = nullptr;
  void (*append_json)(const void* value, std::string& out) = nullptr;
  /// out ← Σ wᵢ·valuesᵢ / Σ wᵢ over `count` values; weights are positive.
  void (*mean)(void* out, const void* const* values, const double* weights,
               std::size_t count) = nullptr;

  bool aggregatable() const { return mean != nullptr; }
};

/// Customisation point: specialise for a plugin's own value type (see docs/plugins.md), giving
/// `from_node`, `append_json` and, for averaging, `mean`.
template <typename T>
struct ValueTraits;

namespace detail {

void append_json_number(double value, std::string& out);
void append_json_string(const std::string& value, std::string& out);
bool read_finite(const Node& node, double& to);
bool read_components(const Node& node, double* to, std::size_t count);

template <typename T, typename = void>
struct HasMean : std::false_type {};
template <typename T>
struct HasMean<T, std::void_t<decltype(&ValueTraits<T>::mean)>> : std::true_type {};

/// Σ wᵢ·f(valuesᵢ) / Σ wᵢ, for averaging one component at a time.
template <typename T, typename Component>
double weighted_mean(const void* const* values, const double* weights, std::size_t count,
                     Component component) {
  double sum = 0.0;
  double total = 0.0;
  for (std::size_t i = 0; i < count; ++i) {
    sum += weights[i] * component(*static_cast<const T*>(values[i]));
    total += weights[i];
  }
  return sum / total;
}

}  // namespace detail

template <>
struct ValueTraits<bool> {
  static bool from_node(const Node& node, bool& to, std::string& expected) {
    const auto value = node.as_bool();
    expected = "a boolean";
    if (value) to = *value;
    return value.has_value();
  }
  static void append_json(const bool& value, std::string& out) { out += value ? "true" : "false"; }
};

template <>
struct ValueTraits<std::int64_t> {
  static bool from_node(const Node& node, std::int64_t& to, std::string& expected) {
    const auto value = node.as_int();
    expected = "an integer";
    if (value) to = *value;
    return value.has_value();
  }
  static void append_json(const std::int64_t& value, std::string& out) {
    out += std::to_string(value);
  }
  /// The mean of integers is rounded to the nearest integer (halves away from zero).
  static void mean(std::int64_t& out, const void* const* values, const double* weights,
                   std::size_t count) {
    out = std::llround(detail::weighted_mean<std::int64_t>(
        values, weights, count, [](std::int64_t v) { return static_cast<double>(v); }));
  }
};

template <>
struct ValueTraits<double> {
  static bool from_node(const Node& node, double& to, std::string& expected) {
    expected = "a finite number";
    return detail::read_finite(node, to);
  }
  static void append_json(const double& value, std::string& out) {
    detail::append_json_number(value, out);
  }
  static void mean(double& out, const void* const* values, const double* weights,
                   std::size_t count) {
    out = detail::weighted_mean<double>(values, weights, count, [](double v) { return v; });
  }
};

template <>
struct ValueTraits<Vec2> {
  static bool from_node(const Node& node, Vec2& to, std::string& expected) {
    expected = "a list of 2 finite numbers";
    double xy[2];
    if (!detail::read_components(node, xy, 2)) return false;
    to = {xy[0], xy[1]};
    return true;
  }
  static void append_json(const Vec2& value, std::string& out) {
    out += '[';
    detail::append_json_number(value.x, out);
    out += ", ";
    detail::append_json_number(value.y, out);
    out += ']';
  }
  static void mean(Vec2& out, const void* const* values, const double* weights, std::size_t count) {
    out.x = detail::weighted_mean<Vec2>(values, weights, count, [](const Vec2& v) { return v.x; });
    out.y = detail::weighted_mean<Vec2>(values, weights, count, [](const Vec2& v) { return v.y; });
  }
};

template <>
struct ValueTraits<Vec3> {
  static bool from_node(const Node& node, Vec3& to, std::string& expected) {
    expected = "a list of 3 finite numbers";
    double xyz[3];
    if (!detail::read_components(node, xyz, 3)) return false;
    to = {xyz[0], xyz[1], xyz[2]};
    return true;
  }
  static void append_json(const Vec3& value, std::string& out) {
    out += '[';
    detail::append_json_number(value.x, out);
    out += ", ";
    detail::append_json_number(value.y, out);
    out += ", ";
    detail::append_json_number(value.z, out);
    out += ']';
  }
  static void mean(Vec3& out, const void* const* values, const double* weights, std::size_t count) {
    out.x = detail::weighted_mean<Vec3>(values, weights, count, [](const Vec3& v) { return v.x; });
    out.y = detail::weighted_mean<Vec3>(values, weights, count, [](const Vec3& v) { return v.y; });
    out.z = detail::weighted_mean<Vec3>(values, weights, count, [](const Vec3& v) { return v.z; });
  }
};

/// Strings are stored as std::string with capacity reserved at compile (kStringCapacity): writes
/// up to that length never allocate in the step loop.
inline constexpr std::size_t kStringCapacity = 64;

template <>
struct ValueTraits<std::string> {
  static bool from_node(const Node& node, std::string& to, std::string& expected) {
    expected = "a string";
    if (!node.is_scalar()) return false;
    to = node.text();
    return true;
  }
  static void append_json(const std::string& value, std::string& out) {
    detail::append_json_string(value, out);
  }
};

/// Builds the ValueType of a C++ type from its ValueTraits.
template <typename T>
ValueType make_value_type(std::string name) {
  using Traits = ValueTraits<T>;
  ValueType type;
  type.name = std::move(name);
  type.cpp_type = &typeid(T);
  type.size = sizeof(T);
  type.alignment = alignof(T);
  type.construct = [](void* at) {
    T* value = new (at) T();
    if constexpr (std::is_same_v<T, std::string>) value->reserve(kStringCapacity);
  };
  type.destroy = [](void* at) { static_cast<T*>(at)->~T(); };
  type.assign = [](void* to, const void* from) {
    *static_cast<T*>(to) = *static_cast<const T*>(from);
  };
  type.from_node = [](const Node& node, void* to, std::string& expected) {
    return Traits::from_node(node, *static_cast<T*>(to), expected);
  };
  type.append_json = [](const void* value, std::string& out) {
    Traits::append_json(*static_cast<const T*>(value), out);
  };
  if constexpr (detail::HasMean<T>::value) {
    type.mean = [](void* out, const void* const* values, const double* weights, std::size_t count) {
      Traits::mean(*static_cast<T*>(out), values, weights, count);
    };
  }
  return type;
}

}  // namespace arbiter
