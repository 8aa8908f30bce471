#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "arbiter/init_context.hpp"
#include "builtins.hpp"

namespace arbiter {
namespace {

/// Requests a scripted activation level per step and writes fixed values while active, so that
/// inhibition graphs can be tried without writing C++.
class ScriptedBehaviour final : public Behaviour {
 public:
  void init(BehaviourInitContext& ctx) override {
    const Node& writes = writes_node_;
    if (writes.reads_as_null()) return;
    if (writes.is_sequence()) {
      read_writes_by_step(ctx, writes);
      return;
    }
    if (!writes.is_mapping()) {
      ctx.error(writes.location(),
                fmt::format("'writes' must map actuators of this layer to values, or be a list of "
                            "{{from: STEP, ACTUATOR: VALUE, ...}}, found {}",
                            writes.describe()));
      return;
    }
    for (const auto& entry : writes.entries()) add_write(ctx, entry, 1);
  }

  double activation(const StepContext& ctx) override {
    const auto index = static_cast<std::size_t>(ctx.step() - 1);
    return levels_.empty() ? 0.0 : levels_[std::min(index, levels_.size() - 1)];
  }

  void execute(ExecuteContext& ctx) override {
    // Each actuator's value due at this step: the last of its writes from this step or before
    // (they are in step order per actuator); none before its first.
    for (std::size_t i = 0; i < writes_.size(); ++i) {
      const Write& write = writes_[i];
      const bool later_due = i + 1 < writes_.size() &&
                             writes_[i + 1].output.slot == write.output.slot &&
                             writes_[i + 1].from <= ctx.step();
      if (write.from <= ctx.step() && !later_due) ctx.write(write.output, write.value);
    }
  }

 private:
  struct Write {
    std::uint64_t from;
    AnyOutput output;
    ValueBox value;
  };

  // `writes: [{from: 1, kick: false}, {from: 45, kick: true}]`: each value written from its step
  // on, until a later item changes it.
  void read_writes_by_step(BehaviourInitContext& ctx, const Node& list) {
    std::uint64_t last = 0;
    for (const auto& item : list.items()) {
      const Node* from = item.is_mapping() ? item.find("from") : nullptr;
      if (from == nullptr) {
        ctx.error(item.location(),
                  item.is_mapping()
                      ? std::string("an item of 'writes' must say from which step its values are "
                                    "written ('from: STEP')")
                      : fmt::format("an item of 'writes' must be {{from: STEP, ACTUATOR: VALUE, "
                                    "...}}, found {}",
                                    item.describe()));
        continue;
      }
      const auto step = from->as_int();
      if (!step || *step < 1 || static_cast<std::uint64_t>(*step) <= last) {
        ctx.error(from->location(),
                  last > 0 && step && *step >= 1
                      ? fmt::format("'from' is {}; the steps of 'writes' must increase (the item "
                                    "before is from step {})",
                                    from->text(), last)
                      : fmt::format("'from' must be a step (an integer from 1), found {}",
                                    from->describe()));
        continue;
      }
      last = static_cast<std::uint64_t>(*step);
      for (const auto& entry : item.entries()) {
        if (entry.key != "from") add_write(ctx, entry, last);
      }
    }
    // Grouped by actuator, in step order within each (a stable sort keeps the steps' order).
    std::stable_sort(writes_.begin(), writes_.end(),
                     [](const Write& a, const Write& b) { return a.output.slot < b.output.slot; });
  }

  void add_write(BehaviourInitContext& ctx, const Node::Entry& entry, std::uint64_t from) {
    const AnyOutput output = ctx.output_to_actuator(entry.key, entry.key_location);
    if (output.type == nullptr) return;
    ValueBox value = ctx.make_value(*output.type, entry.value);
    if (value.type() == nullptr) return;
    writes_.push_back({from, output, std::move(value)});
  }

  friend void arbiter::register_scripted_behaviour(Registry& registry);
  std::vector<double> levels_;
  Node writes_node_;
  std::vector<Write> writes_;
};

}  // namespace

void register_scripted_behaviour(Registry& registry) {
  auto& info = registry.add_behaviour<ScriptedBehaviour>("scripted")
                   .describe(
                       "Requests a scripted activation level each step and writes fixed values "
                       "while active.");
  info.param("activation", &ScriptedBehaviour::levels_)
      .defaults_to(std::vector<double>{1.0})
      .range(0.0, 1.0)
      .held_by_step()
      .describe(
          "the requested level: a number, a list with one level per step (the last is held), "
          "or a list of {from: STEP, level: LEVEL}, each held from its step on (0 before the "
          "first)");
  info.param("writes", &ScriptedBehaviour::writes_node_)
      .defaults_to(Node())
      .schema(R"({"anyOf": [
                    {"title": "Values written", "type": ["object", "null"],
                     "propertyNames": {"$ref": "#/definitions/identifier"},
                     "additionalProperties": {"title": "Value written"}},
                    {"title": "Values written by step", "type": "array",
                     "items": {"title": "Values from a step on", "type": "object",
                               "required": ["from"],
                               "properties": {"from": {"title": "From step", "type": "integer",
                                                       "minimum": 1}},
                               "additionalProperties": {"title": "Value written"}}}]})")
      .describe(
          "a mapping from actuators of the behaviour's own layer to the value written each "
          "step while active, or a list of {from: STEP, ACTUATOR: VALUE, ...}, each value "
          "written from its step on (none before an actuator's first)");
}

void register_builtin_behaviours(Registry& registry) {
  register_inputs_interface(registry);
  register_scripted_behaviour(registry);
  register_scripted_state(registry);
  register_state_machine_behaviour(registry);
}

}  // namespace arbiter
