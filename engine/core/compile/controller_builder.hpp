#pragma once
// Sets a Controller up at load: its states, children, initial queue, pre-emptions and pool. Not
// installed: plugins see only the controller's read-only and stepping API.

#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include "arbiter/controller.hpp"

namespace arbiter {

/// The index of the state named `name`, searched at load only.
std::optional<std::uint32_t> find_state(const Controller& controller, std::string_view name);

/// Resolves `planned.param_index` from its params' names against the class's params (names the
/// model has validated).
void index_params(const ClassInfo& cls, PlannedState& planned);

class ControllerBuilder {
 public:
  explicit ControllerBuilder(Controller& controller) : c_(controller) {}

  std::uint32_t add_state(CompiledState state) {
    c_.states_.push_back(std::move(state));
    return static_cast<std::uint32_t>(c_.states_.size() - 1);
  }
  void set_initial_queue(std::vector<PlannedState> queue) {
    for (auto& planned : queue) index_params(*c_.states_[planned.state].cls, planned);
    c_.initial_ = std::move(queue);
  }
  void add_preemption(std::uint64_t cycle, PlannedState go_to) {
    index_params(*c_.states_[go_to.state].cls, go_to);
    c_.preemptions_.push_back({cycle, std::move(go_to)});
  }
  void set_owned(std::uint32_t owner_behaviour = kUnbound) {
    c_.owned_ = true;
    c_.owner_behaviour_ = owner_behaviour;
  }
  void set_children(std::vector<Controller*> children) { c_.children_ = std::move(children); }
  /// Numbers its states' reports from `base` on (an event source after every behaviour and
  /// layer of the program), each named "machine/state".
  void set_report_base(std::uint32_t base) {
    c_.report_base_ = base;
    c_.report_names_.clear();
    for (const auto& state : c_.states_) c_.report_names_.push_back(c_.name() + "/" + state.name);
  }
  void set_state_child(std::uint32_t state, std::uint32_t child) {
    c_.states_[state].child = child;
  }

  /// Creates `capacity` pooled objects of every state and calls `init(state, object)` on each.
  template <typename Init>
  void build_pool(Init&& init) {
    index_state_values();
    c_.pools_.resize(c_.states_.size());
    for (std::uint32_t s = 0; s < c_.states_.size(); ++s) {
      const std::size_t params = c_.states_[s].cls->params.size();
      for (std::size_t i = 0; i < c_.capacity_; ++i) {
        Controller::Instance instance;
        instance.state = s;
        instance.object = c_.states_[s].cls->make_state();
        instance.args.reserve(params);
        instance.own_values.assign(params, nullptr);
        init(s, *instance.object);
        c_.pools_[s].push_back(static_cast<std::uint32_t>(c_.instances_.size()));
        c_.instances_.push_back(std::move(instance));
      }
    }
    // Room to copy the run-time params of every event a step can record.
    std::size_t most_params = 0;
    for (const auto& state : c_.states_) {
      most_params = std::max(most_params, state.cls->params.size());
    }
    c_.event_args_.resize(Controller::kMaxEventsPerStep * most_params);
    c_.reset_queue();
  }

 private:
  void index_state_values();

  Controller& c_;
};

}  // namespace arbiter
