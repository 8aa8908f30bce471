#include <fmt/format.h>

#include <algorithm>
#include <cassert>
#include <unordered_map>

#include "arbiter/init_context.hpp"
#include "arbiter/program.hpp"
#include "core/compile/controller_builder.hpp"
#include "core/compile/layer_order.hpp"

namespace arbiter {

namespace {

using detail::LayerClosure;
using detail::LayerGraph;
using detail::order_behaviours;
using detail::PositionEdge;

/// Who steps each controller, filled as behaviours and states claim them.
struct Claim {
  bool claimed = false;
  std::uint32_t layer = kNoIndex;      ///< the layer whose sensors the states read
  std::uint32_t owner = kNoBehaviour;  ///< the behaviour whose outputs the states write through
};

/// Lookups shared by every instance's init, so that binding stays linear in the config's size.
struct Bindings {
  std::unordered_map<std::string, std::uint32_t> actuator;  ///< name → actuator index
  std::unordered_map<std::uint64_t, std::uint32_t> slot;    ///< (actuator, owner) → writer slot
};

/// What an instance being initialised belongs to, beyond its layer.
struct InitScope {
  Bindings* bindings = nullptr;
  std::vector<Claim>* claims = nullptr;
  Controller* controller = nullptr;            ///< for states: their controller
  const StateMachineDecl* machine = nullptr;   ///< ... and its declaration
  const std::vector<Name>* sensors = nullptr;  ///< the layer's sensors as declared, if it has one
};

/// What every class's init() may do; the behaviour's and the state's contexts below add theirs.
template <typename Base>
class InstanceInit : public Base {
 public:
  InstanceInit(Program& program, const Registry& registry, Diagnostics& diagnostics,
               const CompiledLayer& layer, std::uint32_t owner, const std::string& name,
               const SourceLocation& location, const ClassInfo& cls, const ParamSet& params,
               const std::vector<PortBinding>& ports, InitScope scope = {})
      : program_(program),
        registry_(registry),
        diagnostics_(diagnostics),
        layer_(layer),
        owner_(owner),
        name_(name),
        location_(location),
        cls_(cls),
        params_(params),
        ports_(ports),
        scope_(scope) {}

  const std::string& name() const override { return name_; }
  const SourceLocation& location() const override { return location_; }
  double rate_hz() const override { return program_.rate_hz; }

  SourceLocation param_location(std::string_view param_name) const {
    const Param* param = params_.find(param_name);
    return param != nullptr ? param->location : location_;
  }

  /// Gives the members that the class binds its params and ports to their values and handles,
  /// before its init(): `instance` points to the Behaviour, Interface or State.
  void bind_members(void* instance) {
    for (std::size_t p = 0; p < cls_.params.size(); ++p) {
      const ParamSpec& spec = cls_.params[p];
      if (!spec.bind) continue;
      const Param* param = params_.find(spec.name);
      if (cls_.kind == ClassKind::kState && spec.per_instance && !spec.member_is_handle) {
        // Its value varies per planned instance: one value in a member would be wrong for most.
        error_at(location_, "class-error",
                 fmt::format("class {} binds param '{}' to a plain member, but the param may be "
                             "set per planned instance: bind a StateParam, or declare it "
                             "state_level()",
                             cls_.name, spec.name));
      } else if (cls_.kind == ClassKind::kState && spec.member_is_handle) {
        // A handle: each planned instance's value is read through it in a step.
        spec.bind(instance, ParamValue{}, static_cast<std::uint32_t>(p));
      } else if (param != nullptr) {
        spec.bind(instance, param->value, static_cast<std::uint32_t>(p));
      }
    }
    for (const auto& port : cls_.ports) {
      if (port.bind) port.bind(instance, port_handle(port));
    }
  }

  AnyOutput output_to_actuator(const std::string& actuator, const SourceLocation& at) override {
    std::vector<std::string> own;
    for (std::uint32_t a = layer_.actuator_begin; a < layer_.actuator_end; ++a) {
      if (program_.actuators[a].name == actuator) return {slot_for(a), program_.actuators[a].type};
      own.push_back(program_.actuators[a].name);
    }
    auto& diagnostic =
        error_at(at, "unknown-actuator",
                 fmt::format("'{}' is not an actuator of layer '{}'", actuator, layer_.name));
    if (const auto other = program_.find_actuator(actuator)) {
      diagnostic.notes.push_back(
          fmt::format("'{}' is an actuator of layer '{}'; a behaviour writes only to actuators "
                      "of its own layer",
                      actuator, program_.layers[program_.actuators[*other].layer].name));
      return {};
    }
    diagnostic.unknown_name(actuator, own, "the layer declares no actuators");
    return {};
  }

