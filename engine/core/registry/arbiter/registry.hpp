#pragma once
// engine/core/registry: C++ classes in (built in, or from plugins: plugin.hpp); a Registry out that
// binds each class name to its params, ports and factory. The model checks configs against it.
//
// The registry maps type names to classes (behaviour, state, interface) and value types, each
// with one declaration of params and ports that serves validation, compile and tooling alike.
// It is a value: no global instance, nothing registered during static initialisation.

#include <array>
#include <cstring>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <typeinfo>
#include <variant>
#include <vector>

#include "arbiter/behaviour.hpp"
#include "arbiter/diagnostics.hpp"
#include "arbiter/document.hpp"
#include "arbiter/value.hpp"

namespace arbiter {

class State;
template <typename T>
struct StateParam;

enum class ClassKind { kBehaviour, kState, kInterface };
const char* to_string(ClassKind kind);

enum class ParamKind {
  kBool,
  kInt,
  kDouble,
  kString,
  kVec2,
  kVec3,
  kDoubleList,
  kStringList,
  kAny
};
const char* to_string(ParamKind kind);

/// A param's value after validation. kAny params keep their document node for the class to read.
using ParamValue = std::variant<bool, std::int64_t, double, std::string, Vec2, Vec3,
                                std::vector<double>, std::vector<std::string>, Node>;

/// The kind of params whose values have C++ type T (ParamValue's alternatives, in kind order).
template <typename T>
constexpr ParamKind param_kind_of() {
  static_assert(std::variant_size_v<ParamValue> == static_cast<std::size_t>(ParamKind::kAny) + 1,
                "ParamValue's alternatives follow ParamKind's order");
  if constexpr (std::is_same_v<T, bool>) return ParamKind::kBool;
  if constexpr (std::is_same_v<T, std::int64_t>) return ParamKind::kInt;
  if constexpr (std::is_same_v<T, double>) return ParamKind::kDouble;
  if constexpr (std::is_same_v<T, std::string>) return ParamKind::kString;
  if constexpr (std::is_same_v<T, Vec2>) return ParamKind::kVec2;
  if constexpr (std::is_same_v<T, Vec3>) return ParamKind::kVec3;
  if constexpr (std::is_same_v<T, std::vector<double>>) return ParamKind::kDoubleList;
  if constexpr (std::is_same_v<T, std::vector<std::string>>) return ParamKind::kStringList;
  if constexpr (std::is_same_v<T, Node>) return ParamKind::kAny;
  static_assert(std::is_same_v<T, bool> || std::is_same_v<T, std::int64_t> ||
                    std::is_same_v<T, double> || std::is_same_v<T, std::string> ||
                    std::is_same_v<T, Vec2> || std::is_same_v<T, Vec3> ||
                    std::is_same_v<T, std::vector<double>> ||
                    std::is_same_v<T, std::vector<std::string>> || std::is_same_v<T, Node>,
                "a param's C++ type is bool, std::int64_t, double, std::string, Vec2, Vec3, "
                "std::vector<double>, std::vector<std::string> or Node");
}

/// A data member of a class, type-erased, so that registration can tell a member bound twice and
/// init() can ask where the param bound to it was written.
class MemberKey {
 public:
  MemberKey() = default;
  template <typename C, typename M>
  explicit MemberKey(M C::*member) : type_(&typeid(member)) {
    static_assert(sizeof member <= sizeof bytes_, "a data member pointer fits in a MemberKey");
    std::memcpy(bytes_.data(), &member, sizeof member);
  }
  bool empty() const { return type_ == nullptr; }
  bool operator==(const MemberKey& other) const {
    return type_ != nullptr && other.type_ != nullptr && *type_ == *other.type_ &&
           bytes_ == other.bytes_;
  }

