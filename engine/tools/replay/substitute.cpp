#include "arbiter/substitute.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "arbiter/program.hpp"

namespace arbiter {
namespace {

// One thing of the model a target can name.
struct Candidate {
  enum class Kind { kBehaviour, kState, kInterfaceLayer, kLayer, kClass };
  Kind kind;
  std::string qualified;  // `layer/name`, `machine/state`, a layer or a class name
  std::string short_name;
  std::size_t outer = 0;  // layer or machine index
  std::size_t inner = 0;  // behaviour or state index
  const ClassInfo* cls = nullptr;
};

std::string describe(const Candidate& candidate) {
  switch (candidate.kind) {
    case Candidate::Kind::kBehaviour:
      return fmt::format("behaviour '{}'", candidate.qualified);
    case Candidate::Kind::kState:
      return fmt::format("state '{}'", candidate.qualified);
    case Candidate::Kind::kInterfaceLayer:
      return fmt::format("interface layer '{}'", candidate.qualified);
    case Candidate::Kind::kLayer:
      return fmt::format("layer '{}'", candidate.qualified);
    case Candidate::Kind::kClass:
      return fmt::format("class '{}'", candidate.qualified);
  }
  return candidate.qualified;
}

std::vector<Candidate> candidates_of(const Model& model) {
  std::vector<Candidate> out;
  std::vector<const ClassInfo*> classes;
  const auto add_class = [&](const ClassInfo* cls) {
    if (cls != nullptr && std::find(classes.begin(), classes.end(), cls) == classes.end()) {
      classes.push_back(cls);
    }
  };
  for (std::size_t l = 0; l < model.layers.size(); ++l) {
    const LayerDecl& layer = model.layers[l];
    const auto kind =
        layer.is_interface() ? Candidate::Kind::kInterfaceLayer : Candidate::Kind::kLayer;
    out.push_back({kind, layer.name.text, layer.name.text, l, 0, layer.interface});
    add_class(layer.interface);
    for (std::size_t b = 0; b < layer.behaviours.size(); ++b) {
      const BehaviourDecl& behaviour = layer.behaviours[b];
      out.push_back({Candidate::Kind::kBehaviour,
                     fmt::format("{}/{}", layer.name.text, behaviour.name.text),
                     behaviour.name.text, l, b, behaviour.cls});
      add_class(behaviour.cls);
    }
  }
  for (std::size_t m = 0; m < model.state_machines.size(); ++m) {
    const StateMachineDecl& machine = model.state_machines[m];
    for (std::size_t s = 0; s < machine.states.size(); ++s) {
      const StateDecl& state = machine.states[s];
      out.push_back({Candidate::Kind::kState,
                     fmt::format("{}/{}", machine.name.text, state.name.text), state.name.text, m,
                     s, state.cls});
      add_class(state.cls);
    }
  }
  for (const ClassInfo* cls : classes) {
    out.push_back({Candidate::Kind::kClass, cls->name, cls->name, 0, 0, cls});
  }
  return out;
}

class Substituter {
 public:
  Substituter(Model& model, const Registry& registry, Diagnostics& diagnostics)
      : model_(model), original_(model), registry_(registry), diagnostics_(diagnostics) {}

  void apply(const Substitution& substitution) {
    const auto matches = resolve(substitution);
    if (matches.empty()) return;
    const Candidate& target = matches.front();
    switch (target.kind) {
      case Candidate::Kind::kBehaviour:
        replace_behaviour(substitution, target.outer, target.inner);
        return;
      case Candidate::Kind::kState:
        replace_state(substitution, target.outer, target.inner);
        return;
      case Candidate::Kind::kInterfaceLayer:
        replace_interface(substitution, target.outer);
        return;
      case Candidate::Kind::kLayer:
        diagnostics_
            .error(substitution.location, "substitute-target",
                   fmt::format("layer '{}' is not an interface layer; substitute its behaviours "
                               "one by one ('{}/NAME') or by class",
                               target.qualified, target.qualified))
            .notes.push_back(behaviours_of(target.outer));
        return;
      case Candidate::Kind::kClass:
        replace_class(substitution, *target.cls);
        return;
    }
  }

 private:
  // The one candidate a target names; reports none or several (then returns none).
  std::vector<Candidate> resolve(const Substitution& substitution) {
    const auto candidates = candidates_of(original_);
    std::vector<Candidate> exact;
    std::vector<Candidate> by_short_name;
    for (const auto& candidate : candidates) {
      if (candidate.qualified == substitution.target) exact.push_back(candidate);
      if (candidate.short_name == substitution.target) by_short_name.push_back(candidate);
    }
    const auto& matches = exact.empty() ? by_short_name : exact;
    if (matches.size() == 1) return matches;
    if (matches.empty()) {
      // Each thing once, by the name that is enough to name it.
      std::vector<std::string> known;
      for (const auto& candidate : candidates) {
        const bool shared =
            std::count_if(candidates.begin(), candidates.end(), [&](const Candidate& other) {
              return other.short_name == candidate.short_name;
            }) > 1;
        known.push_back(shared ? candidate.qualified : candidate.short_name);
      }
      diagnostics_
          .error(substitution.location, "substitute-target",
                 fmt::format("'{}' names no behaviour, state, interface layer or class of "
                             "config '{}'",
                             substitution.target, model_.name))
          .unknown_name(substitution.target, known);
      return {};
    }
    std::vector<std::string> names;
    for (const auto& candidate : matches) names.push_back(describe(candidate));
    auto& error = diagnostics_.error(
        substitution.location, "ambiguous-name",
        fmt::format("'{}' is ambiguous: it names {}", substitution.target, join(names, ", ")));
    std::vector<std::string> qualified;
    for (const auto& candidate : matches) qualified.push_back(candidate.qualified);
    error.notes.push_back(fmt::format("write one of: {}", join(qualified, ", ")));
    return {};
  }

