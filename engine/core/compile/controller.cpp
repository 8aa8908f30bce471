#include "arbiter/controller.hpp"

#include "core/compile/controller_builder.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

namespace arbiter {

const char* to_string(ControllerStatus status) {
  switch (status) {
    case ControllerStatus::kRunning:
      return "running";
    case ControllerStatus::kFinished:
      return "finished";
    case ControllerStatus::kError:
      return "error";
  }
  return "?";
}

// --- Plan ----------------------------------------------------------------------------------------

bool Plan::edit(Mode mode, std::size_t index, std::uint32_t state, const PlannedState* planned,
                const detail::PlanArg* args, std::size_t count) {
  if (state == kNoState) {
    // Only a handle whose resolution failed the load, or a default-constructed one, is unbound.
    controller_->fail("planned a state handle that init() did not resolve");
    return false;
  }
  if (mode == kGoTo) clear();
  const bool done = controller_->insert(index, controller_->create(state, planned, args, count));
  if (done && mode == kGoTo) controller_->note_go_to();
  return done;
}
bool Plan::append(const PlannedState& planned) {
  return edit(kAt, size(), planned.state, &planned, nullptr, 0);
}
bool Plan::prepend(const PlannedState& planned) {
  return edit(kAt, 0, planned.state, &planned, nullptr, 0);
}
bool Plan::go_to(const PlannedState& planned) {
  return edit(kGoTo, 0, planned.state, &planned, nullptr, 0);
}
bool Plan::remove(std::size_t index) {
  auto& queue = controller_->queue_;
  if (index >= queue.size()) {
    controller_->fail(fmt::format("plan.remove({}) on a queue of {} states", index, queue.size()));
    return false;
  }
  controller_->release(queue[index]);
  queue.erase(queue.begin() + static_cast<std::ptrdiff_t>(index));
  return true;
}
void Plan::clear() {
  for (auto instance : controller_->queue_) controller_->release(instance);
  controller_->queue_.clear();
}
std::string_view Plan::peek(std::size_t index) const {
  const auto& queue = controller_->queue_;
  if (index >= queue.size()) return {};
  return controller_->states_[controller_->instances_[queue[index]].state].name;
}
std::size_t Plan::size() const {
  return controller_->queue_.size();
}
bool Plan::contains(std::string_view state) const {
  for (auto instance : controller_->queue_) {
    if (controller_->states_[controller_->instances_[instance].state].name == state) return true;
  }
  return false;
}
void Plan::terminate() {
  controller_->terminate_ = true;
  const auto by = controller_->callback_;
  controller_->terminated_by_ = by == kNoIndex ? kNoState : controller_->instances_[by].state;
}

// --- StateContext --------------------------------------------------------------------------------

StateContext::StateContext(const StepContext& step, ExecuteContext* execute, Controller& controller,
                           std::uint32_t instance)
    : StepContext(step),
      execute_(execute),
      controller_(&controller),
      instance_(instance),
      plan_(controller) {
  if (controller.report_base_ != kNoIndex && instance < controller.instances_.size()) {
    self_ = controller.report_base_ + controller.instances_[instance].state;
  }
}

std::uint64_t StateContext::cycle() const {
  return controller_->cycle_;
}
std::uint64_t StateContext::executions() const {
  return controller_->instances_[instance_].executions;
}
const ParamValue* StateContext::param_value(std::uint32_t index) const {
  const auto& of = controller_->instances_[instance_];
  return index < of.own_values.size() ? of.values[index] : nullptr;
}
Controller* StateContext::child() const {
  const auto state = controller_->instances_[instance_].state;
  const auto child = controller_->states_[state].child;
  return child == kNoController ? nullptr : controller_->children_[child];
}

// --- Controller ----------------------------------------------------------------------------------

Controller::Controller(std::string name, SourceLocation location, std::size_t capacity)
    : name_(std::move(name)), location_(std::move(location)), capacity_(capacity) {
  queue_.reserve(capacity_);
}

std::optional<std::uint32_t> find_state(const Controller& controller, std::string_view name) {
  const auto& states = controller.states();
  for (std::uint32_t s = 0; s < states.size(); ++s) {
    if (states[s].name == name) return s;
  }
  return std::nullopt;
}

void index_params(const ClassInfo& cls, PlannedState& planned) {
  planned.param_index.clear();
  for (const auto& param : planned.params) {
    std::uint32_t index = 0;
    while (index < cls.params.size() && cls.params[index].name != param.name) ++index;
    planned.param_index.push_back(index);
  }
}

void ControllerBuilder::index_state_values() {
  c_.state_values_.assign(c_.states_.size(), {});
  for (std::uint32_t s = 0; s < c_.states_.size(); ++s) {
    const auto& state = c_.states_[s];
    auto& values = c_.state_values_[s];
    for (const auto& spec : state.cls->params) {
      const ParamValue* value = spec.default_value ? &*spec.default_value : nullptr;
      for (const auto& param : state.params) {
        if (param.name == spec.name) value = &param.value;
      }
      values.push_back(value);
    }
  }
  // A state whose every required param has a value of its own needs no check per planning.
  c_.check_required_.assign(c_.states_.size(), 0);
  for (std::uint32_t s = 0; s < c_.states_.size(); ++s) {
    const auto& specs = c_.states_[s].cls->params;
    for (std::size_t p = 0; p < specs.size(); ++p) {
      if (specs[p].required() && c_.state_values_[s][p] == nullptr) c_.check_required_[s] = 1;
    }
  }
}

std::string_view Controller::current_state() const {
  return current_ == kNoIndex ? std::string_view{} : states_[instances_[current_].state].name;
}

std::string_view Controller::queued(std::size_t index) const {
  return index < queue_.size() ? std::string_view(states_[instances_[queue_[index]].state].name)
                               : std::string_view{};
}

void Controller::fail(std::string message) {
  if (status_ == ControllerStatus::kError) return;
  status_ = ControllerStatus::kError;
  std::string where = fmt::format("controller '{}' ({})", name_, to_string(location_));
  if (current_ != kNoIndex) {
    const auto& state = states_[instances_[current_].state];
    where += fmt::format(", state '{}' ({})", state.name, to_string(state.location));
  }
  error_ = fmt::format("{}: {}", where, message);
  if (logger_ != nullptr) {
    logger_->error("{}; the controller stops with status error", error_);
  } else {
    spdlog::error("{}; the controller stops with status error", error_);
  }
}

namespace {

// Converts a run-time argument to the param's kind; empty string when it fits.
std::string convert_arg(const ParamSpec& spec, const ArgValue& value, ParamValue& out) {
  const auto in_range = [&](double number) {
    return std::isfinite(number) && (!spec.minimum || number >= *spec.minimum) &&
           (!spec.maximum || number <= *spec.maximum);
  };
  switch (spec.kind) {
    case ParamKind::kBool:
      if (const bool* flag = std::get_if<bool>(&value)) {
        out = *flag;
        return {};
      }
      return "a boolean";
    case ParamKind::kInt:
      if (const auto* number = std::get_if<std::int64_t>(&value)) {
        if (!in_range(static_cast<double>(*number))) return "an integer in range";
        out = *number;
        return {};
      }
      return "an integer";
    case ParamKind::kDouble: {
      double number = 0.0;
      if (const auto* real = std::get_if<double>(&value)) {
        number = *real;
      } else if (const auto* integer = std::get_if<std::int64_t>(&value)) {
        number = static_cast<double>(*integer);
      } else {
        return "a number";
      }
      if (!in_range(number)) return "a finite number in range";
      out = number;
      return {};
    }
    case ParamKind::kVec2:
      if (const auto* vec = std::get_if<Vec2>(&value)) {
        out = *vec;
        return {};
      }
      return "a vec2";
    case ParamKind::kVec3:
      if (const auto* vec = std::get_if<Vec3>(&value)) {
        out = *vec;
        return {};
      }
      return "a vec3";
    default:
      return fmt::format("a {} (not settable at run time)", to_string(spec.kind));
  }
}

}  // namespace

std::optional<std::uint32_t> Controller::create(std::uint32_t state, const PlannedState* planned,
                                                const detail::PlanArg* args, std::size_t count) {
  const auto& compiled = states_[state];
  // Ignoring them would run the state on other values than the caller gave.
  if (planned != nullptr && planned->param_index.size() != planned->params.size()) {
    fail(
        fmt::format("planned state '{}' has params not resolved at load; plan it through "
                    "StateInitContext::plan_state()",
                    compiled.name));
    return std::nullopt;
  }
  if (live_ >= capacity_ || pools_[state].empty()) {
    fail(
        fmt::format("planning state '{}' exceeds the controller's capacity of {} instances "
                    "(the current state and the queue); raise 'capacity:'",
                    compiled.name, capacity_));
    return std::nullopt;
  }
  const std::uint32_t instance = pools_[state].back();
  pools_[state].pop_back();
  ++live_;
  Instance& created = instances_[instance];
  created.planned = planned == nullptr ? nullptr : &planned->params;
  created.args.clear();
  created.executions = 0;
  // Most plans name a state without params of their own: the instance reads the state's table.
  const bool own = count > 0 || (planned != nullptr && !planned->params.empty());
  created.values = own ? created.own_values.data() : state_values_[state].data();
  if (own) {
    std::copy(state_values_[state].begin(), state_values_[state].end(), created.own_values.begin());
    if (planned != nullptr) {
      for (std::size_t i = 0; i < planned->params.size(); ++i) {
        if (planned->param_index[i] < created.own_values.size()) {
          created.own_values[planned->param_index[i]] = &planned->params[i].value;
        }
      }
    }
  }
  const auto& specs = compiled.cls->params;
  for (std::size_t a = 0; a < count; ++a) {
    const std::uint32_t param = args[a].param;
    ParamValue value;
    if (auto expected = convert_arg(specs[param], args[a].value, value); !expected.empty()) {
      fail(fmt::format("param '{}' of state '{}' must be {}", specs[param].name, compiled.name,
                       expected));
      release(instance);
      return std::nullopt;
    }
    created.args.emplace_back(param, std::move(value));
  }
  // Pointers into args only once it is complete: it is reserved to the class's param count, and
  // load checks that the slots of a handle name distinct params.
  for (const auto& [param, value] : created.args) created.own_values[param] = &value;
  for (std::uint32_t p = 0; check_required_[state] != 0 && p < specs.size(); ++p) {
    if (specs[p].required() && created.values[p] == nullptr) {
      fail(fmt::format("state '{}' ({}) planned without its required param '{}'", compiled.name,
                       compiled.cls->name, specs[p].name));
      release(instance);
      return std::nullopt;
    }
  }
  return instance;
}

bool Controller::insert(std::size_t index, std::optional<std::uint32_t> instance) {
  if (!instance) return false;
  if (index > queue_.size()) {
    fail(fmt::format("plan insertion at index {} of a queue of {} states", index, queue_.size()));
    release(*instance);
    return false;
  }
  queue_.insert(queue_.begin() + static_cast<std::ptrdiff_t>(index), *instance);
  return true;
}

void Controller::release(std::uint32_t instance) {
  pools_[instances_[instance].state].push_back(instance);
  --live_;
}

void Controller::reset_queue() {
  if (current_ != kNoIndex) release(current_);
  current_ = kNoIndex;
  for (auto instance : queue_) release(instance);
  queue_.clear();
  status_ = ControllerStatus::kRunning;
  error_.clear();
  cycle_ = 0;
  proceed_ = false;
  terminate_ = false;
  went_to_ = kNoState;
  terminated_by_ = kNoState;
  for (const auto& planned : initial_) {
    insert(queue_.size(), create(planned.state, &planned, nullptr, 0));
  }
}

void Controller::note_go_to() {
  // Only the current state's own go_to tells why it ends; a hook's is a pre-emption.
  if (callback_ == kNoIndex || callback_ != current_ || queue_.empty()) return;
  went_to_ = instances_[queue_.front()].state;
}

namespace {

// Run-time args hold only the kinds convert_arg() produces.
ArgValue arg_value(const ParamValue& value) {
  if (const auto* flag = std::get_if<bool>(&value)) return *flag;
  if (const auto* integer = std::get_if<std::int64_t>(&value)) return *integer;
  if (const auto* vec = std::get_if<Vec2>(&value)) return *vec;
  if (const auto* vec = std::get_if<Vec3>(&value)) return *vec;
  if (const auto* real = std::get_if<double>(&value)) return *real;
  return false;
}

}  // namespace

void Controller::record(const StepContext& context, Event::Kind kind, std::uint32_t instance,
                        const Ending* ending) {
  const std::uint32_t sequence = next_sequence(context);
  if (event_count_ >= kMaxEventsPerStep) {
    ++event_count_;
    return;
  }
  const Instance& of = instances_[instance];
  Event& event = events_[event_count_++];
  event.kind = kind;
  event.state = of.state;
  event.sequence = sequence;
  if (ending != nullptr) {
    event.cause = ending->cause;
    event.proceeded = ending->proceeded;
    event.other = ending->other;
    event.preempt = ending->preempt;
  }
  event.planned = of.planned;
  event.args_begin = static_cast<std::uint32_t>(event_args_used_);
  event.args_count = 0;
  if (of.args.empty()) return;
  for (const auto& [param, value] : of.args) {
    if (event_args_used_ == event_args_.size()) break;
    event_args_[event_args_used_++] = {param, arg_value(value)};
  }
  event.args_count = static_cast<std::uint32_t>(event_args_used_) - event.args_begin;
}

void Controller::deactivate_current(StateContext& context, const Ending& ending) {
  record(context, Event::Kind::kDeactivate, current_, &ending);
  in_callback(current_, [&] { instances_[current_].object->deactivate(context); });
  release(current_);
  current_ = kNoIndex;
}

Controller::Ending Controller::stop_ending() const {
  if (status_ != ControllerStatus::kRunning) return {EndCause::kError};
  return {EndCause::kTerminated, false, terminated_by_};
}

void Controller::finish() {
  if (status_ == ControllerStatus::kRunning) status_ = ControllerStatus::kFinished;
  for (auto instance : queue_) release(instance);
  queue_.clear();
  if (hooks_ != nullptr) hooks_->on_terminate(*this);
}

void Controller::restart(const StepContext& context) {
  if (stepping_) {
    fail("restarted from inside its own callback");
    return;
  }
  if (current_ != kNoIndex) {
    StateContext state_context(context, nullptr, *this, current_);
    deactivate_current(state_context, {EndCause::kRestarted});
  }
  reset_queue();
}

void Controller::step(const StepContext& context, ExecuteContext* execute) {
  if (stepping_) {
    fail(
        "stepped from inside its own callback; a controller is stepped once per step, by its "
        "owner");
    return;
  }
  if (status_ != ControllerStatus::kRunning) return;
  stepping_ = true;
  ++cycle_;
  try {
    Plan plan(*this);
    bool leave = proceed_ || current_ == kNoIndex;
    Ending ending;
    for (std::uint32_t p = 0; p < preemptions_.size(); ++p) {
      if (preemptions_[p].cycle == cycle_ && plan.go_to(preemptions_[p].go_to)) {
        leave = true;
        ending.cause = EndCause::kPreempted;
        ending.preempt = p;
      }
    }
    if (hooks_ != nullptr && hooks_->pre_step(*this, plan)) {
      leave = true;
      ending.cause = EndCause::kPreempted;
      ending.preempt = kNoIndex;
    }
    if (status_ != ControllerStatus::kRunning) {
      stepping_ = false;
      return;
    }
    if (leave) {
      if (current_ != kNoIndex) {
        // A pre-emption tells the story even of a state that had asked to proceed: it decided
        // what follows.
        if (ending.cause == EndCause::kPreempted) {
          ending.proceeded = proceed_;
          ending.other = queue_.empty() ? kNoState : instances_[queue_.front()].state;
        } else if (queue_.empty()) {
          ending.cause = EndCause::kQueueEmpty;
        } else if (went_to_ != kNoState) {
          ending = {EndCause::kGoTo, false, went_to_};
        } else {
          ending.cause = EndCause::kProceeded;
        }
        StateContext old_context(context, execute, *this, current_);
        deactivate_current(old_context, ending);
      }
      proceed_ = false;
      if (queue_.empty()) {
        finish();
        stepping_ = false;
        return;
      }
      current_ = queue_.front();
      queue_.erase(queue_.begin());
      went_to_ = kNoState;
      const auto& name = states_[instances_[current_].state].name;
      if (hooks_ != nullptr) hooks_->pre_activate(*this, name);
      StateContext activate_context(context, execute, *this, current_);
      record(context, Event::Kind::kActivate, current_, nullptr);
      in_callback(current_, [&] { instances_[current_].object->activate(activate_context); });
    }
    if (terminate_ || status_ != ControllerStatus::kRunning) {
      if (current_ != kNoIndex) {
        StateContext end_context(context, execute, *this, current_);
        deactivate_current(end_context, stop_ending());
      }
      finish();
      stepping_ = false;
      return;
    }
    const auto& name = states_[instances_[current_].state].name;
    if (hooks_ != nullptr) hooks_->pre_execute(*this, name);
    StateContext execute_context(context, execute, *this, current_);
    record_execute(context, current_);
    StateResult result = in_callback(
        current_, [&] { return instances_[current_].object->execute(execute_context); });
    ++instances_[current_].executions;
    if (hooks_ != nullptr && hooks_->post_execute(*this, name, result)) {
      result = StateResult::kProceed;
    }
    if (terminate_ || status_ != ControllerStatus::kRunning) {
      deactivate_current(execute_context, stop_ending());
      finish();
      stepping_ = false;
      return;
    }
    proceed_ = result == StateResult::kProceed;
    if (hooks_ != nullptr) hooks_->post_step(*this);
  } catch (const std::exception& error) {
    fail(fmt::format("a state threw: {}", error.what()));
  } catch (...) {
    fail("a state threw an unknown exception");
  }
  stepping_ = false;
}

namespace {

bool same_node(const Node& a, const Node& b) {
  if (a.kind() != b.kind() || a.text() != b.text() || a.quoted() != b.quoted() ||
      a.items().size() != b.items().size() || a.entries().size() != b.entries().size()) {
    return false;
  }
  for (std::size_t i = 0; i < a.items().size(); ++i) {
    if (!same_node(a.items()[i], b.items()[i])) return false;
  }
  for (std::size_t i = 0; i < a.entries().size(); ++i) {
    if (a.entries()[i].key != b.entries()[i].key ||
        !same_node(a.entries()[i].value, b.entries()[i].value)) {
      return false;
    }
  }
  return true;
}

bool same_value(const ParamValue& a, const ParamValue& b) {
  if (a.index() != b.index()) return false;
  if (const auto* node = std::get_if<Node>(&a)) return same_node(*node, std::get<Node>(b));
  return std::visit(
      [&](const auto& value) {
        using T = std::decay_t<decltype(value)>;
        if constexpr (std::is_same_v<T, Node>) {
          return false;  // handled above
        } else {
          return value == std::get<T>(b);
        }
      },
      a);
}

}  // namespace

bool same_params(const std::vector<Param>& a, const std::vector<Param>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].name != b[i].name || !same_value(a[i].value, b[i].value)) return false;
  }
  return true;
}