  std::vector<LayerItem> layer_actuators() const override {
    std::vector<LayerItem> items;
    for (std::uint32_t a = layer_.actuator_begin; a < layer_.actuator_end; ++a) {
      const CompiledActuator& actuator = program_.actuators[a];
      items.push_back({actuator.name, actuator.type, actuator.location});
    }
    return items;
  }

  std::vector<LayerItem> layer_sensors() const override {
    std::vector<LayerItem> items;
    for (std::size_t s = 0; s < layer_.sensors.size(); ++s) {
      const CompiledActuator& actuator = program_.actuators[layer_.sensors[s]];
      const bool named = scope_.sensors != nullptr && s < scope_.sensors->size();
      items.push_back(
          {actuator.name, actuator.type, named ? (*scope_.sensors)[s].location : location_});
    }
    return items;
  }

  ValueBox make_value(const ValueType& type, const Node& node) override {
    ValueBox box(type);
    std::string expected;
    if (!type.from_node(node, box.data(), expected)) {
      error_at(node.location(), "wrong-type",
               fmt::format("{} '{}' ({}) needs {} ({}) here, found {}", to_string(cls_.kind), name_,
                           cls_.name, expected, type.name, node.describe()));
      return {};
    }
    return box;
  }

  Diagnostic& error(const SourceLocation& at, std::string message) override {
    return error_at(at, "class-error", std::move(message));
  }
  Diagnostic& warning(const SourceLocation& at, std::string message) override {
    return diagnostics_.warning(at, "class-warning", std::move(message));
  }
  Diagnostics& diagnostics() override { return diagnostics_; }

 protected:
  /// The handle of a port the class declares: where its binding points, kUnbound if nowhere.
  std::uint32_t port_handle(const PortSpec& port) {
    for (const auto& binding : ports_) {
      if (binding.port->name != port.name) continue;
      if (binding.target.empty()) return kUnbound;
      const auto actuator = scope_.bindings->actuator.find(binding.target);
      if (actuator == scope_.bindings->actuator.end()) return kUnbound;
      return port.direction == PortDirection::kInput ? actuator->second
                                                     : slot_for(actuator->second);
    }
    return kUnbound;
  }

  SourceLocation bound_param_location(const MemberKey& member) const override {
    for (const auto& spec : cls_.params) {
      if (spec.member == member) return param_location(spec.name);
    }
    diagnostics_.error(location_, "class-error",
                       fmt::format("class {} asks where the param bound to a member was written, "
                                   "but binds no param to that member",
                                   cls_.name));
    return location_;
  }

  std::uint32_t resolve_sensor(const std::string& sensor, const std::type_info& type,
                               const SourceLocation& at) override {
    std::vector<std::string> own;
    for (const auto a : layer_.sensors) {
      const CompiledActuator& actuator = program_.actuators[a];
      if (actuator.name != sensor) {
        own.push_back(actuator.name);
        continue;
      }
      if (actuator.type->cpp_type != nullptr && *actuator.type->cpp_type == type) return a;
      error_at(at, "class-error",
               fmt::format("class {} reads sensor '{}' ({}) as a different C++ type", cls_.name,
                           sensor, actuator.type->name));
      return kUnbound;
    }
    error_at(at, "unknown-actuator",
             fmt::format("'{}' is not a sensor of layer '{}'", sensor, layer_.name))
        .unknown_name(sensor, own, "the layer reads no sensors");
    return kUnbound;
  }

 protected:
  Diagnostic& error_at(const SourceLocation& at, std::string code, std::string message) {
    return diagnostics_.error(at, std::move(code), std::move(message));
  }

  std::uint32_t slot_for(std::uint32_t actuator) {
    const std::uint64_t key = (std::uint64_t{actuator} << 32) | owner_;
    const auto [found, fresh] =
        scope_.bindings->slot.emplace(key, static_cast<std::uint32_t>(program_.slots.size()));
    if (fresh) program_.slots.push_back({actuator, owner_, 0});
    return found->second;
  }

