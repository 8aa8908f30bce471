#include "arbiter/reload.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <unordered_map>

#include "arbiter/trace.hpp"
#include "core/run/carryover.hpp"

namespace arbiter {

namespace {

std::string behaviour_key(const Program& program, std::uint32_t b) {
  return program.layers[program.behaviours[b].layer].name + "/" + program.behaviours[b].name;
}

std::string class_name(const ClassInfo* cls) {
  return cls == nullptr ? std::string("none") : cls->name;
}

std::string actuator_text(const CompiledActuator& actuator) {
  return fmt::format("{}{}", actuator.type->name, actuator.aggregate ? ", aggregate" : "");
}

// A node's value as text, for comparing defaults wherever they were written.
std::string node_text(const Node& node) {
  std::string out;
  if (node.is_scalar()) return node.quoted() ? "\"" + node.text() + "\"" : node.text();
  if (node.is_sequence()) {
    out = "[";
    for (const auto& item : node.items()) out += node_text(item) + ",";
    return out + "]";
  }
  if (node.is_mapping()) {
    out = "{";
    for (const auto& entry : node.entries()) out += entry.key + ":" + node_text(entry.value) + ",";
    return out + "}";
  }
  return "null";
}

std::string default_text(const CompiledActuator& actuator) {
  return actuator.default_value ? node_text(*actuator.default_value) : std::string();
}

/// Declared inhibitions by "layer: inhibitor => inhibited" (arrow without its kind) → chaining.
std::map<std::string, bool> declared_inhibitions(const Program& program) {
  std::map<std::string, bool> out;
  for (const auto& declared : program.inhibitions.declared_inhibitions()) {
    const auto& inhibitor = program.behaviours[declared.inhibitor];
    const auto& inhibited = program.behaviours[declared.inhibited];
    out[fmt::format("{}: {} {} {}", program.layers[inhibited.layer].name, inhibitor.name, "{}",
                    inhibited.name)] = declared.chaining;
  }
  return out;
}

std::string arrow(const std::string& key, bool chaining) {
  return fmt::format(fmt::runtime(key), chaining ? "=>" : "->");
}

template <typename Item, typename Key, typename Describe, typename Compare>
void diff_items(const std::vector<Item>& before, const std::vector<Item>& after,
                const std::string& kind, Key key, Describe describe, Compare compare,
                ProgramDiff& out) {
  std::map<std::string, const Item*> old_items;
  for (const auto& item : before) old_items.emplace(key(item), &item);
  std::map<std::string, const Item*> new_items;
  for (const auto& item : after) new_items.emplace(key(item), &item);
  for (const auto& [name, item] : old_items) {
    if (new_items.count(name) == 0) {
      out.changes.push_back({Change::Kind::kRemoved, kind, name, describe(*item)});
    }
  }
  for (const auto& [name, item] : new_items) {
    const auto old = old_items.find(name);
    if (old == old_items.end()) {
      out.changes.push_back({Change::Kind::kAdded, kind, name, describe(*item)});
      continue;
    }
    std::string what = compare(*old->second, *item);
    if (!what.empty()) out.changes.push_back({Change::Kind::kChanged, kind, name, what});
  }
}

const LayerDecl* find_layer(const Model& model, const std::string& name) {
  return model.find_layer(name);
}

const BehaviourDecl* find_behaviour(const Model& model, const std::string& layer,
                                    const std::string& name) {
  const LayerDecl* decl = find_layer(model, layer);
  if (decl == nullptr) return nullptr;
  for (const auto& behaviour : decl->behaviours) {
    if (behaviour.name.text == name) return &behaviour;
  }
  return nullptr;
}

/// The params that differ, each old -> new: "kick_distance 0.3 -> 0.25, gain 1.0 -> (none)".
std::string params_change(const std::vector<Param>& before, const std::vector<Param>& after) {
  const auto find = [](const std::vector<Param>& params, const std::string& name) {
    const auto found = std::find_if(params.begin(), params.end(),
                                    [&](const Param& param) { return param.name == name; });
    return found == params.end() ? nullptr : &*found;
  };
  std::string out;
  const auto add = [&](const std::string& name, const Param* old, const Param* now) {
    out += fmt::format("{}{} {} -> {}", out.empty() ? "" : ", ", name,
                       old != nullptr ? param_value_text(old->value) : "(none)",
                       now != nullptr ? param_value_text(now->value) : "(none)");
  };
  for (const auto& param : before) {
    const Param* now = find(after, param.name);
    if (now == nullptr || !same_params({param}, {*now})) add(param.name, &param, now);
  }
  for (const auto& param : after) {
    if (find(before, param.name) == nullptr) add(param.name, nullptr, &param);
  }
  return out;
}

/// `[wait_for_button, walk_to_pose {x: -4.2}, monitor_ball]`
std::string queue_text(const Controller& controller) {
  std::string out = "[";
  for (const auto& planned : controller.initial_queue()) {
    if (out.size() > 1) out += ", ";
    out += controller.states()[planned.state].name;
    ParamTexts params;
    for (const auto& param : planned.params) {
      params.emplace_back(param.name, param_value_text(param.value));
    }
    if (!params.empty()) out += " " + params_text(params);
  }
  return out + "]";
}

/// What differs in a state machine's declaration: states added, removed or changed (class,
/// params), the queue old -> new, else the capacity; "pre-emptions or nested machines" when
/// only those differ.
std::string controller_change(const Controller& before, const Controller& after) {
  if (before.same_declaration(after)) return {};
  std::vector<std::string> parts;
  const auto find = [](const Controller& controller, const std::string& name) {
    for (const auto& state : controller.states()) {
      if (state.name == name) return &state;
    }
    return static_cast<const CompiledState*>(nullptr);
  };
  std::string added, removed;
  for (const auto& state : after.states()) {
    if (find(before, state.name) == nullptr) added += (added.empty() ? "" : ", ") + state.name;
  }
  for (const auto& state : before.states()) {
    const CompiledState* now = find(after, state.name);
    if (now == nullptr) {
      removed += (removed.empty() ? "" : ", ") + state.name;
    } else if (now->cls != state.cls) {
      parts.push_back(fmt::format("state {}: class {} -> {}", state.name, class_name(state.cls),
                                  class_name(now->cls)));
    } else if (!same_params(state.params, now->params)) {
      parts.push_back(
          fmt::format("state {}: params {}", state.name, params_change(state.params, now->params)));
    }
  }
  if (!added.empty()) parts.insert(parts.begin(), "states added: " + added);
  if (!removed.empty())
    parts.insert(parts.begin() + (added.empty() ? 0 : 1), "states removed: " + removed);
  const std::string old_queue = queue_text(before);
  const std::string new_queue = queue_text(after);
  if (old_queue != new_queue) parts.push_back(fmt::format("queue {} -> {}", old_queue, new_queue));
  // The capacity follows the states unless written: shown only when nothing else explains it.
  if (parts.empty() && before.capacity() != after.capacity()) {
    parts.push_back(fmt::format("capacity {} -> {}", before.capacity(), after.capacity()));
  }
  if (parts.empty()) parts.emplace_back("pre-emptions or nested machines");
  std::string out;
  for (const auto& part : parts) out += (out.empty() ? "" : "; ") + part;
  return out;
}

bool same_ports(const std::vector<PortBinding>& a, const std::vector<PortBinding>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].port != b[i].port || a[i].target != b[i].target) return false;
  }
  return true;
}