bool Controller::same_declaration(const Controller& other) const {
  const auto child_name = [](const Controller& controller, std::uint32_t state) {
    const Controller* child = controller.child_of(state);
    return child == nullptr ? std::string() : child->name();
  };
  if (capacity_ != other.capacity_ || states_.size() != other.states_.size() ||
      initial_.size() != other.initial_.size() ||
      preemptions_.size() != other.preemptions_.size()) {
    return false;
  }
  for (std::uint32_t s = 0; s < states_.size(); ++s) {
    const auto& mine = states_[s];
    const auto& theirs = other.states_[s];
    if (mine.name != theirs.name || mine.cls != theirs.cls ||
        !same_params(mine.params, theirs.params) || child_name(*this, s) != child_name(other, s)) {
      return false;
    }
  }
  for (std::size_t i = 0; i < initial_.size(); ++i) {
    if (initial_[i].state != other.initial_[i].state ||
        !same_params(initial_[i].params, other.initial_[i].params)) {
      return false;
    }
  }
  for (std::size_t i = 0; i < preemptions_.size(); ++i) {
    const auto& mine = preemptions_[i];
    const auto& theirs = other.preemptions_[i];
    if (mine.cycle != theirs.cycle || mine.go_to.state != theirs.go_to.state ||
        !same_params(mine.go_to.params, theirs.go_to.params)) {
      return false;
    }
  }
  return true;
}

void Controller::end(const StepContext& context) {
  if (stepping_ || current_ == kNoIndex) return;
  StateContext state_context(context, nullptr, *this, current_);
  try {
    deactivate_current(state_context, {EndCause::kDropped});
  } catch (...) {
    // The controller is being dropped: there is nothing left for its error status to stop.
  }
}

}  // namespace arbiter