  Program& program_;
  const Registry& registry_;
  Diagnostics& diagnostics_;
  const CompiledLayer& layer_;
  std::uint32_t owner_;
  const std::string& name_;
  const SourceLocation& location_;
  const ClassInfo& cls_;
  const ParamSet& params_;
  const std::vector<PortBinding>& ports_;
  InitScope scope_;
};

class BehaviourInit final : public InstanceInit<BehaviourInitContext> {
 public:
  using InstanceInit::InstanceInit;

  Controller* claim_controller(const std::string& machine, const SourceLocation& at) override {
    std::vector<std::string> known;
    for (std::uint32_t c = 0; c < program_.controllers.size(); ++c) {
      Controller& controller = *program_.controllers[c];
      known.push_back(controller.name());
      if (controller.name() != machine) continue;
      Claim& claim = (*scope_.claims)[c];
      if (claim.claimed) {
        error_at(at, "machine-owned-twice",
                 fmt::format("state machine '{}' already has an owner; a controller is stepped "
                             "by one owner only",
                             machine));
        return nullptr;
      }
      const bool in_program = !program_.layers.empty() && &layer_ >= &program_.layers.front() &&
                              &layer_ <= &program_.layers.back();
      claim = {true,
               in_program ? static_cast<std::uint32_t>(&layer_ - program_.layers.data()) : kNoIndex,
               owner_};
      ControllerBuilder(controller).set_owned(owner_);
      return &controller;
    }
    error_at(at, "unknown-machine", fmt::format("no state machine named '{}'", machine))
        .unknown_name(machine, known, "the config declares no state_machines");
    return nullptr;
  }
};

class StateInit final : public InstanceInit<StateInitContext> {
 public:
  using InstanceInit::InstanceInit;

  bool plan_state(const std::string& state, const Node* params, const SourceLocation& at,
                  PlannedState& out) override {
    const std::uint32_t s = find_declared(state, at);
    if (s == kNoState) return false;
    const StateDecl& decl = scope_.machine->states[s];
    const std::size_t errors = diagnostics_.error_count();
    out.params = check_state_params(decl, params, at, registry_, diagnostics_);
    out.state = s;
    index_params(*decl.cls, out);
    return diagnostics_.error_count() == errors;
  }

 protected:
  const ParamValue* state_param(std::uint32_t index) const override {
    if (index >= cls_.params.size()) return nullptr;
    const Param* param = params_.find(cls_.params[index].name);
    return param != nullptr ? &param->value : nullptr;
  }

  std::uint32_t resolve_state(const std::string& state, const std::string_view* params,
                              const ParamKind* kinds, std::size_t count, std::uint32_t* indices,
                              const SourceLocation& at) override {
    const std::uint32_t s = find_declared(state, at);
    if (s == kNoState) return kNoState;
    const StateDecl& decl = scope_.machine->states[s];
    const ClassInfo& cls = *decl.cls;
    const std::size_t errors = diagnostics_.error_count();
    std::vector<std::string> known;
    for (const auto& declared : cls.params) known.push_back(declared.name);
    for (std::size_t i = 0; i < count; ++i) {
      const ParamSpec* spec = cls.find_param(params[i]);
      if (spec == nullptr) {
        error_at(at, "class-error",
                 fmt::format("class {} plans state '{}' ({}) with param '{}', which its class "
                             "does not declare",
                             cls_.name, state, cls.name, params[i]))
            .unknown_name(params[i], known);
        continue;
      }
      indices[i] = static_cast<std::uint32_t>(spec - cls.params.data());
      if (spec->kind != kinds[i]) {
        error_at(
            at, "class-error",
            fmt::format("class {} plans param '{}' ({}) of state '{}' in a slot of kind {}",
                        cls_.name, params[i], to_string(spec->kind), state, to_string(kinds[i])));
      }
      for (std::size_t j = 0; j < i; ++j) {
        if (params[j] == params[i]) {
          error_at(at, "class-error",
                   fmt::format("class {} plans param '{}' of state '{}' twice", cls_.name,
                               params[i], state));
        }
      }
    }
    for (std::size_t p = 0; p < cls.params.size(); ++p) {
      const ParamSpec& spec = cls.params[p];
      if (!spec.required() || decl.params.find(spec.name) != nullptr) continue;
      bool slotted = false;
      for (std::size_t i = 0; i < count; ++i) slotted = slotted || params[i] == spec.name;
      if (!slotted) {
        error_at(at, "class-error",
                 fmt::format("class {} plans state '{}' without its required param '{}'; give "
                             "it a slot or set it on the state",
                             cls_.name, state, spec.name));
      }
    }
    return diagnostics_.error_count() == errors ? s : kNoState;
  }

