#pragma once
// engine/core/model: a Document and the Registry in; a validated Model out (every name resolved,
// every param checked, each item with its place), or located diagnostics. Compile reads it.
//
// Stage 2 of the data path: the validated model. Plain structs in which every name has been
// checked to resolve, every type to match and every param to fit its class's schema; each item
// keeps the location it was declared at for later diagnostics.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "arbiter/diagnostics.hpp"
#include "arbiter/document.hpp"
#include "arbiter/registry.hpp"

namespace arbiter {

struct Name {
  std::string text;
  SourceLocation location;
};

struct PortBinding {
  const PortSpec* port = nullptr;
  std::string
      target;  ///< a sensor (input) or an actuator of the own layer (output); empty: unbound
  SourceLocation location;
};

struct ActuatorDecl {
  Name name;
  const ValueType* type = nullptr;
  bool aggregate = false;
  std::optional<Node> default_value;  ///< checked against `type`
  std::optional<Node> safe_value;     ///< `safe:`, checked against `type`
  std::string layer;
};

/// What the manager does with a behaviour (or interface) whose callback throws (`on_exception`,
/// docs/robustness.md). Every policy reports the exception once and drops that step's writes.
enum class FaultPolicy {
  kInactive,  ///< it counts as inactive in each step where it throws, and keeps running
  kDisable,   ///< it counts as inactive from that step on; its callbacks are no longer called
  kStop,      ///< that step completes, then the manager stops (Manager::stopped())
};
const char* to_string(FaultPolicy policy);

struct BehaviourDecl {
  Name name;
  const ClassInfo* cls = nullptr;
  ParamSet params;
  std::vector<PortBinding> ports;  ///< one per port the class declares
  SourceLocation location;
  std::optional<FaultPolicy> on_exception;  ///< unset: the config's
};

struct InhibitionDecl {
  Name inhibitor;
  Name inhibited;
  bool chaining = false;
  SourceLocation location;
};

struct LayerDecl {
  Name name;
  const ClassInfo* interface = nullptr;  ///< set for an interface layer
  ParamSet params;                       ///< the interface class's params
  std::vector<PortBinding> ports;        ///< the interface class's ports
  std::vector<ActuatorDecl> actuators;
  std::vector<Name> sensors;
  std::vector<BehaviourDecl> behaviours;
  std::vector<InhibitionDecl> inhibitions;  ///< duplicates already merged
  std::optional<bool> normalise;
  std::vector<Name> lint_ignore;  ///< lint codes silenced in this layer (`lint: {ignore: [...]}`)
  bool is_interface() const { return interface != nullptr; }
};

struct StateDecl {
  Name name;
  const ClassInfo* cls = nullptr;
  ParamSet params;  ///< the state's params as written (class defaults are not filled in)
  std::optional<Name> machine;  ///< a child controller this state owns and steps
  SourceLocation location;
};

struct QueueEntry {
  Name state;
  std::vector<Param> overrides;  ///< per-instance params, validated against the state class
};

/// Scripted pre-emption: at controller cycle `cycle`, replace the plan with `go_to` and leave
/// the current state now (lets a config try what a pre-step hook would do).
struct Preemption {
  std::uint64_t cycle = 0;
  QueueEntry go_to;
  SourceLocation location;
};

struct StateMachineDecl {
  Name name;
  std::vector<StateDecl> states;
  std::vector<QueueEntry> queue;
  std::vector<Preemption> preempt;
  std::size_t capacity = 0;
  SourceLocation location;
};

struct Model {
  std::string name;
  SourceLocation location;
  double rate_hz = 15.0;
  std::uint64_t steps = 0;  ///< `steps:`, the default length of `arbiter run`; 0: not set
  bool normalise = false;
  FaultPolicy on_exception = FaultPolicy::kInactive;  ///< for behaviours and interfaces
  std::vector<Name> plugins;
  std::vector<LayerDecl> layers;
  std::vector<StateMachineDecl> state_machines;
  std::vector<std::string> files;  ///< the config and everything it includes
  std::vector<Name> lint_ignore;   ///< lint codes silenced in the whole config

  const LayerDecl* find_layer(std::string_view name) const;
  /// The actuator of that name in any layer, or nullptr.
  const ActuatorDecl* find_actuator(std::string_view name) const;
};

/// The longest name, in characters: a longer one is text pasted where a name goes, and every
/// view, trace record and recording schema repeats a name.
constexpr std::size_t kMaxNameLength = 128;

/// Whether `text` is a name: an identifier, `[a-z_][a-z0-9_]*`, of at most kMaxNameLength
/// characters.
bool is_identifier(std::string_view text);

/// Why `text` is not a name, as an error says it: "'Kick' is not WHAT: names are lower-case
/// identifiers ([a-z_][a-z0-9_]*)", where WHAT is "a valid name for a layer", say. A name over
/// kMaxNameLength is shown by its start and its length only.
std::string name_error(std::string_view text, std::string_view what);

/// Validates per-instance params of a state (overrides may be null) against its class: the
/// overrides must fit and, with the state's own params and the class defaults, supply every
/// required param. Returns the overrides.
std::vector<Param> check_state_params(const StateDecl& state, const Node* overrides,
                                      const SourceLocation& where, const Registry& registry,
                                      Diagnostics& diagnostics);

/// A class with its checked params and bound ports, as a config declares an instance.
struct Declaration {
  const ClassInfo* cls = nullptr;
  ParamSet params;                 ///< defaults filled in
  std::vector<PortBinding> ports;  ///< one per port the class declares
};

/// Declares an instance of `model` (built without error) anew, as a config would: `type` names a
/// class of `kind`, `params` (may be null) are checked against it and, for an instance of a
/// layer (`layer`: its index; none for a state), `ports` (may be null) are bound in that layer.
/// Reports at the nodes, naming the instance as `owner` (declared at `owner_at`); nullopt when
/// anything was wrong. Substitution (substitute.hpp) declares its replacements through it.
std::optional<Declaration> redeclare(const Model& model, ClassKind kind, const Node& type,
                                     const Node* params, const Node* ports,
                                     std::optional<std::size_t> layer, const std::string& owner,
                                     const SourceLocation& owner_at, const Registry& registry,
                                     Diagnostics& diagnostics);

/// Validates a parsed config (and the files it includes, read relative to `root`'s file) against
/// the registry's classes. Reports every problem; the model is only meaningful when no error was
/// reported.
Model build_model(const Node& root, const Registry& registry, Diagnostics& diagnostics,
                  const ReadLimits& limits = {});

/// The same, reading included files through `files` (which keeps them, and their text).
Model build_model(const Node& root, const Registry& registry, Diagnostics& diagnostics,
                  SourceFiles& files);

}  // namespace arbiter