/// Builds the carry-over of `after` against the running `before` (docs/hot_reload.md): which of
/// its parts match a running one.
class CarryoverMatcher {
 public:
  CarryoverMatcher(const Program& before, const Model& before_model, const Program& after,
                   const Model& after_model)
      : before_(before), old_model_(before_model), after_(after), new_model_(after_model) {}

  detail::Carryover run(ProgramDiff& diff, std::vector<std::string>& restarted) {
    detail::Carryover carryover;
    match_actuators(carryover);
    slots_of(before_, old_slots_);
    slots_of(after_, new_slots_);
    match_behaviours(carryover, diff);
    match_interfaces(carryover, diff);
    // A kept behaviour holds pointers to the controllers it claimed, so those must be kept with
    // it, and a controller is kept only with its owner: demote until both agree.
    for (bool changed = true; changed;) {
      match_controllers(carryover);
      changed = demote_owners(carryover);
    }
    for (std::uint32_t b = 0; b < after_.behaviours.size(); ++b) {
      if (carryover.behaviour_from[b] != detail::kNoMatch && carryover.behaviour_kept[b] == 0) {
        restarted.push_back(behaviour_key(after_, b));
      }
    }
    for (std::uint32_t l = 0; l < after_.layers.size(); ++l) {
      if (carryover.interface_from[l] != detail::kNoMatch && carryover.interface_kept[l] == 0) {
        restarted.push_back(fmt::format("interface of layer {}", after_.layers[l].name));
      }
    }
    for (std::uint32_t c = 0; c < after_.controllers.size(); ++c) {
      if (carryover.controller_kept[c] == detail::kNoMatch &&
          before_.find_controller(after_.controllers[c]->name()) != nullptr) {
        restarted.push_back(fmt::format("state machine {}", after_.controllers[c]->name()));
      }
    }
    return carryover;
  }