 private:
  // A state of this state's machine, reported at `at` when there is none.
  std::uint32_t find_declared(const std::string& state, const SourceLocation& at) {
    std::vector<std::string> known;
    for (std::uint32_t s = 0; s < scope_.machine->states.size(); ++s) {
      const StateDecl& decl = scope_.machine->states[s];
      if (decl.name.text == state) return s;
      known.push_back(decl.name.text);
    }
    error_at(at, "unknown-state",
             fmt::format("state machine '{}' has no state '{}'", scope_.machine->name.text, state))
        .unknown_name(state, known);
    return kNoState;
  }
};

class Compiler {
 public:
  Compiler(const Model& model, const Registry& registry, Diagnostics& diagnostics)
      : model_(model), registry_(registry), diagnostics_(diagnostics) {}

  std::optional<Program> run() {
    program_.libraries = registry_.libraries();
    program_.name = model_.name;
    program_.rate_hz = model_.rate_hz;
    program_.steps = model_.steps;
    program_.on_exception = model_.on_exception;
    std::size_t behaviours = 0;
    std::size_t inhibitions = 0;
    for (const auto& layer : model_.layers) {
      behaviours += layer.behaviours.size();
      inhibitions += layer.inhibitions.size();
    }
    program_.behaviours.reserve(behaviours);
    sources_.reserve(behaviours);
    declared_.reserve(inhibitions);
    recipes_.begin.reserve(behaviours + 1);
    recipes_.split.reserve(behaviours);
    recipes_.terms.reserve(inhibitions);
    recipes_.begin.push_back(0);
    declare_actuators();
    for (const auto& layer : model_.layers) order_layer(layer);
    if (diagnostics_.has_errors()) return std::nullopt;
    // Recipe terms index two factors per behaviour in 32 bits.
    assert(program_.behaviours.size() < (std::size_t{1} << 31));
    program_.inhibitions = Inhibitions(std::move(files_), std::move(declared_), std::move(recipes_),
                                       program_.behaviours);
    declare_controllers();
    for (std::size_t l = 0; l < model_.layers.size(); ++l) instantiate(model_.layers[l], l);
    if (diagnostics_.has_errors()) return std::nullopt;
    build_controllers();
    if (diagnostics_.has_errors()) return std::nullopt;
    lay_out_values();
    return std::move(program_);
  }

 private:
  void declare_actuators() {
    for (const auto& layer : model_.layers) {
      CompiledLayer compiled;
      compiled.name = layer.name.text;
      compiled.location = layer.name.location;
      compiled.normalise = layer.normalise.value_or(model_.normalise);
      compiled.interface_class = layer.interface;
      compiled.actuator_begin = static_cast<std::uint32_t>(program_.actuators.size());
      for (const auto& actuator : layer.actuators) {
        CompiledActuator out;
        out.name = actuator.name.text;
        out.type = actuator.type;
        out.aggregate = actuator.aggregate;
        out.layer = static_cast<std::uint32_t>(program_.layers.size());
        out.default_value = actuator.default_value;
        out.safe_value = actuator.safe_value;
        out.location = actuator.name.location;
        bindings_.actuator.emplace(out.name, static_cast<std::uint32_t>(program_.actuators.size()));
        program_.actuators.push_back(std::move(out));
      }
      compiled.actuator_end = static_cast<std::uint32_t>(program_.actuators.size());
      program_.layers.push_back(std::move(compiled));
    }
    for (std::size_t l = 0; l < model_.layers.size(); ++l) {
      for (const auto& sensor : model_.layers[l].sensors) {
        program_.layers[l].sensors.push_back(bindings_.actuator.at(sensor.text));
      }
    }
  }