  static std::string join(const std::vector<std::string>& items, const char* separator) {
    std::string out;
    for (const auto& item : items) {
      if (!out.empty()) out += separator;
      out += item;
    }
    return out;
  }

  std::string behaviours_of(std::size_t layer) const {
    std::vector<std::string> names;
    for (const auto& behaviour : original_.layers[layer].behaviours) {
      names.push_back(behaviour.name.text);
    }
    return names.empty() ? "it has no behaviours"
                         : fmt::format("its behaviours: {}", join(names, ", "));
  }

  // The replacement's class, params and ports; nullopt after reporting.
  std::optional<Declaration> declare(const Substitution& substitution, ClassKind kind,
                                     std::optional<std::size_t> layer, const std::string& owner,
                                     const SourceLocation& owner_at) {
    if (substitution.cls != nullptr) {
      if (substitution.cls->kind != kind) {
        diagnostics_.error(substitution.location, "wrong-class-kind",
                           fmt::format("{} cannot be replaced by {} class {}", owner,
                                       to_string(substitution.cls->kind), substitution.cls->name));
        return std::nullopt;
      }
      Declaration declaration;
      declaration.cls = substitution.cls;
      return declaration;
    }
    const Node& node = substitution.declaration;
    const Node* type = &node;
    const Node* params = nullptr;
    const Node* ports = nullptr;
    if (node.is_mapping()) {
      type = node.find("type");
      params = node.find("params");
      ports = node.find("ports");
      for (const auto& entry : node.entries()) {
        if (entry.key == "type" || entry.key == "params" || entry.key == "ports") continue;
        diagnostics_
            .error(entry.key_location, "unknown-key",
                   fmt::format("unknown key '{}' in the replacement of {}", entry.key, owner))
            .unknown_name(entry.key, {"type", "params", "ports"}, {}, "allowed");
      }
      if (type == nullptr) {
        diagnostics_.error(
            node.location(), "missing-key",
            fmt::format("the replacement of {} is missing the required key 'type'", owner));
        return std::nullopt;
      }
    } else if (!node.is_scalar() || node.reads_as_null()) {
      diagnostics_.error(node.location(), "wrong-type",
                         fmt::format("the replacement of {} must be a class name or {{type: "
                                     "CLASS, params: {{...}}}}, found {}",
                                     owner, node.describe()));
      return std::nullopt;
    }
    return redeclare(original_, kind, *type, params, ports, layer, owner, owner_at, registry_,
                     diagnostics_);
  }

  void replace_behaviour(const Substitution& substitution, std::size_t layer, std::size_t index) {
    BehaviourDecl& behaviour = model_.layers[layer].behaviours[index];
    auto declaration =
        declare(substitution, ClassKind::kBehaviour, layer,
                fmt::format("behaviour '{}'", behaviour.name.text), behaviour.location);
    if (!declaration) return;
    behaviour.cls = declaration->cls;
    behaviour.params = std::move(declaration->params);
    behaviour.ports = std::move(declaration->ports);
  }

  void replace_state(const Substitution& substitution, std::size_t machine, std::size_t index) {
    StateMachineDecl& decl = model_.state_machines[machine];
    StateDecl& state = decl.states[index];
    auto declaration = declare(substitution, ClassKind::kState, std::nullopt,
                               fmt::format("state '{}'", state.name.text), state.location);
    if (!declaration) return;
    state.cls = declaration->cls;
    state.params = std::move(declaration->params);
    for (auto& entry : decl.queue) {
      if (entry.state.text == state.name.text) entry.overrides.clear();
    }
    for (auto& preemption : decl.preempt) {
      if (preemption.go_to.state.text == state.name.text) preemption.go_to.overrides.clear();
    }
  }

  void replace_interface(const Substitution& substitution, std::size_t index) {
    LayerDecl& layer = model_.layers[index];
    auto declaration =
        declare(substitution, ClassKind::kInterface, index,
                fmt::format("interface layer '{}'", layer.name.text), layer.name.location);
    if (!declaration) return;
    layer.interface = declaration->cls;
    layer.params = std::move(declaration->params);
    layer.ports = std::move(declaration->ports);
  }

  void replace_class(const Substitution& substitution, const ClassInfo& cls) {
    for (std::size_t l = 0; l < original_.layers.size(); ++l) {
      const LayerDecl& layer = original_.layers[l];
      if (layer.interface == &cls) replace_interface(substitution, l);
      for (std::size_t b = 0; b < layer.behaviours.size(); ++b) {
        if (layer.behaviours[b].cls == &cls) replace_behaviour(substitution, l, b);
      }
    }
    for (std::size_t m = 0; m < original_.state_machines.size(); ++m) {
      const auto& states = original_.state_machines[m].states;
      for (std::size_t s = 0; s < states.size(); ++s) {
        if (states[s].cls == &cls) replace_state(substitution, m, s);
      }
    }
  }

  Model& model_;
  // Targets resolve against the config as written, whatever an earlier substitution replaced.
  const Model original_;
  const Registry& registry_;
  Diagnostics& diagnostics_;
};

}  // namespace

bool substitute(Model& model, const std::vector<Substitution>& substitutions,
                const Registry& registry, Diagnostics& diagnostics) {
  const std::size_t errors = diagnostics.error_count();
  Substituter substituter(model, registry, diagnostics);
  for (const auto& substitution : substitutions) substituter.apply(substitution);
  return diagnostics.error_count() == errors;
}

}  // namespace arbiter
