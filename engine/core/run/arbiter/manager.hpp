#pragma once
// engine/core/run: a Program in; each step, activation levels, actuator values and state changes
// out, to the run's observers (trace, recording, views) and the interface layers' outside world.
//
// Stage 4 of the data path: the behaviour manager steps a compiled program. step() walks flat
// arrays sized at compile: it allocates nothing, looks up no name and lets no exception out.

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "arbiter/behaviour.hpp"
#include "arbiter/program.hpp"
#include "arbiter/run_state.hpp"

namespace spdlog {
class logger;
}

namespace arbiter {

class Manager;

/// Receives every step's outcome (trace writers, loggers, live views). Called after the step,
/// on the stepping thread; an observer may allocate, the step itself does not.
class Observer {
 public:
  virtual ~Observer() = default;
  virtual void on_start(const Manager& /*manager*/) {}
  virtual void on_step(const Manager& manager) = 0;
  /// After a hot reload swapped a new program in (between two steps, before the next on_step):
  /// behaviour, actuator and controller indices may all have changed, so anything an observer
  /// keyed by index must be rebuilt from manager.program().
  virtual void on_reload(const Manager& /*manager*/) {}
  /// On the thread that stages a hot reload (Manager::stage()), with the staged program, before
  /// a step can swap it in: what on_reload() will need can be prepared here, off the stepping
  /// thread. A later stage() may replace it before it is swapped in: `stage` numbers them, and
  /// Manager::stage_number() tells which one runs.
  virtual void on_staged(const Program& /*next*/, std::uint64_t /*stage*/) {}
  /// On the staging thread (Manager::stage() or withdraw()), before the program that the last
  /// swap replaced is freed: an observer that still reads it (a recorder's writer formatting its
  /// last steps) returns once it no longer does.
  virtual void on_retiring(const Program& /*replaced*/) {}
  virtual void on_finish(const Manager& /*manager*/) {}
  /// After the safe-value pass (Manager::safe_pass()): the actuators hold what it output; the
  /// step counter is that of the last step.
  virtual void on_safe(const Manager& /*manager*/) {}
};

/// Decides after each step, before the observers see it, whether the run should stop there
/// (`arbiter run --break`, docs/cli.md "Breakpoints"). Called on the stepping thread: it must not
/// allocate, look up a name or throw.
class StepCheck {
 public:
  virtual ~StepCheck() = default;
  /// What made the step a break, or nullptr: a text that stays valid at least until the next
  /// step (the step's event and break_text() point at it).
  virtual const char* check(const Manager& manager) = 0;
};

/// Seconds since the run started, for the step records' `"t"` and `"duration"`. The host injects
/// it (`arbiter run`: the steady clock); tests use a manual one, so their traces stay exact.
/// now() is called twice per step on the stepping thread: it must not allocate.
class StepClock {
 public:
  virtual ~StepClock() = default;
  virtual double now() = 0;
};

namespace detail {
struct Carryover;  // carryover.hpp, not installed: the Reloader builds it
}  // namespace detail

class Manager {
 public:
  /// Reports (StepContext::report) kept per step; later ones are dropped.
  static constexpr std::size_t kEventsPerStep = 64;
  /// Primitives and their points drawn per step (StepContext::scene); later ones are dropped.
  static constexpr std::size_t kScenePrimitivesPerStep = 128;
  static constexpr std::size_t kScenePointsPerStep = 512;
  /// Room for the frames' names and the texts of a step's picture: as much as the most
  /// primitives may take, so that only the primitives and the points run out.
  static constexpr std::size_t kSceneStringBytesPerStep =
      kScenePrimitivesPerStep * (ScenePrimitive::kFrameBytes + ScenePrimitive::kTextBytes);

  /// Takes the program; run-time warnings go to `logger` (default: spdlog's default logger).
  explicit Manager(Program program, std::shared_ptr<spdlog::logger> logger = nullptr);
  ~Manager();
  Manager(Manager&&) noexcept;  // buffers live on the heap: their addresses survive
  Manager& operator=(Manager&&) = delete;
  Manager(const Manager&) = delete;
  Manager& operator=(const Manager&) = delete;

  /// One step of docs/semantics.md, "A step": input pass, every layer, output pass, then the
  /// observers. Does nothing once stopped().
  void step();

  /// True once behaviour or interface code under `on_exception: stop` threw (or, under a
  /// config-wide stop, a state machine stopped with an error): the step in which it happened was
  /// completed and seen by the observers; later step() calls do nothing. The host should end
  /// the run (and call finish()).
  bool stopped() const { return stopped_; }
  /// Why the manager stopped: the exception's report (who, where, what); "" unless stopped().
  const std::string& stop_reason() const { return stop_reason_; }