 private:
  const std::type_info* type_ = nullptr;
  std::array<unsigned char, 2 * sizeof(void*)> bytes_{};
};

namespace detail {

template <typename M>
struct StateParamTraits : std::false_type {};
template <typename T>
struct StateParamTraits<StateParam<T>> : std::true_type {
  using type = T;
};

template <typename M>
struct PortTraits : std::false_type {};
template <typename T>
struct PortTraits<Input<T>> : std::true_type {
  using type = T;
  static constexpr bool kInput = true;
};
template <typename T>
struct PortTraits<Output<T>> : std::true_type {
  using type = T;
  static constexpr bool kInput = false;
};

/// The Behaviour, Interface or State that T derives from: what a binder is given an instance as.
template <typename T>
using RootOf =
    std::conditional_t<std::is_base_of_v<Behaviour, T>, Behaviour,
                       std::conditional_t<std::is_base_of_v<Interface, T>, Interface, State>>;

/// Class T's object, given as a pointer to its Behaviour, Interface or State part.
template <typename T>
T& instance_as(void* instance) {
  return static_cast<T&>(*static_cast<RootOf<T>*>(instance));
}

/// Whether class T may bind a member of class B: B is T or a public, unambiguous base of T, so
/// that a pointer to the member applies to a T.
template <typename T, typename B>
inline constexpr bool kMemberOf = std::is_base_of_v<B, T>&& std::is_convertible_v<T*, B*>;

/// Whether class T may bind a param to a member of type M: a StateParam handle is read per
/// planned instance, which only a state has.
template <typename T, typename M>
inline constexpr bool kParamMember = !StateParamTraits<M>::value || std::is_base_of_v<State, T>;

}  // namespace detail

/// A validated param of one instance.
struct Param {
  std::string name;
  ParamValue value;
  SourceLocation location;  ///< where it was written; the owner's location for a default
  bool defaulted = false;
};

struct ParamSet {
  std::vector<Param> items;  ///< in the class's declaration order, defaults filled in
  const Param* find(std::string_view name) const;
};

struct ParamSpec {
  std::string name;
  ParamKind kind = ParamKind::kDouble;
  std::optional<ParamValue> default_value;  ///< none: the param is required
  std::optional<double> minimum;            ///< for numbers, and each element of a number list
  std::optional<double> maximum;
  std::vector<std::string> choices;  ///< for strings: the allowed values, if restricted
  std::string description;
  /// For states: false when the param may only be set on the state, not per planned instance.
  bool per_instance = true;
  /// The param's JSON Schema (draft-07, as JSON text) for `arbiter schema`, instead of the one
  /// its kind gives: how a structured (kAny) param tells editors and CI its shape.
  std::string json_schema;
  /// The member the param is bound to, and how a new instance's member gets it before init():
  /// its value (behaviours, interfaces) or its handle, `index` among the class's params (states).
  MemberKey member;
  std::function<void(void* instance, const ParamValue& value, std::uint32_t index)> bind;
  bool member_is_handle = false;  ///< a StateParam, given its index rather than a value
  /// For a number list indexed by step (the last is held): its items may instead be written as
  /// `{from: N, level: X}`, each level held from step N on (0 before the first), which the model
  /// expands into the per-step list.
  bool by_step = false;

  /// The default, which makes the param optional. It has the kind's C++ type (an integer is
  /// taken for a double); any other type is a mistake in the class's registration, which then
  /// throws std::logic_error (reported against the plugin).
  ParamSpec& defaults_to(ParamValue value);
  ParamSpec& range(double low, double high) {
    minimum = low;
    maximum = high;
    return *this;
  }
  ParamSpec& at_least(double low) {
    minimum = low;
    return *this;
  }
  ParamSpec& one_of(std::vector<std::string> allowed) {
    choices = std::move(allowed);
    return *this;
  }
  ParamSpec& describe(std::string text) {
    description = std::move(text);
    return *this;
  }
  ParamSpec& schema(std::string json_schema_text) {
    json_schema = std::move(json_schema_text);
    return *this;
  }
  /// A number list with one number per step may be given by step ranges (see by_step).
  ParamSpec& held_by_step() {
    by_step = true;
    return *this;
  }
  ParamSpec& state_level() {
    per_instance = false;
    return *this;
  }
  bool required() const { return !default_value.has_value(); }
};

enum class PortDirection { kInput, kOutput };

struct PortSpec {
  std::string name;
  PortDirection direction = PortDirection::kInput;
  const std::type_info* cpp_type = nullptr;
  bool optional = false;  ///< may stay unbound when nothing of its name exists
  std::string description;
  /// The Input or Output member the port is bound to, and how a new instance's member gets its
  /// handle before init().
  MemberKey member;
  std::function<void(void* instance, std::uint32_t handle)> bind;