 private:
  void match_actuators(detail::Carryover& carryover) {
    std::unordered_map<std::string, std::uint32_t> index;
    for (std::uint32_t a = 0; a < before_.actuators.size(); ++a) {
      index.emplace(before_.actuators[a].name, a);
    }
    carryover.actuator_from.assign(after_.actuators.size(), detail::kNoMatch);
    for (std::uint32_t a = 0; a < after_.actuators.size(); ++a) {
      const auto found = index.find(after_.actuators[a].name);
      if (found != index.end() &&
          before_.actuators[found->second].type == after_.actuators[a].type) {
        carryover.actuator_from[a] = found->second;
      }
    }
    same_index_.assign(before_.actuators.size(), 0);
    for (std::uint32_t a = 0; a < before_.actuators.size() && a < after_.actuators.size(); ++a) {
      same_index_[a] = carryover.actuator_from[a] == a ? 1 : 0;
    }
  }

  // Writer slots by owner: behaviours first, then one list per layer for its interface.
  void slots_of(const Program& program, std::vector<std::vector<std::uint32_t>>& out) {
    out.assign(program.behaviours.size() + program.layers.size(), {});
    for (std::uint32_t s = 0; s < program.slots.size(); ++s) {
      const WriterSlot& slot = program.slots[s];
      const std::size_t owner =
          slot.owner != kNoBehaviour
              ? slot.owner
              : program.behaviours.size() + program.actuators[slot.actuator].layer;
      out[owner].push_back(s);
    }
  }

  // Whether the handles an instance resolved in the running program (actuator indices of its
  // layer's sensors and actuators, and its writer slots) mean the same in the new one.
  bool same_handles(std::uint32_t old_layer, std::size_t old_owner, std::size_t new_owner) const {
    const CompiledLayer& layer = before_.layers[old_layer];
    for (auto a = layer.actuator_begin; a < layer.actuator_end; ++a) {
      if (same_index_[a] == 0) return false;
    }
    for (const auto a : layer.sensors) {
      if (same_index_[a] == 0) return false;
    }
    const auto& mine = old_slots_[old_owner];
    const auto& theirs = new_slots_[new_owner];
    if (mine.size() != theirs.size()) return false;
    for (std::size_t i = 0; i < mine.size(); ++i) {
      if (mine[i] != theirs[i] ||
          before_.slots[mine[i]].actuator != after_.slots[theirs[i]].actuator) {
        return false;
      }
    }
    return true;
  }

  void match_behaviours(detail::Carryover& carryover, ProgramDiff& diff) {
    std::unordered_map<std::string, std::uint32_t> index;
    for (std::uint32_t b = 0; b < before_.behaviours.size(); ++b) {
      index.emplace(behaviour_key(before_, b), b);
    }
    carryover.behaviour_from.assign(after_.behaviours.size(), detail::kNoMatch);
    carryover.behaviour_kept.assign(after_.behaviours.size(), 0);
    for (std::uint32_t b = 0; b < after_.behaviours.size(); ++b) {
      const auto found = index.find(behaviour_key(after_, b));
      if (found == index.end()) continue;
      const std::uint32_t from = found->second;
      const CompiledBehaviour& old = before_.behaviours[from];
      const CompiledBehaviour& now = after_.behaviours[b];
      if (old.cls != now.cls) continue;
      carryover.behaviour_from[b] = from;
      const std::string& layer = after_.layers[now.layer].name;
      const BehaviourDecl* old_decl = find_behaviour(old_model_, layer, now.name);
      const BehaviourDecl* new_decl = find_behaviour(new_model_, layer, now.name);
      const bool same_params = old_decl != nullptr && new_decl != nullptr &&
                               arbiter::same_params(old_decl->params.items, new_decl->params.items);
      if (!same_params) {
        diff.changes.push_back(
            {Change::Kind::kChanged, "behaviour", behaviour_key(after_, b),
             "params: " + (old_decl != nullptr && new_decl != nullptr
                               ? params_change(old_decl->params.items, new_decl->params.items)
                               : std::string("changed"))});
      }
      const bool same_declaration = same_params && same_ports(old_decl->ports, new_decl->ports) &&
                                    old.on_exception == now.on_exception;
      carryover.behaviour_kept[b] = same_declaration && same_handles(old.layer, from, b) ? 1 : 0;
    }
  }