  /// The safe-value pass of a pausing or stopping engine (docs/config.md): every actuator with
  /// a `safe:` value carries it, written; every other keeps its value, unwritten; then the
  /// interface layers' output pass runs and the observers' on_safe(). Steps no behaviour and
  /// does not count as a step; the next step() continues as usual. Runs also when stopped() (that
  /// is when it matters); does nothing before the first step or when no actuator has a safe
  /// value. finish() runs it first. Allocates nothing.
  void safe_pass();
  /// True during the observers' on_safe().
  bool in_safe_pass() const { return in_safe_pass_; }
  /// How many safe-value passes ran.
  std::uint64_t safe_passes() const { return safe_passes_; }

  /// Asks `check` after every step from now on (nullptr: none); not owned. A step it stops at
  /// carries the text it returned as an event reported by kBreakSource, so that traces,
  /// recordings and views mark it.
  void set_check(StepCheck* check) { check_ = check; }
  /// The text of the check that fired in the last step, or nullptr.
  const char* break_text() const { return break_text_; }
  /// The source of a break's event: event_source() names it "break".
  static constexpr std::uint32_t kBreakSource = kNoIndex - 1;

  /// From the next step on, a step's picture is what interface layers draw in its input pass
  /// alone: what behaviours, states and the output pass draw is ignored. A replay of the
  /// recorded config sets it, as the recorded picture its interface draws holds what the
  /// behaviours drew (docs/replay.md).
  void keep_input_pass_scene_only(bool only) { input_pass_scene_only_ = only; }

  /// Times every step from now on (nullptr: none); not owned.
  void set_clock(StepClock* clock) { clock_ = clock; }
  bool timed() const { return clock_ != nullptr; }
  /// With a clock: when the last step (or safe pass) started, and how long it took, in seconds.
  double step_time() const { return step_time_; }
  double step_duration() const { return step_duration_; }

  /// Observers are not owned; they must outlive the manager or be removed. Add and remove them
  /// while no other thread stages a program: stage() and withdraw() call them too.
  void add_observer(Observer& observer);
  void remove_observer(Observer& observer);
  /// Tells the observers that the run is over (e.g. to close a trace).
  void finish();

  /// Hot reload, first half (docs/hot_reload.md); Reloader does all of it for a config file.
  /// Prepares on the calling thread everything the swap of `program` needs (buffers sized for
  /// it, the carry-over `carryover`, made against program()) and hands it to step(), which swaps
  /// it in at its start without allocating, then calls the observers' on_reload(). Replaces a
  /// staged program not yet swapped in. One thread at a time may stage and withdraw, while
  /// another steps; step() never waits for it. Throws std::invalid_argument when the
  /// carry-over's sizes or indices do not fit the two programs.
  void stage(Program program, detail::Carryover carryover);
  /// Takes back a staged program not swapped in yet (returns true then) and frees what the last
  /// swap replaced (the old program and its instances). stage() frees that too. Both wait, when
  /// they must, until the observers' on_reload() of that swap returned, and then until their
  /// on_retiring() returns (a recorder's writer may still be writing the replaced program's last
  /// steps), as observers may read the replaced program until then. Until the next stage(),
  /// program() then stays as it is, so the staging thread may read it while another thread steps.
  bool withdraw();
  /// How many staged programs step() has swapped in.
  std::uint64_t reloads() const;
  /// Which stage() the running program came from, as Observer::on_staged() numbered it (0: the
  /// program the manager was made with).
  std::uint64_t stage_number() const { return stage_number_; }

  /// The running program. Another thread may read it only between withdraw() and stage().
  const Program& program() const { return program_; }
  /// Steps completed so far.
  std::uint64_t steps() const { return data_.step; }