  // Topological order, closure and the layer's inhibitions, or a cycle error.
  void order_layer(const LayerDecl& layer) {
    const std::size_t n = layer.behaviours.size();
    const auto base = static_cast<std::uint32_t>(program_.behaviours.size());
    CompiledLayer& compiled = program_.layers[&layer - model_.layers.data()];
    compiled.behaviour_begin = base;

    const LayerGraph graph = order_behaviours(layer, diagnostics_);
    if (graph.order.size() != n) {
      compiled.behaviour_end = base;
      return;
    }
    const auto& edges = graph.edges;
    const auto& order = graph.order;
    std::vector<std::uint32_t> position(n, 0);
    for (std::uint32_t p = 0; p < n; ++p) position[order[p]] = p;

    for (std::uint32_t p = 0; p < n; ++p) {
      const BehaviourDecl& decl = layer.behaviours[order[p]];
      sources_.push_back(&decl);
      CompiledBehaviour behaviour;
      behaviour.name = decl.name.text;
      behaviour.cls = decl.cls;
      behaviour.location = decl.location;
      behaviour.on_exception = decl.on_exception.value_or(model_.on_exception);
      behaviour.layer = static_cast<std::uint32_t>(&compiled - program_.layers.data());
      program_.behaviours.push_back(std::move(behaviour));
    }
    compiled.behaviour_end = static_cast<std::uint32_t>(program_.behaviours.size());

    std::vector<PositionEdge> by_position;
    by_position.reserve(edges.size());
    for (const auto& edge : edges) {
      by_position.push_back(
          {position[edge.from], position[edge.to], edge.chaining, &edge.location});
    }
    LayerClosure closure(n, std::move(by_position));
    closure.append_recipes(base, recipes_);
    for (const auto& edge : closure.edges()) {
      const SourceLocation& at = *edge.location;
      const auto file = file_index_.emplace(at.file, static_cast<std::uint32_t>(files_.size()));
      if (file.second) files_.push_back(at.file);
      declared_.push_back({base + edge.from, base + edge.to, file.first->second, at.line, at.column,
                           edge.chaining});
    }
  }

  void instantiate(const LayerDecl& decl, std::size_t l) {
    CompiledLayer& layer = program_.layers[l];
    if (decl.interface != nullptr) {
      layer.interface = decl.interface->make_interface();
      InstanceInit<InitContext> init(
          program_, registry_, diagnostics_, layer, kNoBehaviour, layer.name, layer.location,
          *decl.interface, decl.params, decl.ports,
          InitScope{&bindings_, &claims_, nullptr, nullptr, &decl.sensors});
      guarded_init(diagnostics_, *decl.interface, layer.location, [&] {
        init.bind_members(layer.interface.get());
        layer.interface->init(init);
      });
      return;
    }
    // Initialised in declaration order, not execution order: the writer slots their outputs get
    // then do not move when an edit only reorders the layer (a flipped inhibition), so a hot
    // reload keeps those behaviours' instances (their handles are unchanged).
    std::vector<std::uint32_t> by_declaration;
    for (std::uint32_t b = layer.behaviour_begin; b < layer.behaviour_end; ++b) {
      by_declaration.push_back(b);
    }
    std::sort(by_declaration.begin(), by_declaration.end(), [&](std::uint32_t a, std::uint32_t b) {
      return std::less<const BehaviourDecl*>()(sources_[a], sources_[b]);
    });
    for (const std::uint32_t b : by_declaration) {
      CompiledBehaviour& behaviour = program_.behaviours[b];
      const BehaviourDecl* source = sources_[b];
      behaviour.instance = behaviour.cls->make_behaviour();
      BehaviourInit init(program_, registry_, diagnostics_, layer, b, behaviour.name,
                         behaviour.location, *behaviour.cls, source->params, source->ports,
                         InitScope{&bindings_, &claims_, nullptr, nullptr, &decl.sensors});
      guarded_init(diagnostics_, *behaviour.cls, behaviour.location, [&] {
        init.bind_members(behaviour.instance.get());
        behaviour.instance->init(init);
      });
    }
  }

  template <typename F>
  void guarded_init(Diagnostics& into, const ClassInfo& cls, const SourceLocation& at, F&& init) {
    try {
      init();
    } catch (const std::exception& error) {
      into.error(at, "init-failed",
                 fmt::format("class {} failed to initialise: {}", cls.name, error.what()));
    } catch (...) {
      into.error(at, "init-failed",
                 fmt::format("class {} failed to initialise (unknown exception)", cls.name));
    }
  }

  void declare_controllers() {
    for (const auto& machine : model_.state_machines) {
      auto controller =
          std::make_unique<Controller>(machine.name.text, machine.location, machine.capacity);
      for (const auto& state : machine.states) {
        CompiledState compiled;
        compiled.name = state.name.text;
        compiled.cls = state.cls;
        compiled.location = state.location;
        compiled.params = state.params.items;
        ControllerBuilder(*controller).add_state(std::move(compiled));
      }
      program_.controllers.push_back(std::move(controller));
    }
    claims_.assign(program_.controllers.size(), Claim{});
  }

