#pragma once
// The C++ API for behaviour and interface classes: typed port handles and the narrow context each
// callback receives. Handles are indices resolved once in init(); the step reads and writes
// through them without looking up a name.

#include <fmt/format.h>

#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <typeinfo>
#include <utility>
#include <variant>
#include <vector>

#include "arbiter/diagnostics.hpp"
#include "arbiter/document.hpp"
#include "arbiter/scene.hpp"
#include "arbiter/value.hpp"

namespace arbiter {

/// The index that names nothing. Each role it plays has its own name, so that a reader knows
/// which absence is meant.
inline constexpr std::uint32_t kNoIndex = std::numeric_limits<std::uint32_t>::max();
/// A port, input or output bound to no actuator (an optional port with nothing to bind).
inline constexpr std::uint32_t kUnbound = kNoIndex;
/// No behaviour: the layer's interface writes, or the code runs outside any behaviour.
inline constexpr std::uint32_t kNoBehaviour = kNoIndex;
/// No controller: a state machine with no parent, a state with no child machine.
inline constexpr std::uint32_t kNoController = kNoIndex;
/// No state: a state machine that is not in any state.
inline constexpr std::uint32_t kNoState = kNoIndex;

/// Reads the actuator a sensor names. Unbound (an optional port with nothing to bind) reads the
/// type's zero value.
template <typename T>
struct Input {
  std::uint32_t actuator = kUnbound;
  bool bound() const { return actuator != kUnbound; }
};

/// Writes one behaviour's contribution to an actuator of its own layer.
template <typename T>
struct Output {
  std::uint32_t slot = kUnbound;
  bool bound() const { return slot != kUnbound; }
};

/// An output whose type is known only at load (e.g. the scripted behaviour's `writes`).
struct AnyOutput {
  std::uint32_t slot = kUnbound;
  const ValueType* type = nullptr;
};

/// A value of a type known only at load, owned; built by InitContext::make_value.
class ValueBox {
 public:
  ValueBox() = default;
  explicit ValueBox(const ValueType& type);
  ValueBox(ValueBox&& other) noexcept;
  ValueBox& operator=(ValueBox&& other) noexcept;
  ValueBox(const ValueBox&) = delete;
  ValueBox& operator=(const ValueBox&) = delete;
  ~ValueBox();

  const ValueType* type() const { return type_; }
  void* data() { return storage_.get(); }
  const void* data() const { return storage_.get(); }

 private:
  const ValueType* type_ = nullptr;
  std::unique_ptr<std::max_align_t[]> storage_;
};

namespace detail {

/// The manager's flat buffers, as the contexts see them. Owned by the Program.
struct StepData {
  std::byte* values = nullptr;
  const std::uint32_t* actuator_offset = nullptr;
  const bool* actuator_written = nullptr;
  const std::uint32_t* slot_offset = nullptr;
  const ValueType* const* slot_type = nullptr;
  bool* slot_written = nullptr;
  std::uint64_t step = 0;
  double period = 0.0;  ///< seconds per step, 1 / rate_hz
  /// Events reported this step (see StepContext::report), in a buffer sized at load.
  struct Event {
    std::uint32_t source;  ///< a behaviour index, or the number of behaviours + a layer index
    const char* text;
    std::uint32_t sequence;  ///< see `sequence` below
  };
  Event* events = nullptr;
  std::size_t event_capacity = 0;
  std::size_t event_count = 0;
  /// Counts what happens in the step, reports and state machine events alike (from 0 in every
  /// step), so that observers can tell them in the order they happened.
  std::uint32_t sequence = 0;
  /// The text of formatted reports: event_capacity slots of kReportBytes, laid out at load.
  char* report_text = nullptr;
  /// What code drew this step (StepContext::scene), in buffers sized at load.
  SceneData scene;
};

/// The bytes of a formatted report's text slot, its terminating NUL included.
inline constexpr std::size_t kReportBytes = 128;

/// Ends the formatted text of `size` bytes in `text` (a kReportBytes slot that holds the first
/// kReportBytes - 1 of them): text cut short ends in "…", and no UTF-8 character is split.
inline void end_report(char* text, std::size_t size) {
  constexpr std::size_t kMax = kReportBytes - 1;
  if (size <= kMax) {
    text[size] = '\0';
    return;
  }
  constexpr char kEllipsis[] = "\xE2\x80\xA6";
  std::size_t end = kMax - (sizeof kEllipsis - 1);
  while (end > 0 && (static_cast<unsigned char>(text[end]) & 0xC0) == 0x80) --end;
  std::memcpy(text + end, kEllipsis, sizeof kEllipsis);
}

template <typename T>
const T& zero_value() {
  static const T kZero{};
  return kZero;
}

}  // namespace detail

/// What every step callback may do: read sensors and know the step.
class StepContext {
 public:
  StepContext(detail::StepData& data, std::uint32_t self) : data_(&data), self_(self) {}

