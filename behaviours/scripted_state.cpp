#include <fmt/format.h>

#include <vector>

#include "arbiter/controller.hpp"
#include "arbiter/init_context.hpp"
#include "builtins.hpp"

namespace arbiter {
namespace {

/// Holds for `hold` executions, then edits the plan as scripted and proceeds; with a child
/// controller (`machine:`), steps it and proceeds once it has finished. Lets plans be tried
/// without writing C++.
class ScriptedState final : public State {
 public:
  void init(StateInitContext& ctx) override {
    read_list(ctx, append_list_, "append", append_);
    read_list(ctx, prepend_list_, "prepend", prepend_);
  }

  StateResult execute(StateContext& ctx) override {
    // hold and terminate may differ per planned instance, so they are read per execution.
    const auto hold = static_cast<std::uint64_t>(ctx.param(hold_));
    if (Controller* child = ctx.child()) {
      child->step(ctx.step_context(), ctx.execute_context());
      if (child->status() == ControllerStatus::kRunning) return StateResult::kHold;
    } else if (ctx.executions() + 1 < hold) {
      return StateResult::kHold;
    }
    for (const auto& planned : append_) ctx.plan().append(planned);
    // Prepending in reverse keeps the list's order at the head of the queue.
    for (auto it = prepend_.rbegin(); it != prepend_.rend(); ++it) ctx.plan().prepend(*it);
    if (ctx.param(terminate_)) ctx.terminate();
    return StateResult::kProceed;
  }

 private:
  /// Plans the states of `list`, the param `param`.
  static void read_list(StateInitContext& ctx, const Node& list, const char* param,
                        std::vector<PlannedState>& out) {
    if (list.reads_as_null()) return;
    if (!list.is_sequence()) {
      ctx.error(list.location(), fmt::format("'{}' must be a list of states (a name, or "
                                             "{{name: {{param: value}}}}), found {}",
                                             param, list.describe()));
      return;
    }
    for (const auto& item : list.items()) {
      PlannedState planned;
      bool ok = false;
      if (item.is_mapping() && item.entries().size() == 1) {
        const auto& entry = item.entries()[0];
        ok = ctx.plan_state(entry.key, &entry.value, entry.key_location, planned);
      } else if (item.is_scalar()) {
        ok = ctx.plan_state(item.text(), nullptr, item.location(), planned);
      } else {
        ctx.error(item.location(), fmt::format("an entry of '{}' must be a state name or "
                                               "{{name: {{param: value}}}}, found {}",
                                               param, item.describe()));
      }
      if (ok) out.push_back(std::move(planned));
    }
  }

  friend void arbiter::register_scripted_state(Registry& registry);
  Node append_list_;
  Node prepend_list_;
  std::vector<PlannedState> append_;
  std::vector<PlannedState> prepend_;
  StateParam<std::int64_t> hold_;
  StateParam<bool> terminate_;
};

/// Steps a state machine while active (docs/config.md, "Built-in classes"): requests `activation`
/// while its controller is running and 0 once it has finished; pauses it while inhibited.
class StateMachineBehaviour final : public Behaviour {
 public:
  void init(BehaviourInitContext& ctx) override {
    controller_ =
        ctx.claim_controller(machine_, ctx.param_location(&StateMachineBehaviour::machine_));
  }

  double activation(const StepContext&) override {
    return controller_ != nullptr && controller_->status() == ControllerStatus::kRunning ? level_
                                                                                         : 0.0;
  }

  void execute(ExecuteContext& ctx) override {
    if (restart_ && ctx.just_activated() && controller_->cycle() > 0) controller_->restart(ctx);
    controller_->step(ctx, &ctx);
  }

 private:
  friend void arbiter::register_state_machine_behaviour(Registry& registry);
  std::string machine_;
  Controller* controller_ = nullptr;
  double level_ = 1.0;
  bool restart_ = false;
};

}  // namespace

void register_scripted_state(Registry& registry) {
  auto& info =
      add_state_class<ScriptedState>(registry, "scripted")
          .describe(
              "Holds for a number of executions, then appends or prepends planned states, or "
              "terminates "
              "the controller, and proceeds. With a child machine, steps it until it finishes.");
  info.param("hold", &ScriptedState::hold_)
      .defaults_to(1)
      .at_least(1)
      .describe("executions before proceeding");
  // The entries are written as the queue's (`arbiter schema` refers editors to its definition).
  const std::string planned_states =
      R"({"type": ["array", "null"], "items": {"$ref": "#/definitions/queue_entry"}})";
  info.param("append", &ScriptedState::append_list_)
      .defaults_to(Node())
      .schema(planned_states)
      .state_level()
      .describe("states to append to the queue when proceeding: names or {name: {params}}");
  info.param("prepend", &ScriptedState::prepend_list_)
      .defaults_to(Node())
      .schema(planned_states)
      .state_level()
      .describe("states to put at the head of the queue when proceeding, in this order");
  info.param("terminate", &ScriptedState::terminate_)
      .defaults_to(false)
      .describe("terminate the controller instead of proceeding");
}

void register_state_machine_behaviour(Registry& registry) {
  auto& info = registry.add_behaviour<StateMachineBehaviour>("state_machine")
                   .describe("Steps a state machine's controller while active.");
  info.param("machine", &StateMachineBehaviour::machine_).describe("the state machine to step");
  info.param("activation", &StateMachineBehaviour::level_)
      .defaults_to(1.0)
      .range(0.0, 1.0)
      .describe("the level requested while the controller is running");
  info.param("restart", &StateMachineBehaviour::restart_)
      .defaults_to(false)
      .describe(
          "start the controller again from its configured queue whenever the behaviour "
          "is activated anew");
}

}  // namespace arbiter
