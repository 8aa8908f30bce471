#pragma once
// An SCL state controller, compiled: its states, the pool of single-use instances sized at load,
// the queue, and the step of docs/semantics.md, "State machines". Built by compile(), stepped by
// its owner (a behaviour or a parent state) or, when standalone, by the manager after the output
// pass.

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "arbiter/model.hpp"
#include "arbiter/state.hpp"

namespace spdlog {
class logger;
}

namespace arbiter {

struct CompiledState {
  std::string name;
  const ClassInfo* cls = nullptr;
  SourceLocation location;
  std::vector<Param> params;            ///< as written for the state (no class defaults)
  std::uint32_t child = kNoController;  ///< index of the controller this state owns
};

/// Whether two param lists hold the same names and values, wherever they were written.
bool same_params(const std::vector<Param>& a, const std::vector<Param>& b);

class Controller {
 public:
  /// Why a state was deactivated (docs/semantics.md, "State machines"). Recorded as it happens,
  /// with indices only; observers turn it into text (end_text() in trace.hpp).
  enum class EndCause : std::uint8_t {
    kNone,        ///< not a deactivation
    kProceeded,   ///< it asked to proceed; the head of the queue followed
    kQueueEmpty,  ///< it asked to proceed with nothing queued: the controller finished
    kPreempted,   ///< a pre-emption (a hook, or a `preempt:` entry) replaced the plan
    kGoTo,        ///< it asked to proceed after replacing the plan with go_to
    kTerminated,  ///< terminate() ended the controller
    kError,       ///< the controller stopped with an error (an impossible plan edit)
    kRestarted,   ///< restart(): its owner started the controller again
    kDropped,     ///< end(): a hot reload dropped the controller
  };
  /// A run-time param of a state instance as planned (Plan calls), copied when the event is
  /// recorded: the instance may be planned anew, with other params, later in the same step.
  struct EventArg {
    std::uint32_t param;  ///< index into the state class's params
    ArgValue value;
  };
  /// What happened to a state instance in a step. Three are recorded in a plain transition, so
  /// each kind writes only the fields it has: `kind`, `state`, `sequence` and `args_count` are
  /// always set; the rest hold stale values where the comment says they do not apply.
  struct Event {
    enum class Kind : std::uint8_t { kActivate, kExecute, kDeactivate };
    Kind kind = Kind::kExecute;
    /// kDeactivate only, as `proceeded`, `other` and `preempt` are.
    EndCause cause = EndCause::kNone;
    /// kPreempted: the state had asked to proceed too (the pre-emption decided what followed).
    bool proceeded = false;
    std::uint32_t state = kNoState;
    /// Where in the step it happened: reports (StepContext::report) and the events of every
    /// controller draw from one counter per step, so observers can print them in order.
    std::uint32_t sequence = 0;
    /// The run-time params (event_args()); 0 for kExecute.
    std::uint32_t args_count = 0;
    /// kPreempted, kGoTo: the state planned in its place (kNoState: none); kTerminated: the
    /// state whose callback called terminate() (kNoState: a hook of the owner).
    std::uint32_t other = kNoState;
    /// kPreempted: the index of the `preempt:` entry that fired (kNoIndex: a hook).
    std::uint32_t preempt = kNoIndex;
    /// kActivate, kDeactivate: where the run-time params start in event_args().
    std::uint32_t args_begin = 0;
    /// kActivate, kDeactivate: the instance's per-instance params from the config (or null).
    const std::vector<Param>* planned = nullptr;
  };
  static constexpr std::size_t kMaxEventsPerStep = 64;

  Controller(std::string name, SourceLocation location, std::size_t capacity);
  Controller(Controller&&) = delete;  // states and contexts point at their controller

  const std::string& name() const { return name_; }
  const SourceLocation& location() const { return location_; }
  ControllerStatus status() const { return status_; }
  std::uint64_t cycle() const { return cycle_; }
  std::size_t capacity() const { return capacity_; }
  const std::vector<CompiledState>& states() const { return states_; }
  /// What a report of one of its states names as its source ("machine/state"), for an event
  /// source (StepData::Event::source) of this controller's states; else nullptr. A state's report
  /// is its own, not that of the behaviour stepping the machine.
  const std::string* report_source(std::uint32_t source) const {
    if (source < report_base_ || source - report_base_ >= report_names_.size()) return nullptr;
    return &report_names_[source - report_base_];
  }
  /// The configured initial queue (`queue:`), which a restart begins with.
  const std::vector<PlannedState>& initial_queue() const { return initial_; }

