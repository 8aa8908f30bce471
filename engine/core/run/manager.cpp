#include "arbiter/manager.hpp"

#include "core/compile/controller_builder.hpp"
#include "core/run/carryover.hpp"
#include "core/run/code_placement.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>
#include <typeinfo>

namespace arbiter {

namespace {

// Stands in for a behaviour that is inactive because its code threw (docs/robustness.md).
class Inert final : public Behaviour {
 public:
  double activation(const StepContext&) override { return 0.0; }
};

bool is_finite(const void* value, std::uint8_t components) {
  switch (components) {
    case 1:
      return std::isfinite(*static_cast<const double*>(value));
    case 2: {
      const auto& v = *static_cast<const Vec2*>(value);
      return std::isfinite(v.x) && std::isfinite(v.y);
    }
    case 3: {
      const auto& v = *static_cast<const Vec3*>(value);
      return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
    }
    default:
      return true;
  }
}

}  // namespace

// GCC guesses that a virtual call goes to the one override it sees in this file (Inert) and
// moves the real call out of line behind a comparison: for activation() that costs ~5 % of a
// step (callgrind), while the same guess for update() (the base's no-op) saves the call.
#if defined(__GNUC__) && !defined(__clang__)
#define ARBITER_NO_SPECULATIVE_DEVIRTUALIZATION \
  __attribute__((optimize("no-devirtualize-speculatively")))
#else
#define ARBITER_NO_SPECULATIVE_DEVIRTUALIZATION
#endif

// Runs one callback of behaviour code; an exception stops at the step boundary.
// `index` is captured by value: a loop counter captured by reference would live on the stack.
#define ARBITER_GUARDED(index, callback, statement)                   \
  [&, guarded_index = static_cast<std::uint32_t>(index)]() -> bool {  \
    try {                                                             \
      statement;                                                      \
      return true;                                                    \
    } catch (const std::exception& error) {                           \
      report_exception(guarded_index, callback, error.what());        \
    } catch (...) {                                                   \
      report_exception(guarded_index, callback, "unknown exception"); \
    }                                                                 \
    return false;                                                     \
  }()

// What stage() prepares for a swap: the program, its run state and the carry-over from the
// running program. After the swap it holds what was replaced.
struct Manager::Staged {
  std::uint64_t stage = 0;  // Observer::on_staged()'s number
  Program program;
  RunState state;
  detail::Carryover carryover;
  // Scratch for the swap, per running behaviour, layer and controller: which go on in the new
  // program (kept, or taken over by carry_over()); and per new behaviour and layer, which took
  // over.
  std::vector<char> behaviour_continues;
  std::vector<char> interface_continues;
  std::vector<char> controller_continues;
  std::vector<char> took_over;
};

struct Manager::Reloading {
  std::mutex mutex;  // step() only ever try_locks it
  std::atomic<bool> has_pending{false};
  std::unique_ptr<Staged> pending;
  std::unique_ptr<Staged> retired;
  std::atomic<std::uint64_t> reloads{0};
  std::uint64_t stages = 0;  // by the staging thread
  /// False from a swap until the observers' on_reload() returned: until then they may still read
  /// what the swap replaced, so `retired` is not freed (and after, not before on_retiring()).
  std::atomic<bool> observed{true};