  // Children inherit their parent's layer and owner; then every pooled state is initialised
  // against that layer.
  void build_controllers() {
    const auto index_of = [&](const std::string& name) {
      for (std::uint32_t c = 0; c < model_.state_machines.size(); ++c) {
        if (model_.state_machines[c].name.text == name) return c;
      }
      return kNoController;
    };
    std::vector<std::uint32_t> parent(program_.controllers.size(), kNoController);
    for (std::uint32_t c = 0; c < model_.state_machines.size(); ++c) {
      Controller& controller = *program_.controllers[c];
      std::vector<Controller*> children;
      const auto& decl = model_.state_machines[c];
      for (std::uint32_t s = 0; s < decl.states.size(); ++s) {
        if (!decl.states[s].machine) continue;
        const auto child = index_of(decl.states[s].machine->text);
        if (child == kNoController) continue;
        if (claims_[child].claimed) {
          diagnostics_.error(decl.states[s].machine->location, "machine-owned-twice",
                             fmt::format("state machine '{}' is stepped by a behaviour and "
                                         "cannot also be the child of state '{}'",
                                         decl.states[s].machine->text, decl.states[s].name.text));
          continue;
        }
        ControllerBuilder(*program_.controllers[child]).set_owned();
        parent[child] = c;
        ControllerBuilder(controller)
            .set_state_child(s, static_cast<std::uint32_t>(children.size()));
        children.push_back(program_.controllers[child].get());
      }
      ControllerBuilder(controller).set_children(std::move(children));
    }
    for (std::uint32_t c = 0; c < program_.controllers.size(); ++c) {
      auto root = c;
      while (parent[root] != kNoController && !claims_[root].claimed) root = parent[root];
      if (root != c) claims_[c] = {true, claims_[root].layer, claims_[root].owner};
    }
    static const CompiledLayer kNoLayer;
    for (std::uint32_t c = 0; c < program_.controllers.size(); ++c) {
      Controller& controller = *program_.controllers[c];
      const StateMachineDecl& decl = model_.state_machines[c];
      const Claim& claim = claims_[c];
      const CompiledLayer& layer =
          claim.layer == kNoIndex ? kNoLayer : program_.layers[claim.layer];
      const std::vector<Name>* sensors =
          claim.layer == kNoIndex ? nullptr : &model_.layers[claim.layer].sensors;
      std::vector<ParamSet> params(decl.states.size());
      std::vector<std::vector<PortBinding>> ports(decl.states.size());
      for (std::uint32_t s = 0; s < decl.states.size(); ++s) {
        params[s] = with_defaults(decl.states[s]);
        ports[s] = bind_state_ports(decl.states[s], layer);
      }
      std::vector<PlannedState> initial;
      for (const auto& entry : decl.queue) {
        const auto s = find_state(controller, entry.state.text);
        if (s) initial.push_back({*s, entry.overrides, {}});
      }
      ControllerBuilder(controller).set_initial_queue(std::move(initial));
      for (const auto& preemption : decl.preempt) {
        const auto s = find_state(controller, preemption.go_to.state.text);
        if (s) {
          ControllerBuilder(controller)
              .add_preemption(preemption.cycle, {*s, preemption.go_to.overrides, {}});
        }
      }
      std::vector<bool> reported(decl.states.size(), false);
      ControllerBuilder(controller).build_pool([&](std::uint32_t s, State& state) {
        // Every pooled object is initialised alike; report problems once, for the first.
        Diagnostics repeat;
        StateInit init(program_, registry_, reported[s] ? repeat : diagnostics_, layer, claim.owner,
                       decl.states[s].name.text, decl.states[s].location, *decl.states[s].cls,
                       params[s], ports[s],
                       InitScope{&bindings_, &claims_, &controller, &decl, sensors});
        guarded_init(reported[s] ? repeat : diagnostics_, *decl.states[s].cls,
                     decl.states[s].location, [&] {
                       init.bind_members(&state);
                       state.init(init);
                     });
        reported[s] = true;
      });
    }
  }

  static ParamSet with_defaults(const StateDecl& state) {
    ParamSet set;
    for (const auto& spec : state.cls->params) {
      if (const Param* given = state.params.find(spec.name)) {
        set.items.push_back(*given);
      } else if (spec.default_value) {
        set.items.push_back({spec.name, *spec.default_value, state.location, true});
      }
    }
    return set;
  }