  void match_interfaces(detail::Carryover& carryover, ProgramDiff& diff) {
    carryover.interface_from.assign(after_.layers.size(), detail::kNoMatch);
    carryover.interface_kept.assign(after_.layers.size(), 0);
    for (std::uint32_t l = 0; l < after_.layers.size(); ++l) {
      const CompiledLayer& now = after_.layers[l];
      if (!now.is_interface()) continue;
      for (std::uint32_t from = 0; from < before_.layers.size(); ++from) {
        const CompiledLayer& old = before_.layers[from];
        if (old.name != now.name || old.interface_class != now.interface_class) continue;
        carryover.interface_from[l] = from;
        const LayerDecl* old_decl = find_layer(old_model_, now.name);
        const LayerDecl* new_decl = find_layer(new_model_, now.name);
        const bool same_params =
            old_decl != nullptr && new_decl != nullptr &&
            arbiter::same_params(old_decl->params.items, new_decl->params.items);
        if (!same_params) {
          diff.changes.push_back(
              {Change::Kind::kChanged, "layer", now.name,
               "params: " + (old_decl != nullptr && new_decl != nullptr
                                 ? params_change(old_decl->params.items, new_decl->params.items)
                                 : std::string("changed"))});
        }
        carryover.interface_kept[l] = same_params && same_ports(old_decl->ports, new_decl->ports) &&
                                              same_handles(from, before_.behaviours.size() + from,
                                                           after_.behaviours.size() + l)
                                          ? 1
                                          : 0;
      }
    }
  }

  static std::vector<std::uint32_t> parents(const Program& program) {
    std::vector<std::uint32_t> parent(program.controllers.size(), kNoController);
    for (std::uint32_t c = 0; c < program.controllers.size(); ++c) {
      const Controller& controller = *program.controllers[c];
      for (std::uint32_t s = 0; s < controller.states().size(); ++s) {
        const Controller* child = controller.child_of(s);
        if (child == nullptr) continue;
        for (std::uint32_t k = 0; k < program.controllers.size(); ++k) {
          if (program.controllers[k].get() == child) parent[k] = c;
        }
      }
    }
    return parent;
  }

  static std::uint32_t root_of(const std::vector<std::uint32_t>& parent, std::uint32_t c) {
    while (parent[c] != kNoController) c = parent[c];
    return c;
  }

  // A controller is kept with its whole tree (parents hold pointers to their children): when
  // every controller of the tree was declared alike and the root's owner is kept, or both roots
  // are standalone.
  void match_controllers(detail::Carryover& carryover) {
    const auto old_parent = parents(before_);
    const auto new_parent = parents(after_);
    std::vector<std::uint32_t> from(after_.controllers.size(), detail::kNoMatch);
    for (std::uint32_t c = 0; c < after_.controllers.size(); ++c) {
      for (std::uint32_t o = 0; o < before_.controllers.size(); ++o) {
        if (before_.controllers[o]->name() == after_.controllers[c]->name()) from[c] = o;
      }
    }
    std::vector<char> tree_ok(after_.controllers.size(), 1);
    for (std::uint32_t c = 0; c < after_.controllers.size(); ++c) {
      const bool ok = from[c] != detail::kNoMatch &&
                      after_.controllers[c]->same_declaration(*before_.controllers[from[c]]);
      if (!ok) tree_ok[root_of(new_parent, c)] = 0;
    }
    for (std::uint32_t c = 0; c < after_.controllers.size(); ++c) {
      if (new_parent[c] != kNoController || from[c] == detail::kNoMatch) continue;
      const Controller& now = *after_.controllers[c];
      const Controller& old = *before_.controllers[from[c]];
      if (old_parent[from[c]] != kNoController) tree_ok[c] = 0;
      const std::uint32_t owner = now.owner_behaviour();
      if (now.owned() != old.owned()) tree_ok[c] = 0;
      if (owner == kNoBehaviour) {
        if (old.owner_behaviour() != kNoBehaviour) tree_ok[c] = 0;
      } else if (carryover.behaviour_kept[owner] == 0 ||
                 carryover.behaviour_from[owner] != old.owner_behaviour()) {
        tree_ok[c] = 0;
      }
    }
    carryover.controller_kept.assign(after_.controllers.size(), detail::kNoMatch);
    for (std::uint32_t c = 0; c < after_.controllers.size(); ++c) {
      if (tree_ok[root_of(new_parent, c)] != 0) carryover.controller_kept[c] = from[c];
    }
  }