  /// The lock, taken once the last swap's observers are done with the program it replaced.
  std::unique_lock<std::mutex> lock_when_observed() {
    for (;;) {
      std::unique_lock<std::mutex> lock(mutex);
      if (observed.load(std::memory_order_acquire)) return lock;
      lock.unlock();
      std::this_thread::yield();
    }
  }
};

Manager::Manager(Program program, std::shared_ptr<spdlog::logger> logger)
    : reloading_(std::make_unique<Reloading>()),
      logger_(logger ? std::move(logger) : spdlog::default_logger()) {
  inert_ = std::make_unique<Inert>();
  events_.resize(kEventsPerStep);
  data_.events = events_.data();
  data_.event_capacity = events_.size();
  report_text_.resize(kEventsPerStep * detail::kReportBytes);
  data_.report_text = report_text_.data();
  scene_primitives_.resize(kScenePrimitivesPerStep);
  scene_points_.resize(kScenePointsPerStep);
  data_.scene.primitives = scene_primitives_.data();
  data_.scene.primitive_capacity = scene_primitives_.size();
  data_.scene.points = scene_points_.data();
  data_.scene.point_capacity = scene_points_.size();
  scene_strings_.resize(kSceneStringBytesPerStep);
  data_.scene.strings = scene_strings_.data();
  data_.scene.string_capacity = scene_strings_.size();
  scene_frames_.resize(kScenePrimitivesPerStep);  // a frame is drawn in by a primitive at least
  data_.scene.frames = scene_frames_.data();
  data_.scene.frame_capacity = scene_frames_.size();
  data_.step = 0;
  const auto first = prepare(std::move(program), detail::Carryover{});
  swap_in(*first);
}

Manager::Manager(Manager&&) noexcept = default;
// Observers are not called here (no on_retiring()): many are gone by now. A recorder is finished
// before, its writer joined (Recorder), so none reads what a swap replaced.
Manager::~Manager() = default;

std::unique_ptr<Manager::Staged> Manager::prepare(Program program,
                                                  detail::Carryover carryover) const {
  auto staged = std::make_unique<Staged>();
  staged->state = RunState(program);
  // Each state's reports carry a source of their own, after every behaviour and layer.
  auto source = static_cast<std::uint32_t>(program.behaviours.size() + program.layers.size());
  for (const auto& controller : program.controllers) {
    controller->set_logger(logger_.get());
    ControllerBuilder(*controller).set_report_base(source);
    source += static_cast<std::uint32_t>(controller->states().size());
  }
  staged->behaviour_continues.assign(program_.behaviours.size(), 0);
  staged->interface_continues.assign(program_.layers.size(), 0);
  staged->controller_continues.assign(program_.controllers.size(), 0);
  staged->took_over.assign(program.behaviours.size() + program.layers.size(), 0);
  staged->program = std::move(program);
  staged->carryover = std::move(carryover);
  return staged;
}

// Exchanges the running program and its run state with `staged`'s; allocates nothing.
void Manager::swap_in(Staged& staged) noexcept {
  std::swap(program_, staged.program);
  std::swap(run_, staged.state);
  point_step_data();
}

void Manager::point_step_data() noexcept {
  data_.values = run_.values;
  data_.actuator_offset = program_.actuator_offsets.data();
  data_.actuator_written = run_.actuator_written;
  data_.slot_offset = program_.slot_offsets.data();
  data_.slot_type = program_.slot_types.data();
  data_.slot_written = run_.slot_written.get();
  data_.period = 1.0 / program_.rate_hz;
}

void Manager::stage(Program program, detail::Carryover carryover) {
  // A carry-over that does not fit would index out of bounds inside step(): refuse it here.
  const auto fits = [](const auto& from, std::size_t size, std::size_t limit) {
    return from.size() == size && std::all_of(from.begin(), from.end(), [&](std::uint32_t index) {
             return index == detail::kNoMatch || index < limit;
           });
  };
  if (!fits(carryover.behaviour_from, program.behaviours.size(), program_.behaviours.size()) ||
      carryover.behaviour_kept.size() != program.behaviours.size() ||
      !fits(carryover.actuator_from, program.actuators.size(), program_.actuators.size()) ||
      !fits(carryover.interface_from, program.layers.size(), program_.layers.size()) ||
      carryover.interface_kept.size() != program.layers.size() ||
      !fits(carryover.controller_kept, program.controllers.size(), program_.controllers.size())) {
    throw std::invalid_argument(
        "Manager::stage: the carry-over does not fit the programs (build it with Reloader)");
  }
  auto staged = prepare(std::move(program), std::move(carryover));
  staged->stage = ++reloading_->stages;
  for (Observer* observer : observers_) observer->on_staged(staged->program, staged->stage);
  std::unique_ptr<Staged> dropped;
  std::unique_ptr<Staged> retired;
  {
    const auto lock = reloading_->lock_when_observed();
    dropped = std::move(reloading_->pending);
    retired = std::move(reloading_->retired);
    reloading_->pending = std::move(staged);
    reloading_->has_pending.store(true, std::memory_order_release);
  }
  retire(retired.get());
  // Destroyed here, outside the lock and off the step path.
}

void Manager::retire(const Staged* retired) const {
  if (retired == nullptr) return;
  for (Observer* observer : observers_) observer->on_retiring(retired->program);
}

bool Manager::withdraw() {
  std::unique_ptr<Staged> dropped;
  std::unique_ptr<Staged> retired;
  {
    const auto lock = reloading_->lock_when_observed();
    dropped = std::move(reloading_->pending);
    retired = std::move(reloading_->retired);
    reloading_->has_pending.store(false, std::memory_order_relaxed);
  }
  retire(retired.get());
  return dropped != nullptr;
}

std::uint64_t Manager::reloads() const {
  return reloading_->reloads.load(std::memory_order_relaxed);
}

// The swap, at the start of a step: the running program's parts that do not go on get their
// final call while its buffers are still in place; then everything is exchanged and what goes
// on is carried over. Every buffer was sized by prepare(): nothing here allocates.
void Manager::apply(Staged& staged) {
  const detail::Carryover& carryover = staged.carryover;
  Program& next = staged.program;
  for (std::uint32_t b = 0; b < next.behaviours.size(); ++b) {
    const std::uint32_t from = carryover.behaviour_from[b];
    if (from == detail::kNoMatch) continue;
    if (carryover.behaviour_kept[b] != 0) {
      staged.behaviour_continues[from] = 1;
      continue;
    }
    Behaviour& previous = *program_.behaviours[from].instance;
    bool took = false;
    ARBITER_GUARDED(from, Callback::kCarryOver,
                    took = next.behaviours[b].instance->carry_over(previous));
    staged.took_over[b] = took ? 1 : 0;
    staged.behaviour_continues[from] = took ? 1 : 0;
  }
  const auto behaviours = static_cast<std::uint32_t>(next.behaviours.size());
  for (std::uint32_t l = 0; l < next.layers.size(); ++l) {
    const std::uint32_t from = carryover.interface_from[l];
    if (from == detail::kNoMatch) continue;
    if (carryover.interface_kept[l] != 0) {
      staged.interface_continues[from] = 1;
      continue;
    }
    Interface& previous = *program_.layers[from].interface;
    bool took = false;
    ARBITER_GUARDED(program_.behaviours.size() + from, Callback::kCarryOver,
                    took = next.layers[l].interface->carry_over(previous));
    staged.took_over[behaviours + l] = took ? 1 : 0;
    staged.interface_continues[from] = took ? 1 : 0;
  }
  for (const auto from : carryover.controller_kept) {
    if (from != detail::kNoMatch) staged.controller_continues[from] = 1;
  }
  end_replaced(staged);

  swap_in(staged);
  // From here on `staged` holds the replaced program and its buffers.
  carry_values(staged);
  for (std::uint32_t b = 0; b < program_.behaviours.size(); ++b) {
    const std::uint32_t from = carryover.behaviour_from[b];
    if (from == detail::kNoMatch) continue;
    if (carryover.behaviour_kept[b] != 0) {
      std::swap(program_.behaviours[b].instance, staged.program.behaviours[from].instance);
      run_.instances[b] = program_.behaviours[b].instance.get();
    } else if (staged.took_over[b] == 0) {
      continue;
    }
    run_.active[b] = staged.state.active[from];
    run_.requested[b] = staged.state.requested[from];
    run_.activation[b] = staged.state.activation[from];
    run_.nan_reported[b] = staged.state.nan_reported[from];
  }
  for (std::uint32_t l = 0; l < program_.layers.size(); ++l) {
    const std::uint32_t from = carryover.interface_from[l];
    if (from != detail::kNoMatch && carryover.interface_kept[l] != 0) {
      std::swap(program_.layers[l].interface, staged.program.layers[from].interface);
    }
  }
  for (std::uint32_t c = 0; c < program_.controllers.size(); ++c) {
    const std::uint32_t from = carryover.controller_kept[c];
    if (from != detail::kNoMatch)
      std::swap(program_.controllers[c], staged.program.controllers[from]);
  }
}

// Final calls for what the swap drops: inhibited() for behaviours, deactivation of the current
// state of controllers, against the running program's buffers.
void Manager::end_replaced(Staged& staged) {
  for (std::uint32_t b = 0; b < program_.behaviours.size(); ++b) {
    if (staged.behaviour_continues[b] != 0 || run_.disabled[b] != 0) continue;
    const InhibitedContext context(data_, b, run_.active[b] != 0);
    ARBITER_GUARDED(b, Callback::kInhibited, program_.behaviours[b].instance->inhibited(context));
  }
  const StepContext context(data_, kNoBehaviour);
  for (std::uint32_t c = 0; c < program_.controllers.size(); ++c) {
    if (staged.controller_continues[c] == 0) program_.controllers[c]->end(context);
  }
}

// Actuators that go on keep their value and written flag (docs/semantics.md, "Persistence").
void Manager::carry_values(const Staged& staged) {
  for (std::uint32_t a = 0; a < program_.actuators.size(); ++a) {
    const std::uint32_t from = staged.carryover.actuator_from[a];
    if (from == detail::kNoMatch) continue;
    program_.actuators[a].type->assign(run_.values + program_.actuators[a].offset,
                                       staged.state.values + staged.program.actuators[from].offset);
    run_.actuator_written[a] = staged.state.actuator_written[from];
  }
}

const std::string& Manager::event_source(const detail::StepData::Event& event) const {
  static const std::string kStandalone = "state machines";
  static const std::string kBreak = "break";
  if (event.source == kNoBehaviour) return kStandalone;
  if (event.source == kBreakSource) return kBreak;
  if (event.source < program_.behaviours.size()) return program_.behaviours[event.source].name;
  if (event.source - program_.behaviours.size() < program_.layers.size()) {
    return program_.layers[event.source - program_.behaviours.size()].name;
  }
  for (const auto& controller : program_.controllers) {
    if (const std::string* name = controller->report_source(event.source)) return *name;
  }
  return kStandalone;
}

void Manager::add_observer(Observer& observer) {
  observers_.push_back(&observer);
  observer.on_start(*this);
}

void Manager::remove_observer(Observer& observer) {
  observers_.erase(std::remove(observers_.begin(), observers_.end(), &observer), observers_.end());
}

void Manager::finish() {
  safe_pass();
  for (Observer* observer : observers_) observer->on_finish(*this);
}

void Manager::safe_pass() {
  const bool any_safe = std::any_of(run_.safe_values.begin(), run_.safe_values.end(),
                                    [](const ValueBox& box) { return box.data() != nullptr; });
  if (data_.step == 0 || !any_safe) return;
  if (clock_ != nullptr) step_time_ = clock_->now();
  for (std::uint32_t a = 0; a < program_.actuators.size(); ++a) {
    const bool safe = run_.safe_values[a].data() != nullptr;
    if (safe) {
      program_.actuators[a].type->assign(run_.values + program_.actuators[a].offset,
                                         run_.safe_values[a].data());
    }
    run_.actuator_written[a] = safe;
  }
  data_.event_count = 0;
  data_.sequence = 0;
  clear_scene();
  input_pass_events_ = 0;  // the safe pass has only an output pass
  for (const auto& controller : program_.controllers) controller->clear_events();
  for (const auto& layer : program_.layers) {
    if (!layer.is_interface()) continue;
    const auto index =
        static_cast<std::uint32_t>(program_.behaviours.size() + (&layer - program_.layers.data()));
    const StepContext context(data_, index);
    if (run_.disabled[index] == 0)
      ARBITER_GUARDED(index, Callback::kOutput, layer.interface->output(context));
  }
  if (clock_ != nullptr) step_duration_ = clock_->now() - step_time_;
  ++safe_passes_;
  in_safe_pass_ = true;
  for (Observer* observer : observers_) observer->on_safe(*this);
  in_safe_pass_ = false;
}

const char* Manager::name(Callback callback) {
  switch (callback) {
    case Callback::kUpdate:
      return "update";
    case Callback::kActivation:
      return "activation";
    case Callback::kExecute:
      return "execute";
    case Callback::kInhibited:
      return "inhibited";
    case Callback::kInput:
      return "input";
    case Callback::kOutput:
      return "output";
    case Callback::kCarryOver:
      return "carry_over";
  }
  return "?";
}

// Called from ARBITER_GUARDED's handlers: reports the exception once and applies the thrower's
// on_exception policy. Every policy drops the thrower's writes of this step (resolve_actuators
// skips a writer whose run_.faulted_step is this step).
void Manager::report_exception(std::uint32_t index, Callback callback, const char* what) {
  const bool is_behaviour = index < program_.behaviours.size();
  const FaultPolicy policy =
      is_behaviour ? program_.behaviours[index].on_exception : program_.on_exception;
  run_.faulted_step[index] = data_.step;
  if (is_behaviour && run_.instances[index] != inert_.get()) {
    // A throw from update() leaves nothing to ask for a level: the behaviour sits out the
    // rest of the step (and, when disabled, the rest of the run).
    if (policy == FaultPolicy::kDisable) {
      run_.instances[index] = inert_.get();
    } else if (callback == Callback::kUpdate) {
      run_.instances[index] = inert_.get();
      run_.suspended.push_back(index);
    }
  }
  if (policy == FaultPolicy::kDisable) run_.disabled[index] = 1;
  // Formatting allocates: a behaviour that throws in every step is described once (and once more
  // for the stop reason), not in every step.
  const bool sets_stop_reason = policy == FaultPolicy::kStop && !stopping_;
  if (run_.exception_reported[index] != 0 && !sets_stop_reason) return;
  const char* outcome =
      "it counts as inactive in each step where it throws (on_exception: "
      "inactive; reported once)";
  if (policy == FaultPolicy::kDisable) {
    outcome = "it is disabled for the rest of the run (on_exception: disable)";
  } else if (policy == FaultPolicy::kStop) {
    outcome = "the manager stops after this step (on_exception: stop)";
  }
  std::string message;
  if (is_behaviour) {
    const auto& behaviour = program_.behaviours[index];
    message = fmt::format("{}: behaviour '{}' ({}) threw from {}() in step {}: {}",
                          to_string(behaviour.location), behaviour.name, behaviour.cls->name,
                          name(callback), data_.step, what);
  } else {
    const auto& layer = program_.layers[index - program_.behaviours.size()];
    message = fmt::format("{}: interface of layer '{}' ({}) threw from {}() in step {}: {}",
                          to_string(layer.location), layer.name, layer.interface_class->name,
                          name(callback), data_.step, what);
  }
  if (policy == FaultPolicy::kStop && !stopping_) {
    stopping_ = true;
    stop_reason_ = message;
  }
  if (run_.exception_reported[index] != 0) return;
  run_.exception_reported[index] = 1;
  logger_->error("{}; {}", message, outcome);
}

// End of a step: behaviours that sat out this step come back; a stop takes effect.
void Manager::finish_faults() {
  for (const std::uint32_t b : run_.suspended) {
    if (run_.disabled[b] == 0) run_.instances[b] = program_.behaviours[b].instance.get();
  }
  run_.suspended.clear();
  if (program_.on_exception == FaultPolicy::kStop && !stopping_) {
    // A state's exception stops its controller with status error (docs/semantics.md, "State
    // machines"); under `on_exception: stop` it stops the manager too.
    for (const auto& controller : program_.controllers) {
      if (controller->status() != ControllerStatus::kError) continue;
      stopping_ = true;
      stop_reason_ = fmt::format("state machine '{}' stopped with an error: {}", controller->name(),
                                 controller->error());
      logger_->error("{}; the manager stops after this step (on_exception: stop)", stop_reason_);
      break;
    }
  }
  if (stopping_) stopped_ = true;
}

void Manager::report_non_finite_write(std::uint32_t slot) {
  if (run_.non_finite_reported[slot] != 0) return;
  run_.non_finite_reported[slot] = 1;
  const WriterSlot& writer = program_.slots[slot];
  const CompiledActuator& actuator = program_.actuators[writer.actuator];
  const SourceLocation* where = &program_.layers[actuator.layer].location;
  std::string who =
      fmt::format("the interface of layer '{}'", program_.layers[actuator.layer].name);
  if (writer.owner != kNoBehaviour) {
    where = &program_.behaviours[writer.owner].location;
    who = fmt::format("behaviour '{}' ({})", program_.behaviours[writer.owner].name,
                      program_.behaviours[writer.owner].cls->name);
  }
  logger_->warn(
      "{}: {} wrote a non-finite value (NaN or infinity) to actuator '{}' in step {}; "
      "such writes are ignored (reported once)",
      to_string(*where), who, actuator.name, data_.step);
}

void Manager::step() {
  Reloading& reloading = *reloading_;
  if (reloading.has_pending.load(std::memory_order_acquire) && reloading.mutex.try_lock()) {
    // A swap the staging thread holds the lock for waits for the next step.
    std::unique_ptr<Staged> staged = std::move(reloading.pending);
    reloading.has_pending.store(false, std::memory_order_relaxed);
    const bool swapped = staged != nullptr;
    if (swapped) {
      apply(*staged);
      // stage() and withdraw() empty `retired` before a program can be pending, so nothing is
      // destroyed here: the replaced program waits for them.
      stage_number_ = staged->stage;
      reloading.retired = std::move(staged);
      reloading.reloads.fetch_add(1, std::memory_order_relaxed);
      reloading.observed.store(false, std::memory_order_relaxed);
    }
    reloading.mutex.unlock();
    if (swapped) {
      for (Observer* observer : observers_) observer->on_reload(*this);
      reloading.observed.store(true, std::memory_order_release);
    }
  }
  if (stopped_) return;
  if (clock_ != nullptr) step_time_ = clock_->now();
  ++data_.step;
  data_.event_count = 0;
  data_.sequence = 0;
  clear_scene();
  for (const auto& controller : program_.controllers) controller->clear_events();
  const auto interface_index = [&](const CompiledLayer& layer) {
    return static_cast<std::uint32_t>(program_.behaviours.size() +
                                      (&layer - program_.layers.data()));
  };

  for (const auto& layer : program_.layers) {
    if (!layer.is_interface()) continue;
    for (std::uint32_t a = layer.actuator_begin; a < layer.actuator_end; ++a) {
      for (auto s = program_.actuator_slot_begin[a]; s < program_.actuator_slot_begin[a + 1]; ++s) {
        run_.slot_written[program_.actuator_slots[s]] = false;
      }
    }
    WriteContext context(data_, interface_index(layer));
    if (run_.disabled[interface_index(layer)] == 0) {
      ARBITER_GUARDED(interface_index(layer), Callback::kInput, layer.interface->input(context));
    }
    resolve_actuators(layer);
  }
  input_pass_events_ = event_count();
  data_.scene.muted = input_pass_scene_only_;

  for (const auto& layer : program_.layers) {
    if (!layer.is_interface()) run_layer(layer);
  }

  for (const auto& layer : program_.layers) {
    if (!layer.is_interface()) continue;
    const StepContext context(data_, interface_index(layer));
    if (run_.disabled[interface_index(layer)] == 0) {
      ARBITER_GUARDED(interface_index(layer), Callback::kOutput, layer.interface->output(context));
    }
  }

  // Standalone controllers run after the output pass (docs/semantics.md, "State machines"); a
  // controller contains the exceptions of its states itself.
  const StepContext standalone(data_, kNoBehaviour);
  for (const auto& controller : program_.controllers) {
    if (!controller->owned()) controller->step(standalone);
  }
  finish_faults();
  if (clock_ != nullptr) step_duration_ = clock_->now() - step_time_;
  break_text_ = check_ != nullptr ? check_->check(*this) : nullptr;
  if (break_text_ != nullptr) {
    if (data_.event_count < data_.event_capacity) {
      events_[data_.event_count] = {kBreakSource, break_text_, data_.sequence};
    }
    ++data_.event_count;
    ++data_.sequence;
  }

  for (Observer* observer : observers_) observer->on_step(*this);
}

void Manager::run_layer(const CompiledLayer& layer) {
  const std::uint32_t begin = layer.behaviour_begin;
  const std::uint32_t end = layer.behaviour_end;
  // Sensors read actuators in place: an actuator of this or a later layer still holds last
  // step's value and written flag until resolve_actuators() below, the timing of docs/semantics.md,
  // "Timing: the one-step delay".
  for (std::uint32_t a = layer.actuator_begin; a < layer.actuator_end; ++a) {
    for (auto s = program_.actuator_slot_begin[a]; s < program_.actuator_slot_begin[a + 1]; ++s) {
      run_.slot_written[program_.actuator_slots[s]] = false;
    }
  }
  update_behaviours(begin, end);
  request_and_refine(begin, end);
  if (layer.normalise) {
    double sum = 0.0;
    for (std::uint32_t b = begin; b < end; ++b) sum += run_.activation[b];
    if (sum > 0.0) {
      for (std::uint32_t b = begin; b < end; ++b) run_.activation[b] /= sum;
    }
  }
  execute_behaviours(begin, end);
  resolve_actuators(layer);
}

// Each pass over a layer's behaviours is a function of its own (never inlined into one big
// one), so that its loop keeps its counters in registers across the calls into behaviour code.

ARBITER_OUT_OF_LINE void Manager::update_behaviours(std::uint32_t begin, std::uint32_t end) {
  for (std::uint32_t b = begin; b < end; ++b) {
    const StepContext context(data_, b);
    ARBITER_GUARDED(b, Callback::kUpdate, run_.instances[b]->update(context));
  }
}

// Queries each behaviour's level (docs/semantics.md, "A step") and refines it at once
// ("Refinement"): refinement reads only requested levels and the refined levels of behaviours
// earlier in the order, and no behaviour code sees a refined level before execute(), so the result
// is that of two passes. In one loop the products' latency overlaps the calls into behaviour code
// instead of adding to them. a[b] = r[b] * Π (1 - a[i]) over b's closed inhibitors is computed
// through b's recipe: the product Q[b] over its chained inhibitors from earlier behaviours' block
// products, then the rest.
ARBITER_NO_SPECULATIVE_DEVIRTUALIZATION ARBITER_OUT_OF_LINE void Manager::request_and_refine(
    std::uint32_t begin, std::uint32_t end) {
  const auto& recipes = program_.inhibitions.recipes();
  const std::uint32_t* recipe = recipes.begin.data();
  const std::uint32_t* split = recipes.split.data();
  const std::uint32_t* terms = recipes.terms.data();
  double* factor = run_.factors.data();
  for (std::uint32_t b = begin; b < end; ++b) {
    const StepContext context(data_, b);
    double level = 0.0;
    if (!ARBITER_GUARDED(b, Callback::kActivation, level = run_.instances[b]->activation(context)))
      level = 0.0;
    if (!std::isfinite(level)) level = non_finite_level(b, level);
    level = std::clamp(level, 0.0, 1.0);
    run_.requested[b] = level;

    // The first factor starts the product: a multiplication by 1.0 would lengthen a chain's
    // latency, which runs from behaviour to behaviour.
    double chained = 1.0;
    if (recipe[b] < split[b]) {
      chained = factor[terms[recipe[b]]];
      for (auto t = recipe[b] + 1; t < split[b]; ++t) chained *= factor[terms[t]];
    }
    level *= chained;
    for (auto t = split[b]; t < recipe[b + 1]; ++t) level *= factor[terms[t]];
    run_.activation[b] = level;
    factor[2 * b] = 1.0 - level;
    factor[2 * b + 1] = (1.0 - level) * chained;
  }
}

// NaN counts as 0, ±infinity is clamped; each reported once per behaviour.
double Manager::non_finite_level(std::uint32_t b, double level) {
  const double clamped = std::isnan(level) ? 0.0 : std::clamp(level, 0.0, 1.0);
  if (run_.nan_reported[b] != 0) return clamped;
  run_.nan_reported[b] = 1;
  const auto& where = program_.behaviours[b].location;
  logger_->warn(
      "{}: behaviour '{}' requested a{} activation level; it counts as {} (reported "
      "once)",
      to_string(where), program_.behaviours[b].name,
      std::isnan(level) ? " NaN"
      : level > 0       ? "n infinite"
                        : " negative infinite",
      clamped);
  return clamped;
}

ARBITER_OUT_OF_LINE void Manager::execute_behaviours(std::uint32_t begin, std::uint32_t end) {
  for (std::uint32_t b = begin; b < end; ++b) {
    Behaviour& behaviour = *run_.instances[b];
    const bool was_active = run_.active[b] != 0;
    const bool is_active = run_.activation[b] > 0.0;
    run_.active[b] = is_active ? 1 : 0;
    if (is_active) {
      ExecuteContext context(data_, b, run_.activation[b], !was_active);
      ARBITER_GUARDED(b, Callback::kExecute, behaviour.execute(context));
    } else {
      const InhibitedContext context(data_, b, was_active);
      ARBITER_GUARDED(b, Callback::kInhibited, behaviour.inhibited(context));
    }
  }
}

void Manager::resolve_actuators(const CompiledLayer& layer) {
  const auto interface =
      static_cast<std::uint32_t>(program_.behaviours.size() + (&layer - program_.layers.data()));
  for (std::uint32_t a = layer.actuator_begin; a < layer.actuator_end; ++a) {
    const CompiledActuator& actuator = program_.actuators[a];
    void* value = run_.values + actuator.offset;
    std::size_t count = 0;
    double best = 0.0;
    std::uint32_t winner = kNoBehaviour;
    for (auto s = program_.actuator_slot_begin[a]; s < program_.actuator_slot_begin[a + 1]; ++s) {
      const std::uint32_t slot = program_.actuator_slots[s];
      if (!run_.slot_written[slot]) continue;
      const std::uint32_t owner = program_.slots[slot].owner;
      const double weight = owner == kNoBehaviour ? 1.0 : run_.activation[owner];
      if (weight <= 0.0) continue;  // writes of inactive behaviours are ignored
      // Writes of a writer that threw this step, and non-finite numbers, are ignored too.
      if (run_.faulted_step[owner == kNoBehaviour ? interface : owner] == data_.step) continue;
      if (run_.finite_components[slot] != 0 &&
          !is_finite(run_.values + program_.slot_offsets[slot], run_.finite_components[slot])) {
        report_non_finite_write(slot);
        continue;
      }
      run_.mean_values[count] = run_.values + program_.slot_offsets[slot];
      run_.mean_weights[count] = weight;
      ++count;
      if (weight > best) {  // strictly greater: on a tie the earlier writer wins
        best = weight;
        winner = slot;
      }
    }
    run_.actuator_written[a] = count > 0;
    if (count == 0) continue;  // values persist
    if (actuator.aggregate) {
      actuator.type->mean(value, run_.mean_values.data(), run_.mean_weights.data(), count);
    } else {
      actuator.type->assign(value, run_.values + program_.slot_offsets[winner]);
    }
  }
}

}  // namespace arbiter
