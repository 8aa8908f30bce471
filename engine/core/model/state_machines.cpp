// State machines: their states (a class each, or a child machine), the initial queue, pre-emptions
// and capacity, the params of each queued state instance, and which machine owns which (once, and
// without a cycle).
#include <algorithm>
#include <map>
#include <set>

#include <fmt/format.h>

#include "arbiter/fields.hpp"
#include "core/model/builder.hpp"

namespace arbiter::detail {

void ModelBuilder::read_state_machines(const Node& node) {
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
            .notes.push_back(
                {fmt::format("first declared at {}", to_string(other.location)), other.location});
      }
    }
    StateMachineDecl machine;
    machine.name = {entry.key, entry.key_location};
    machine.location = entry.key_location;
    pending_machines_.push_back(&entry.value);
    model_.state_machines.push_back(std::move(machine));
  }
}

std::optional<QueueEntry> ModelBuilder::read_queue_entry(const Node& item,
                                                         const StateMachineDecl& machine,
                                                         std::string_view what) {
  QueueEntry entry;
  const Node* overrides = nullptr;
  if (item.is_mapping() && item.entries().size() == 1) {
    entry.state = {item.entries()[0].key, item.entries()[0].key_location};
    overrides = &item.entries()[0].value;
  } else if (item.is_mapping()) {
    diagnostics_.error(item.location(), "wrong-type",
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
    diagnostics_
        .error(entry.state.location, "unknown-state",
               fmt::format("{} of state machine '{}' names unknown state '{}'", what,
                           machine.name.text, entry.state.text))
        .unknown_name(entry.state.text, state_names);
    return std::nullopt;
  }
  entry.overrides = check_instance_params(*state, overrides, entry.state.location);
  return entry;
}

void ModelBuilder::check_machine_ownership() {
  std::map<std::string, const Name*> owner_of;
  std::map<std::string, std::vector<std::string>> children;
  std::vector<std::string> names;
  for (const auto& machine : model_.state_machines) names.push_back(machine.name.text);
  for (const auto& machine : model_.state_machines) {
    for (const auto& state : machine.states) {
      if (!state.machine) continue;
      const Name& child = *state.machine;
      if (std::find(names.begin(), names.end(), child.text) == names.end()) {
        diagnostics_
            .error(child.location, "unknown-machine",
                   fmt::format("state '{}' names unknown state machine '{}'", state.name.text,
                               child.text))
            .unknown_name(child.text, names);
        continue;
      }
      if (auto [it, fresh] = owner_of.emplace(child.text, &child); !fresh) {
        diagnostics_
            .error(child.location, "machine-owned-twice",
                   fmt::format("state machine '{}' already has an owner; a controller is "
                               "stepped by one owner only",
                               child.text))
            .notes.push_back({fmt::format("first claimed at {}", to_string(it->second->location)),
                              it->second->location});
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

void ModelBuilder::check_state_machine(StateMachineDecl& machine) {
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

std::vector<Param> ModelBuilder::check_instance_params(const StateDecl& state,
                                                       const Node* overrides,
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

}  // namespace arbiter::detail