  template <typename T>
  const T& read(Input<T> input) const {
    if (!input.bound()) return detail::zero_value<T>();
    return *reinterpret_cast<const T*>(data_->values + data_->actuator_offset[input.actuator]);
  }
  /// Whether the value read was written in the step it comes from (see docs/semantics.md, "Timing:
  /// the one-step delay" for which).
  template <typename T>
  bool written(Input<T> input) const {
    return input.bound() && data_->actuator_written[input.actuator];
  }
  /// The step being executed, counting from 1.
  std::uint64_t step() const { return data_->step; }
  /// The nominal time between steps, 1 / rate_hz of the config, in seconds.
  double period() const { return data_->period; }
  /// Tells observers (the terminal view of `arbiter run`, ...) that something happened this
  /// step, e.g. "ball kicked". `text` must outlive the step (a string literal). Allocation-free;
  /// beyond a per-step capacity further events are dropped.
  void report(const char* text) const {
    if (data_->event_count < data_->event_capacity) {
      data_->events[data_->event_count] = {self_, text, data_->sequence};
    }
    ++data_->event_count;
    ++data_->sequence;
  }
  /// Reports text formatted as fmt::format would (`ctx.report("room {} started", room)`), into
  /// a buffer of the step laid out at load: allocation-free for numbers, strings and every type
  /// whose formatter allocates nothing. Text longer than kReportBytes - 1 bytes is cut and ends in
  /// "…". C++20 checks the format string when compiling; under C++17, one that does not fit its
  /// arguments is reported as written, followed by " (bad format)", rather than throwing.
  template <typename... Args>
  void report(fmt::format_string<Args...> format, Args&&... args) const {
    if (data_->event_count < data_->event_capacity && data_->report_text != nullptr) {
      char* text = data_->report_text + data_->event_count * detail::kReportBytes;
      try {
        detail::end_report(text, fmt::format_to_n(text, detail::kReportBytes - 1, format,
                                                  std::forward<Args>(args)...)
                                     .size);
      } catch (const fmt::format_error&) {
        detail::end_report(text, fmt::format_to_n(text, detail::kReportBytes - 1, "{} (bad format)",
                                                  fmt::string_view(format))
                                     .size);
      }
      data_->events[data_->event_count] = {self_, text, data_->sequence};
    }
    ++data_->event_count;
    ++data_->sequence;
  }
  /// Draws the world this step, in `frame` (copied): see Scene. Allocation-free.
  Scene scene(const char* frame) const { return Scene(data_->scene, frame); }

 protected:
  friend class Controller;  // numbers its events in the step's sequence
  detail::StepData* data_;
  std::uint32_t self_;
};

/// An interface's input(): reads sensors and writes actuators; a second write to one output
/// replaces the first.
class WriteContext : public StepContext {
 public:
  WriteContext(detail::StepData& data, std::uint32_t self) : StepContext(data, self) {}

  template <typename T>
  void write(Output<T> output, const T& value) {
    if (!output.bound()) return;
    *reinterpret_cast<T*>(data_->values + data_->slot_offset[output.slot]) = value;
    data_->slot_written[output.slot] = true;
  }
  void write(AnyOutput output, const ValueBox& value) {
    if (output.slot == kUnbound) return;
    output.type->assign(data_->values + data_->slot_offset[output.slot], value.data());
    data_->slot_written[output.slot] = true;
  }
};

/// A behaviour's execute(): writes like an interface's input(), and knows its activation.
class ExecuteContext : public WriteContext {
 public:
  ExecuteContext(detail::StepData& data, std::uint32_t self, double activation, bool just_activated)
      : WriteContext(data, self), activation_(activation), just_activated_(just_activated) {}

  /// This behaviour's refined activation level this step, in (0, 1].
  double activation() const { return activation_; }
  bool just_activated() const { return just_activated_; }

 private:
  double activation_;
  bool just_activated_;
};

/// inhibited(): the behaviour is inactive this step; it may read sensors but not write.
class InhibitedContext : public StepContext {
 public:
  InhibitedContext(detail::StepData& data, std::uint32_t self, bool just_deactivated)
      : StepContext(data, self), just_deactivated_(just_deactivated) {}
  bool just_deactivated() const { return just_deactivated_; }

 private:
  bool just_deactivated_;
};

class InitContext;
class BehaviourInitContext;

/// A behaviour of the BCF. Callbacks run in this order each step (docs/semantics.md, "A step"):
/// update(), then activation() for every behaviour of the layer, then execute() or inhibited().
class Behaviour {
 public:
  virtual ~Behaviour() = default;
  /// Reads params and resolves ports; problems go to ctx.error() and fail the load.
  virtual void init(BehaviourInitContext& /*ctx*/) {}
  virtual void update(const StepContext& /*ctx*/) {}
  /// The requested activation level; clamped to [0, 1], NaN counts as 0.
  virtual double activation(const StepContext& ctx) = 0;
  virtual void execute(ExecuteContext& /*ctx*/) {}
  virtual void inhibited(const InhibitedContext& /*ctx*/) {}

  /// Hot reload (docs/hot_reload.md). A behaviour whose layer, name, class, params and port
  /// handles are unchanged simply keeps its instance. When its params or handles changed, a new
  /// instance is initialised with the new config (init() as usual, off the step path), and at
  /// the swap, inside step(), it is offered the instance it replaces: `previous` has this
  /// class. Return true after taking over its run-time state (counters, memories, ...; not
  /// handles or params: those are this instance's own); the behaviour then also keeps its
  /// activation history. Return false (the default) to start afresh: `previous` gets a final
  /// inhibited() call and the new instance counts as inactive before its first step. Runs on
  /// the stepping thread, so it must not allocate, block or throw.
  virtual bool carry_over(Behaviour& /*previous*/) { return false; }
};

/// The class behind an interface layer: moves data between the engine and the outside world.
class Interface {
 public:
  virtual ~Interface() = default;
  virtual void init(InitContext& /*ctx*/) {}
  /// Input pass, every step: writes this layer's actuators (its output ports). An interface is
  /// never inhibited, so it has no activation; its first step is `ctx.step() == 1`.
  virtual void input(WriteContext& /*ctx*/) {}
  /// Output pass: reads this layer's sensors (its input ports).
  virtual void output(const StepContext& /*ctx*/) {}
  /// Hot reload: as Behaviour::carry_over, for an interface whose params or handles changed.
  virtual bool carry_over(Interface& /*previous*/) { return false; }
};

}  // namespace arbiter