  // A kept behaviour whose controllers are not all kept is given a new instance instead.
  bool demote_owners(detail::Carryover& carryover) {
    bool changed = false;
    std::vector<char> old_kept(before_.controllers.size(), 0);
    for (const auto from : carryover.controller_kept) {
      if (from != detail::kNoMatch) old_kept[from] = 1;
    }
    for (std::uint32_t b = 0; b < after_.behaviours.size(); ++b) {
      if (carryover.behaviour_kept[b] == 0) continue;
      bool keep = true;
      for (std::uint32_t c = 0; c < after_.controllers.size(); ++c) {
        if (after_.controllers[c]->owner_behaviour() == b &&
            carryover.controller_kept[c] == detail::kNoMatch) {
          keep = false;
        }
      }
      for (std::uint32_t o = 0; o < before_.controllers.size(); ++o) {
        if (before_.controllers[o]->owner_behaviour() == carryover.behaviour_from[b] &&
            old_kept[o] == 0) {
          keep = false;
        }
      }
      if (!keep) {
        carryover.behaviour_kept[b] = 0;
        changed = true;
      }
    }
    return changed;
  }

  const Program& before_;
  const Model& old_model_;
  const Program& after_;
  const Model& new_model_;
  std::vector<char> same_index_;  // per running actuator: the new program has it at that index
  std::vector<std::vector<std::uint32_t>> old_slots_;
  std::vector<std::vector<std::uint32_t>> new_slots_;
};

}  // namespace

ProgramDiff diff(const Program& before, const Program& after) {
  ProgramDiff out;
  diff_items(
      before.layers, after.layers, "layer", [](const CompiledLayer& layer) { return layer.name; },
      [](const CompiledLayer& layer) {
        return layer.is_interface() ? fmt::format("interface {}", layer.interface_class->name)
                                    : std::string();
      },
      [](const CompiledLayer& a, const CompiledLayer& b) {
        std::string what;
        if (a.interface_class != b.interface_class) {
          what = fmt::format("interface {} -> {}", class_name(a.interface_class),
                             class_name(b.interface_class));
        } else if (a.normalise != b.normalise) {
          what = fmt::format("normalise {} -> {}", a.normalise, b.normalise);
        }
        return what;
      },
      out);

  std::vector<std::pair<std::string, const CompiledBehaviour*>> before_behaviours;
  std::vector<std::pair<std::string, const CompiledBehaviour*>> after_behaviours;
  for (std::uint32_t b = 0; b < before.behaviours.size(); ++b) {
    before_behaviours.emplace_back(behaviour_key(before, b), &before.behaviours[b]);
  }
  for (std::uint32_t b = 0; b < after.behaviours.size(); ++b) {
    after_behaviours.emplace_back(behaviour_key(after, b), &after.behaviours[b]);
  }
  using Keyed = std::pair<std::string, const CompiledBehaviour*>;
  diff_items(
      before_behaviours, after_behaviours, "behaviour",
      [](const Keyed& item) { return item.first; },
      [](const Keyed& item) { return item.second->cls->name; },
      [](const Keyed& a, const Keyed& b) {
        return a.second->cls == b.second->cls
                   ? std::string()
                   : fmt::format("class {} -> {}", a.second->cls->name, b.second->cls->name);
      },
      out);

  const auto old_inhibitions = declared_inhibitions(before);
  const auto new_inhibitions = declared_inhibitions(after);
  for (const auto& [key, chaining] : old_inhibitions) {
    const auto found = new_inhibitions.find(key);
    if (found == new_inhibitions.end()) {
      out.changes.push_back({Change::Kind::kRemoved, "inhibition", arrow(key, chaining), ""});
    } else if (found->second != chaining) {
      out.changes.push_back({Change::Kind::kChanged, "inhibition", arrow(key, found->second),
                             chaining ? "was chaining" : "was non-chaining"});
    }
  }
  for (const auto& [key, chaining] : new_inhibitions) {
    if (old_inhibitions.count(key) == 0) {
      out.changes.push_back({Change::Kind::kAdded, "inhibition", arrow(key, chaining), ""});
    }
  }

  diff_items(
      before.actuators, after.actuators, "actuator",
      [](const CompiledActuator& actuator) { return actuator.name; },
      [&](const CompiledActuator& actuator) { return actuator_text(actuator); },
      [&](const CompiledActuator& a, const CompiledActuator& b) {
        std::string what;
        if (a.type != b.type || a.aggregate != b.aggregate) {
          what = fmt::format("{} -> {}", actuator_text(a), actuator_text(b));
        } else if (before.layers[a.layer].name != after.layers[b.layer].name) {
          what = fmt::format("layer {} -> {}", before.layers[a.layer].name,
                             after.layers[b.layer].name);
        } else if (default_text(a) != default_text(b)) {
          what = "default";
        }
        return what;
      },
      out);

  using Owned = std::unique_ptr<Controller>;
  diff_items(
      before.controllers, after.controllers, "controller",
      [](const Owned& controller) { return controller->name(); },
      [](const Owned& controller) {
        return fmt::format("{} state{}", controller->states().size(),
                           controller->states().size() == 1 ? "" : "s");
      },
      [](const Owned& a, const Owned& b) { return controller_change(*a, *b); }, out);
  return out;
}

