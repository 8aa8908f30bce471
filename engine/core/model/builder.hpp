#pragma once
// ModelBuilder reads a config document, and the files it includes, into the validated Model.
// Private to engine/core/model. Each part of a config is read in its own file:
//   model.cpp           the top level of each file, includes, and the entry points of model.hpp
//   params.cpp          classes, their params, and the scalar values configs are made of
//   layers.cpp          layers, actuators, sensors, port bindings and behaviours
//   inhibitions.cpp     a layer's inhibitions
//   state_machines.cpp  state machines, their queues and pre-emptions, and who owns which
// Every diagnostic goes to `diagnostics_`; reading goes on after an error, so that one run reports
// every mistake of a config.

#include <cstddef>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "arbiter/model.hpp"

namespace arbiter::detail {

class ModelBuilder {
 public:
  ModelBuilder(const Registry& registry, Diagnostics& diagnostics, SourceFiles& files)
      : registry_(registry), diagnostics_(diagnostics), files_(files) {}

  /// Marks the root file as being read, so that including it again is a cycle.
  void enter_root(const std::string& file);
  Model build(const Node& root);

  /// Validates per-instance params of a queued state: the overrides must fit the class and,
  /// together with the state's defaults, supply every required param.
  std::vector<Param> check_instance_params(const StateDecl& state, const Node* overrides,
                                           const SourceLocation& where);

  /// Takes a built model's layers and actuators, so that redeclare() binds ports as build()
  /// did.
  void seed(const Model& model);
  std::optional<Declaration> redeclare(ClassKind kind, const Node& type, const Node* params,
                                       const Node* ports, std::optional<std::size_t> layer,
                                       const std::string& owner, const SourceLocation& owner_at);

 private:
  // Raw per-layer parts kept until every actuator of every file is known.
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
  struct ActuatorInfo {
    std::string layer;
    SourceLocation location;
    const ValueType* type = nullptr;
  };
  struct InhibitionIndex;  // inhibitions.cpp

  // --- files and includes (model.cpp) ---------------------------------------------------------

  void read_file(const Node& root, bool is_root);
  void include(const std::string& relative, const SourceLocation& where);

  // --- scalar readers and classes (params.cpp) -------------------------------------------------

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
  static void add_quote_hint(Diagnostic& diagnostic, const Node& node);
  std::optional<std::string> read_string(const Node& node, std::string_view expected);
  std::optional<std::string> read_identifier(const Node& node, std::string_view what);
  /// A name that is reported when it is not an identifier but still returned, so that the rest
  /// of its item is checked (and named in messages) as written.
  std::optional<std::string> read_name(const Node& node, std::string_view what);
  bool check_identifier(const std::string& text, const SourceLocation& where,
                        std::string_view what);
  std::optional<FaultPolicy> read_fault_policy(const Node& node);
  std::optional<bool> read_bool(const Node& node, std::string_view what);
  /// `lint: {ignore: [code, ...]}`. The codes are checked by the lint stage, which defines them.
  void read_lint(const Node& node, std::vector<Name>& ignore);
  /// Whether `name` (`soccer.KickBall`) belongs to a plugin the config lists (by name or as a
  /// path to `arbiter_soccer.so`) but that registered no class: it was not found or not loaded.
  bool from_unloaded_plugin(const std::string& name) const;
  const ClassInfo* read_class(const Node& node, ClassKind kind, std::string_view what);

  // --- params (params.cpp) ---------------------------------------------------------------------

  std::optional<ParamValue> read_param(const ParamSpec& spec, const Node& node,
                                       std::string_view owner);
  /// A by_step number list written as `{from: N, level: X}` items, expanded into one per step.
  std::optional<ParamValue> read_by_step(const ParamSpec& spec, const Node& node,
                                         std::string_view owner);
  /// Validates `params` (may be null) against the class; fills in defaults.
  ParamSet read_params(const ClassInfo& cls, const Node* params, const SourceLocation& owner_at,
                       std::string_view owner, bool fill_defaults = true);
  /// Whether `key` was written beside `params:` (and so reported already, not missing).
  bool misplaced(const std::string& key) const;

  // --- layers (layers.cpp) ---------------------------------------------------------------------

  void read_layer(const Node& node);
  /// "layer 'control'", or where a layer without a (usable) name was declared.
  static std::string layer_label(const LayerDecl& layer);
  void read_actuators(const Node& node, LayerDecl& layer);
  void check_layers();
  void read_sensors(const Node& node, LayerDecl& layer, PendingLayer& pending);
  std::vector<std::string> actuator_names() const;
  std::vector<PortBinding> bind_ports(const ClassInfo& cls, const Node* ports,
                                      const LayerDecl& layer, const std::string& owner,
                                      const SourceLocation& owner_at);
  /// Whether `target` is what a misspelt sensor of the layer meant; if so, the port reading it
  /// becomes a note of that sensor's error.
  bool fold_into_misspelt_sensor(const std::string& target, const LayerDecl& layer,
                                 const std::string& owner, const std::string& port);
  /// Whether `name` was written in the layer's sensors (input) or actuators (output) but
  /// rejected there, with an error already reported.
  bool declared_but_invalid(const std::string& name, bool input, const LayerDecl& layer) const;
  /// A param or port written beside `params:` or `ports:` instead of under it.
  void note_misplaced_keys(const ClassInfo& cls,
                           const std::vector<std::pair<std::string, std::size_t>>& keys);
  void read_behaviours(const Node& node, LayerDecl& layer, PendingLayer& pending);

  // --- inhibitions (inhibitions.cpp) -----------------------------------------------------------

  void read_inhibitions(const Node& node, LayerDecl& layer, const PendingLayer& pending);
  bool parse_inhibition(const Node& item, InhibitionDecl& inhibition);
  void add_inhibition(InhibitionDecl inhibition, LayerDecl& layer, const PendingLayer& pending,
                      InhibitionIndex& index);

  // --- state machines (state_machines.cpp) -----------------------------------------------------

  void read_state_machines(const Node& node);
  /// `state` or `{state: {param: value}}`, naming a state of `machine`.
  std::optional<QueueEntry> read_queue_entry(const Node& item, const StateMachineDecl& machine,
                                             std::string_view what);
  /// Child controllers: each named machine exists, is owned once, and ownership has no cycle.
  void check_machine_ownership();
  void check_state_machine(StateMachineDecl& machine);

  const Registry& registry_;
  Diagnostics& diagnostics_;
  SourceFiles& files_;  // the included files, alive while pending
  Model model_;
  std::vector<PendingLayer> pending_layers_;
  std::vector<const Node*> pending_machines_;
  std::map<std::string, ActuatorInfo> actuator_index_;
  /// The one type-mismatch error of each actuator some port disagrees with, by actuator name
  /// (an index into the diagnostics): every port that disagrees is a note of it.
  std::map<std::string, std::size_t> type_mismatches_;
  // The keys written beside a behaviour's `params:` while its params are read.
  const std::vector<std::pair<std::string, std::size_t>>* misplaced_ = nullptr;
  std::vector<std::string> include_stack_;  // canonical paths of the files being read
  std::vector<std::string> include_names_;  // the same files as diagnostics name them
  std::vector<std::string> include_chain_;
  std::set<std::string> included_;
};

}  // namespace arbiter::detail