  PortSpec& make_optional() {
    optional = true;
    return *this;
  }
  PortSpec& describe(std::string text) {
    description = std::move(text);
    return *this;
  }
};

/// A class as the registry knows it. add_behaviour<T>, add_interface<T> and add_state_class<T>
/// return it as a ClassBinder<T>, which binds its params and ports to members of T.
struct ClassInfo {
  ClassInfo() = default;
  ClassInfo(const ClassInfo&) = default;
  ClassInfo(ClassInfo&&) = default;
  ClassInfo& operator=(const ClassInfo&) = default;
  ClassInfo& operator=(ClassInfo&&) = default;
  virtual ~ClassInfo();

  std::string name;
  ClassKind kind = ClassKind::kBehaviour;
  std::string origin = "built-in";
  std::string description;
  std::vector<ParamSpec> params;
  std::vector<PortSpec> ports;
  std::function<std::unique_ptr<Behaviour>()> make_behaviour;
  std::function<std::unique_ptr<Interface>()> make_interface;
  std::function<std::unique_ptr<State>()> make_state;

  ClassInfo& describe(std::string text) {
    description = std::move(text);
    return *this;
  }
  const ParamSpec* find_param(std::string_view param_name) const;
  const PortSpec* find_port(std::string_view port_name) const;

 protected:
  /// Throw std::logic_error for a name or member that comes twice.
  ParamSpec& add_param(std::string param_name, ParamKind param_kind, MemberKey member,
                       std::function<void(void*, const ParamValue&, std::uint32_t)> bind);
  PortSpec& add_port(std::string port_name, PortDirection direction, const std::type_info& type,
                     MemberKey member, std::function<void(void*, std::uint32_t)> bind);
};

/// Class T's ClassInfo, which binds T's params and ports to its members (or to members of a
/// public base of T: a mixin). The member's class is checked at compile time, and a new instance
/// reaches the member through T by static_cast, whatever base declared it.
template <typename T>
class ClassBinder final : public ClassInfo {
 public:
  /// A param bound to a data member: `info.param("gain", &GoTo::gain_)`. The kind follows from
  /// the member's type (bool, std::int64_t, double, std::string, Vec2, Vec3, std::vector<double>,
  /// std::vector<std::string> or Node); a new instance's member holds the validated value before
  /// init(). A state's params vary per planned instance, so a state binds a StateParam<T> handle,
  /// read in a step with `ctx.param(handle)`; only a state_level() param may bind a state's plain
  /// member (else the load fails). A member of a class that T does not publicly derive from, or
  /// a StateParam member of a class that is no state, does not compile; a name or member that
  /// comes twice throws std::logic_error.
  template <typename B, typename M>
  ParamSpec& param(std::string param_name, M B::*member) {
    static_assert(detail::kMemberOf<T, B>,
                  "a param binds a member of the registered class or of a public base of it");
    static_assert(detail::kParamMember<T, M>,
                  "only a state binds a param to a StateParam handle (read per planned "
                  "instance); bind a member of the param's type");
    if constexpr (detail::StateParamTraits<M>::value) {
      ParamSpec& spec = add_param(
          std::move(param_name), param_kind_of<typename detail::StateParamTraits<M>::type>(),
          MemberKey(member), [member](void* instance, const ParamValue&, std::uint32_t index) {
            detail::instance_as<T>(instance).*member = M{index};
          });
      spec.member_is_handle = true;
      return spec;
    } else {
      return add_param(std::move(param_name), param_kind_of<M>(), MemberKey(member),
                       [member](void* instance, const ParamValue& value, std::uint32_t) {
                         detail::instance_as<T>(instance).*member = std::get<M>(value);
                       });
    }
  }
  /// A port bound to an Input<T> (a sensor the class reads) or Output<T> (an actuator it
  /// writes) member: `info.port("velocity", &GoTo::velocity_)`. A new instance's member holds
  /// the resolved handle before init(). Members are checked, and duplicates throw, as for params.
  template <typename B, typename M>
  PortSpec& port(std::string port_name, M B::*member) {
    using Traits = detail::PortTraits<M>;
    static_assert(Traits::value, "a port binds to an Input<T> or Output<T> member");
    static_assert(detail::kMemberOf<T, B>,
                  "a port binds a member of the registered class or of a public base of it");
    return add_port(std::move(port_name),
                    Traits::kInput ? PortDirection::kInput : PortDirection::kOutput,
                    typeid(typename Traits::type), MemberKey(member),
                    [member](void* instance, std::uint32_t handle) {
                      detail::instance_as<T>(instance).*member = M{handle};
                    });
  }
  ClassBinder& describe(std::string text) {
    ClassInfo::describe(std::move(text));
    return *this;
  }
};

class Registry {
 public:
  /// A registry that knows the built-in value types (bool, int, double, vec2, vec3, string) and
  /// no classes.
  Registry();