namespace {

/// What carries over from `before` to `after`, and in `out` their structural diff followed by the
/// params changes the models tell.
detail::Carryover match(const Program& before, const Program& after, ProgramDiff& out,
                        std::vector<std::string>& restarted) {
  const Model no_model;
  CarryoverMatcher matcher(before, before.model ? *before.model : no_model, after,
                           after.model ? *after.model : no_model);
  ProgramDiff params;
  detail::Carryover carryover = matcher.run(params, restarted);
  out = diff(before, after);
  out.changes.insert(out.changes.end(), params.changes.begin(), params.changes.end());
  return carryover;
}

}  // namespace

ProgramDiff config_diff(const Program& before, const Program& after) {
  ProgramDiff out;
  std::vector<std::string> restarted;
  match(before, after, out, restarted);
  // What a reload keeps (docs/hot_reload.md) but two runs may differ by.
  if (before.name != after.name) {
    out.changes.push_back({Change::Kind::kChanged, "config", "name",
                           fmt::format("{} -> {}", before.name, after.name)});
  }
  if (before.rate_hz != after.rate_hz) {
    out.changes.push_back({Change::Kind::kChanged, "config", "rate_hz",
                           fmt::format("{:g} -> {:g}", before.rate_hz, after.rate_hz)});
  }
  return out;
}

std::string format(const ProgramDiff& diff, const std::string& indent) {
  std::string out;
  for (const auto& change : diff.changes) {
    const char sign = change.kind == Change::Kind::kAdded     ? '+'
                      : change.kind == Change::Kind::kRemoved ? '-'
                                                              : '~';
    out += fmt::format("{}{} {} {}", indent, sign, change.item, change.name);
    if (!change.detail.empty()) {
      out += change.kind == Change::Kind::kChanged ? ": " : " (";
      out += change.detail;
      if (change.kind != Change::Kind::kChanged) out += ")";
    }
    out += "\n";
  }
  return out;
}

Reloader::Reloader(Registry& registry, LoadOptions options)
    : registry_(registry), options_(std::move(options)) {}

Reloader::~Reloader() = default;

std::optional<Program> Reloader::load_program(Diagnostics& diagnostics) {
  Loaded loaded = load_config(path_, registry_, options_);
  diagnostics = std::move(loaded.diagnostics);
  texts_.clear();
  if (loaded.model) {
    // Copies of every file's text: only a recording's reload record needs them.
    for (std::size_t i = 0; on_staging_ && i < loaded.model->files.size(); ++i) {
      const std::string& file = loaded.model->files[i];
      const SourceFile* read = loaded.files.find(file);
      texts_.emplace_back(file, read != nullptr ? read->text : std::string());
    }
    if (!loaded.model->files.empty()) files_ = loaded.model->files;
  }
  return std::move(loaded.program);
}

std::optional<Program> Reloader::load(const std::string& path, Diagnostics& diagnostics) {
  path_ = path;
  files_ = {path};
  return load_program(diagnostics);
}

ReloadResult Reloader::reload(Manager& manager) {
  ReloadResult result;
  // After withdraw() the manager's program stays put until stage(), so it can be read here.
  manager.withdraw();
  auto program = load_program(result.diagnostics);
  if (!program) return result;
  detail::Carryover carryover = match(manager.program(), *program, result.diff, result.restarted);
  if (on_staging_) on_staging_(texts_);
  manager.stage(std::move(*program), std::move(carryover));
  result.staged = true;
  return result;
}

}  // namespace arbiter