  double requested(std::uint32_t behaviour) const { return run_.requested[behaviour]; }
  double activation(std::uint32_t behaviour) const { return run_.activation[behaviour]; }
  bool active(std::uint32_t behaviour) const { return run_.active[behaviour] != 0; }
  /// The same of every behaviour, by index (active: non-zero), for observers that copy them
  /// whole.
  const double* requested_levels() const { return run_.requested; }
  const double* activation_levels() const { return run_.activation; }
  const char* active_flags() const { return run_.active; }
  /// The actuator's current value (of its ValueType) and whether it was written this step.
  const void* actuator_value(std::uint32_t actuator) const {
    return run_.values + program_.actuator_offsets[actuator];
  }
  bool actuator_written(std::uint32_t actuator) const {
    return run_.actuator_written[actuator] != 0;
  }
  /// The same of every actuator, by index, for observers that copy them whole.
  const bool* actuator_written_flags() const { return run_.actuator_written; }
  /// All of the above in one run of bytes, laid out by tracked_layout(), for observers that copy
  /// them at every step.
  const std::byte* tracked_parts() const { return run_.tracked.data(); }
  const TrackedLayout& tracked_layout() const { return run_.tracked_layout; }
  /// Events that behaviour and interface code reported in the last step (StepContext::report).
  std::size_t event_count() const { return std::min(data_.event_count, data_.event_capacity); }
  /// How many of those were reported in the input pass (the first ones): a replay reports
  /// an interface's again in the same pass.
  std::size_t input_pass_events() const { return input_pass_events_; }
  const detail::StepData::Event& event(std::size_t index) const { return events_[index]; }
  /// Who reported an event: a behaviour's or an interface layer's name.
  const std::string& event_source(const detail::StepData::Event& event) const;
  /// What code drew in the last step (StepContext::scene): its primitives, their points, and
  /// how many were dropped for want of room.
  const detail::SceneData& scene() const { return data_.scene; }
  std::size_t scene_primitive_count() const {
    return std::min(data_.scene.primitive_count, data_.scene.primitive_capacity);
  }
  /// Primitives dropped in all steps so far.
  std::uint64_t scene_dropped_total() const { return scene_dropped_total_; }

  template <typename T>
  const T& actuator(std::uint32_t actuator) const {
    return *static_cast<const T*>(actuator_value(actuator));
  }

 private:
  void run_layer(const CompiledLayer& layer);
  // The passes of run_layer() over behaviours [begin, end) (docs/semantics.md, "A step").
  void update_behaviours(std::uint32_t begin, std::uint32_t end);
  void request_and_refine(std::uint32_t begin, std::uint32_t end);
  void execute_behaviours(std::uint32_t begin, std::uint32_t end);
  void resolve_actuators(const CompiledLayer& layer);
  // Faults of behaviour code (docs/robustness.md).
  /// The callbacks of behaviour and interface code, as named in fault reports.
  enum class Callback { kUpdate, kActivation, kExecute, kInhibited, kInput, kOutput, kCarryOver };
  static const char* name(Callback callback);
  void report_exception(std::uint32_t behaviour, Callback callback, const char* what);
  void finish_faults();
  double non_finite_level(std::uint32_t behaviour, double level);
  void report_non_finite_write(std::uint32_t slot);

  struct Staged;     // a program, its run state and the carry-over from the running one
  struct Reloading;  // the hand-over between stage() and step(); on the heap: Manager moves
  std::unique_ptr<Staged> prepare(Program program, detail::Carryover carryover) const;
  void swap_in(Staged& staged) noexcept;
  void point_step_data() noexcept;
  /// Starts a step's picture afresh, counting what the last one dropped.
  void clear_scene() noexcept {
    scene_dropped_total_ += data_.scene.dropped;
    data_.scene.primitive_count = data_.scene.point_count = data_.scene.dropped = 0;
    data_.scene.string_size = data_.scene.frame_count = 0;
    data_.scene.muted = false;
  }
  void apply(Staged& staged);
  void end_replaced(Staged& staged);
  /// Observer::on_retiring() for what a swap replaced, before it is freed.
  void retire(const Staged* retired) const;
  void carry_values(const Staged& staged);

  Program program_;
  RunState run_;  // the running program's; a reload swaps it whole with the staged one
  std::unique_ptr<Reloading> reloading_;
  std::shared_ptr<spdlog::logger> logger_;
  std::unique_ptr<Behaviour> inert_;  // stands in for a behaviour whose code threw
  bool stopping_ = false;
  bool stopped_ = false;
  std::string stop_reason_;
  bool in_safe_pass_ = false;
  std::uint64_t safe_passes_ = 0;
  StepClock* clock_ = nullptr;
  StepCheck* check_ = nullptr;
  const char* break_text_ = nullptr;
  double step_time_ = 0.0;
  double step_duration_ = 0.0;
  std::size_t input_pass_events_ = 0;
  std::uint64_t stage_number_ = 0;
  std::vector<Observer*> observers_;
  std::vector<detail::StepData::Event> events_;
  std::vector<char> report_text_;  ///< the text slots of formatted reports (StepContext::report)
  std::vector<ScenePrimitive> scene_primitives_;
  std::vector<ScenePoint> scene_points_;
  std::vector<char> scene_strings_;
  std::vector<std::uint16_t> scene_frames_;
  std::uint64_t scene_dropped_total_ = 0;
  bool input_pass_scene_only_ = false;
  detail::StepData data_;
};

}  // namespace arbiter