  /// One controller step (docs/semantics.md, "State machines"). `execute` is the owner's execute
  /// context, through which states write actuators; null for a standalone controller (its states
  /// cannot write).
  void step(const StepContext& context, ExecuteContext* execute = nullptr);
  /// Back to cycle 0 with the configured initial queue; a current state is deactivated first.
  void restart(const StepContext& context);

  /// The current state's name, or "" before the first step and once finished.
  std::string_view current_state() const;
  /// The current instance's per-instance params from the config's plan (or null), and from Plan
  /// calls (class param index, value); null and empty when there is no current state.
  const std::vector<Param>* current_planned() const {
    return current_ == kNoIndex ? nullptr : instances_[current_].planned;
  }
  const std::vector<std::pair<std::uint32_t, ParamValue>>& current_args() const {
    static const std::vector<std::pair<std::uint32_t, ParamValue>> kNone;
    return current_ == kNoIndex ? kNone : instances_[current_].args;
  }
  /// The current state's index, or kNoState.
  std::uint32_t current_state_index() const {
    return current_ == kNoIndex ? kNoState : instances_[current_].state;
  }
  std::size_t queue_size() const { return queue_.size(); }
  std::string_view queued(std::size_t index) const;
  /// The state index of the queue's entry `index` (< queue_size()).
  std::uint32_t queued_state(std::size_t index) const { return instances_[queue_[index]].state; }
  const Event* events() const { return events_.data(); }
  std::size_t event_count() const { return std::min(event_count_, kMaxEventsPerStep); }
  /// The run-time params of an activation or deactivation: [first, first + event.args_count).
  const EventArg* event_args(const Event& event) const {
    return event_args_.data() + event.args_begin;
  }
  /// Called by the manager at the start of every step, so a paused controller shows no events.
  void clear_events() {
    event_count_ = 0;
    event_args_used_ = 0;
  }

  /// Not owned; the hooks must outlive the controller or be reset.
  void set_hooks(ControllerHooks* hooks) { hooks_ = hooks; }
  void set_logger(spdlog::logger* logger) { logger_ = logger; }

  /// The child controller a state owns (`machine:`), or nullptr.
  const Controller* child_of(std::uint32_t state) const {
    const auto child = states_[state].child;
    return child == kNoController ? nullptr : children_[child];
  }
  /// Whether a behaviour or a parent state steps it (else the manager does: standalone).
  bool owned() const { return owned_; }
  /// The behaviour that claimed it (and so holds a pointer to it), or kNoBehaviour: standalone, or
  /// the child of a state.
  std::uint32_t owner_behaviour() const { return owner_behaviour_; }

  /// Whether `other` was declared alike: the same states (names, classes, params, children by
  /// name), initial queue, pre-emptions and capacity. A hot reload keeps a controller, with its
  /// current state and queue, only then (docs/hot_reload.md).
  bool same_declaration(const Controller& other) const;
  /// For a hot reload that drops this controller: deactivates the current state, if any, as a
  /// finish would; the controller is not stepped again. Allocates nothing.
  void end(const StepContext& context);

  /// The message of the error that stopped the controller ("" unless status is error).
  const std::string& error() const { return error_; }

 private:
  friend class Plan;
  friend class StateContext;
  friend class ControllerBuilder;  // sets it up at load (core/compile/controller_builder.hpp)

  struct Instance {
    std::uint32_t state = 0;
    std::unique_ptr<State> object;
    const std::vector<Param>* planned = nullptr;  ///< per-instance params from the config
    std::vector<std::pair<std::uint32_t, ParamValue>> args;  ///< from Plan calls, by param index
    /// Each class param's value for this instance (args, else planned, else the state's, else
    /// the default; null: none), so that a step reads a param by index: the state's own table
    /// (state_values_) while nothing was planned for the instance, else `own_values`.
    const ParamValue* const* values = nullptr;
    std::vector<const ParamValue*> own_values;  ///< sized at load: one per class param
    std::uint64_t executions = 0;
  };

