#include <fmt/format.h>

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
    if (!writes.is_mapping()) {
      ctx.error(writes.location(),
                fmt::format("'writes' must map actuators of this layer to values, found {}",
                            writes.describe()));
      return;
    }
    for (const auto& entry : writes.entries()) {
      const AnyOutput output = ctx.output_to_actuator(entry.key, entry.key_location);
      if (output.type == nullptr) continue;
      ValueBox value = ctx.make_value(*output.type, entry.value);
      if (value.type() == nullptr) continue;
      writes_.emplace_back(output, std::move(value));
    }
  }

  double activation(const StepContext& ctx) override {
    const auto index = static_cast<std::size_t>(ctx.step() - 1);
    return levels_.empty() ? 0.0 : levels_[std::min(index, levels_.size() - 1)];
  }

  void execute(ExecuteContext& ctx) override {
    for (const auto& [output, value] : writes_) ctx.write(output, value);
  }

 private:
  friend void arbiter::register_scripted_behaviour(Registry& registry);
  std::vector<double> levels_;
  Node writes_node_;
  std::vector<std::pair<AnyOutput, ValueBox>> writes_;
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
      .schema(R"({"type": ["object", "null"],
                  "propertyNames": {"$ref": "#/definitions/identifier"},
                  "additionalProperties": {"title": "Value written"}})")
      .describe(
          "a mapping from actuators of the behaviour's own layer to the value written each "
          "step while active");
}

void register_builtin_behaviours(Registry& registry) {
  register_inputs_interface(registry);
  register_scripted_behaviour(registry);
  register_scripted_state(registry);
  register_state_machine_behaviour(registry);
}

}  // namespace arbiter