  // A state's ports bind by name to its owner's layer: sensors for inputs, actuators for outputs.
  std::vector<PortBinding> bind_state_ports(const StateDecl& state, const CompiledLayer& layer) {
    std::vector<PortBinding> bindings;
    for (const auto& spec : state.cls->ports) {
      PortBinding binding{&spec, {}, state.location};
      std::optional<std::uint32_t> actuator;
      if (spec.direction == PortDirection::kInput) {
        for (auto sensor : layer.sensors) {
          if (program_.actuators[sensor].name == spec.name) actuator = sensor;
        }
      } else {
        for (auto a = layer.actuator_begin; a < layer.actuator_end; ++a) {
          if (program_.actuators[a].name == spec.name) actuator = a;
        }
      }
      if (!actuator) {
        if (!spec.optional) {
          diagnostics_.error(
              state.location, "unbound-port",
              fmt::format(
                  "{} port '{}' of state '{}' ({}) needs {} named '{}'{}",
                  spec.direction == PortDirection::kInput ? "input" : "output", spec.name,
                  state.name.text, state.cls->name,
                  spec.direction == PortDirection::kInput ? "a sensor" : "an actuator", spec.name,
                  layer.name.empty() ? " but its controller is standalone (no owning behaviour)"
                                     : fmt::format(" in layer '{}'", layer.name)));
        }
        bindings.push_back(binding);
        continue;
      }
      const ValueType* type = program_.actuators[*actuator].type;
      if (registry_.value_type_of(*spec.cpp_type) != type) {
        diagnostics_.error(
            state.location, "type-mismatch",
            fmt::format("port '{}' of state '{}' has type '{}' but '{}' is '{}'", spec.name,
                        state.name.text, registry_.value_type_name(*spec.cpp_type), spec.name,
                        type->name));
        bindings.push_back(binding);
        continue;
      }
      binding.target = spec.name;
      bindings.push_back(binding);
    }
    return bindings;
  }

  void lay_out_values() {
    std::size_t bytes = 0;
    auto place = [&](const ValueType& type) {
      bytes = (bytes + type.alignment - 1) / type.alignment * type.alignment;
      const auto offset = static_cast<std::uint32_t>(bytes);
      bytes += type.size;
      return offset;
    };
    for (auto& actuator : program_.actuators) {
      actuator.offset = place(*actuator.type);
      program_.actuator_offsets.push_back(actuator.offset);
    }
    std::vector<std::vector<std::uint32_t>> writers(program_.actuators.size());
    for (std::uint32_t s = 0; s < program_.slots.size(); ++s) {
      auto& slot = program_.slots[s];
      const ValueType* type = program_.actuators[slot.actuator].type;
      slot.offset = place(*type);
      program_.slot_offsets.push_back(slot.offset);
      program_.slot_types.push_back(type);
      writers[slot.actuator].push_back(s);
    }
    for (auto& list : writers) {
      // Ties between writers go to the earlier in execution order, whoever created the slot.
      std::stable_sort(list.begin(), list.end(), [&](std::uint32_t a, std::uint32_t b) {
        return program_.slots[a].owner < program_.slots[b].owner;
      });
      program_.actuator_slot_begin.push_back(
          static_cast<std::uint32_t>(program_.actuator_slots.size()));
      program_.actuator_slots.insert(program_.actuator_slots.end(), list.begin(), list.end());
      program_.max_writers = std::max(program_.max_writers, list.size());
    }
    program_.actuator_slot_begin.push_back(
        static_cast<std::uint32_t>(program_.actuator_slots.size()));
    program_.value_bytes = bytes;
  }

  const Model& model_;
  const Registry& registry_;
  Diagnostics& diagnostics_;
  Program program_;
  std::vector<Claim> claims_;
  Bindings bindings_;
  std::vector<const BehaviourDecl*> sources_;  // each compiled behaviour's declaration
  // The inhibitions, gathered layer by layer.
  std::vector<std::string> files_;
  std::unordered_map<std::string, std::uint32_t> file_index_;
  std::vector<Inhibitions::Declared> declared_;
  Inhibitions::Recipes recipes_;
};

}  // namespace

std::optional<Program> compile(const Model& model, const Registry& registry,
                               Diagnostics& diagnostics) {
  return Compiler(model, registry, diagnostics).run();
}

}  // namespace arbiter