  template <typename T>
  ClassBinder<T>& add_behaviour(std::string name) {
    static_assert(std::is_base_of_v<Behaviour, T>, "a behaviour class derives from Behaviour");
    auto& info = add_bound_class<T>(std::move(name), ClassKind::kBehaviour);
    info.make_behaviour = [] { return std::unique_ptr<Behaviour>(new T()); };
    return info;
  }
  template <typename T>
  ClassBinder<T>& add_interface(std::string name) {
    static_assert(std::is_base_of_v<Interface, T>, "an interface class derives from Interface");
    auto& info = add_bound_class<T>(std::move(name), ClassKind::kInterface);
    info.make_interface = [] { return std::unique_ptr<Interface>(new T()); };
    return info;
  }
  /// States are created through a factory so that the State header stays out of this one.
  ClassInfo& add_state(std::string name, std::function<std::unique_ptr<State>()> factory) {
    auto& info = add_class(std::move(name), ClassKind::kState);
    info.make_state = std::move(factory);
    return info;
  }
  template <typename T>
  ValueType& add_value_type(std::string name) {
    return add_value_type(make_value_type<T>(std::move(name)));
  }
  ValueType& add_value_type(ValueType type);

  /// Throws std::logic_error when `name` is taken for that kind: registering twice is a
  /// programming error. A behaviour and a state may share a name (`scripted`).
  ClassInfo& add_class(std::string name, ClassKind kind);
  /// As add_class, as a ClassBinder<T> (add_behaviour<T>, add_interface<T> and
  /// add_state_class<T> set its factory).
  template <typename T>
  ClassBinder<T>& add_bound_class(std::string name, ClassKind kind) {
    auto binder = std::make_unique<ClassBinder<T>>();
    ClassBinder<T>& info = *binder;
    add_class(std::move(binder), std::move(name), kind);
    return info;
  }

  const ClassInfo* find_class(ClassKind kind, std::string_view name) const;
  /// A class of that name of any kind (for "is a state class, not a behaviour class").
  const ClassInfo* find_any_class(std::string_view name) const;
  const ValueType* find_value_type(std::string_view name) const;
  const ValueType* value_type_of(const std::type_info& type) const;
  /// "double" for a registered C++ type, else its mangled name (for messages).
  std::string value_type_name(const std::type_info& type) const;

  std::vector<std::string> class_names(ClassKind kind) const;
  std::vector<std::string> value_type_names() const;
  /// Every class, ordered by name, then kind.
  const std::map<std::pair<std::string, ClassKind>, std::unique_ptr<ClassInfo>>& classes() const {
    return classes_;
  }
  const std::vector<std::unique_ptr<ValueType>>& value_types() const { return value_types_; }

  /// Sets the origin recorded for classes and value types added from now on.
  void set_origin(std::string origin) { origin_ = std::move(origin); }

  /// Keeps a plugin library loaded while this registry, or any program compiled from it, lives.
  void keep_loaded(std::string path, std::shared_ptr<void> library) {
    library_paths_.push_back(std::move(path));
    libraries_.push_back(std::move(library));
  }
  bool has_library(std::string_view path) const {
    for (const auto& loaded : library_paths_) {
      if (loaded == path) return true;
    }
    return false;
  }
  const std::vector<std::shared_ptr<void>>& libraries() const { return libraries_; }

  /// Moves every class and value type of `other` into this registry. A name both define is
  /// reported at `where` with both origins and not merged.
  void merge(Registry&& other, const SourceLocation& where, Diagnostics& diagnostics);

 private:
  void add_class(std::unique_ptr<ClassInfo> info, std::string name, ClassKind kind);

  // Declared first so that it is destroyed last: the classes and value types below hold code
  // from these libraries.
  std::vector<std::shared_ptr<void>> libraries_;
  std::vector<std::string> library_paths_;
  // Behind pointers: each is the ClassBinder<T> of its class, when it was added as one.
  std::map<std::pair<std::string, ClassKind>, std::unique_ptr<ClassInfo>> classes_;
  std::vector<std::unique_ptr<ValueType>> value_types_;  // stable addresses for handles
  std::string origin_ = "built-in";
};

}  // namespace arbiter