  std::optional<std::uint32_t> create(std::uint32_t state, const PlannedState* planned,
                                      const detail::PlanArg* args, std::size_t count);
  bool insert(std::size_t index, std::optional<std::uint32_t> instance);
  void release(std::uint32_t instance);
  void reset_queue();
  /// Why the current state is left, as found in the first phase of a step.
  struct Ending {
    EndCause cause = EndCause::kNone;
    bool proceeded = false;
    std::uint32_t other = kNoState;
    std::uint32_t preempt = kNoIndex;
  };
  /// Records an activation (no `ending`) or a deactivation of `instance`; each kind writes only
  /// the fields it has, as three events are recorded in a plain transition.
  void record(const StepContext& context, Event::Kind kind, std::uint32_t instance,
              const Ending* ending);
  /// Records an execution: the event of every step.
  void record_execute(const StepContext& context, std::uint32_t instance) {
    const std::uint32_t sequence = next_sequence(context);
    if (event_count_ >= kMaxEventsPerStep) {
      ++event_count_;
      return;
    }
    Event& event = events_[event_count_++];
    event.kind = Event::Kind::kExecute;
    event.state = instances_[instance].state;
    event.sequence = sequence;
    event.args_count = 0;
  }
  static std::uint32_t next_sequence(const StepContext& context) {
    return context.data_->sequence++;
  }
  void fail(std::string message);
  void deactivate_current(StateContext& context, const Ending& ending);
  /// Why terminate() or an error ends the current state.
  Ending stop_ending() const;
  void note_go_to();
  /// Calls a callback of `instance`, so that plan edits know which state made them.
  template <typename Call>
  auto in_callback(std::uint32_t instance, Call&& call) {
    const std::uint32_t outer = callback_;
    callback_ = instance;
    struct Restore {
      std::uint32_t& callback;
      std::uint32_t outer;
      ~Restore() { callback = outer; }
    } restore{callback_, outer};
    return call();
  }
  void finish();

  std::string name_;
  SourceLocation location_;
  std::size_t capacity_;
  std::vector<CompiledState> states_;
  /// Per state, each class param's value before any planning (the state's, else the default).
  std::vector<std::vector<const ParamValue*>> state_values_;
  /// Per state, 1 when a required param has no value of the state's own: planning checks it.
  std::vector<std::uint8_t> check_required_;
  std::vector<Instance> instances_;
  std::vector<std::vector<std::uint32_t>> pools_;  ///< free instances per state
  std::size_t live_ = 0;
  std::vector<std::uint32_t> queue_;  ///< reserved to capacity: edits never allocate
  std::uint32_t current_ = kNoIndex;
  std::vector<PlannedState> initial_;
  struct Preempt {
    std::uint64_t cycle;
    PlannedState go_to;
  };
  std::vector<Preempt> preemptions_;
  std::vector<Controller*> children_;
  ControllerStatus status_ = ControllerStatus::kRunning;
  std::uint64_t cycle_ = 0;
  bool proceed_ = false;
  bool terminate_ = false;
  bool stepping_ = false;
  bool owned_ = false;
  std::uint32_t owner_behaviour_ = kNoBehaviour;
  /// The event source of its first state's reports (kNoIndex: its states report as the owner
  /// does), and each state's source name.
  std::uint32_t report_base_ = kNoIndex;
  std::vector<std::string> report_names_;
  std::array<Event, kMaxEventsPerStep> events_{};
  std::size_t event_count_ = 0;
  std::vector<EventArg> event_args_;  ///< sized when the pool is built
  std::size_t event_args_used_ = 0;
  /// The instance whose callback is running (kNoIndex: none, or a hook).
  std::uint32_t callback_ = kNoIndex;
  /// The state the current instance replaced the plan with (go_to), or kNoState.
  std::uint32_t went_to_ = kNoState;
  /// The state whose callback called terminate() (kNoState: a hook), valid with terminate_.
  std::uint32_t terminated_by_ = kNoState;
  ControllerHooks* hooks_ = nullptr;
  spdlog::logger* logger_ = nullptr;
  std::string error_;
};

}  // namespace arbiter
