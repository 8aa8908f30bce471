#pragma once
// The step record of the trace (docs/semantics.md, "The trace") and of recordings, in two halves:
// StepSnapshot::capture() copies a step's values out of the manager into storage sized when the
// program was loaded (no allocation: a recorder does it on the stepping thread), and
// append_step_record() formats a snapshot, wherever and whenever it runs (a recorder's writer
// thread). Both the trace writer and the recorder go through them, so their records are the same
// bytes.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "arbiter/controller.hpp"
#include "arbiter/manager.hpp"
#include "arbiter/trace.hpp"

namespace arbiter::detail {

/// What formatting needs of a program besides a step's values: names, ranges and closed
/// inhibitions, copied, so that a snapshot can be formatted after a hot reload replaced (and
/// freed) the program it was taken from.
struct StepLayout {
  explicit StepLayout(const Program& program);

  struct Layer {
    std::string name;
    std::uint32_t behaviour_begin = 0, behaviour_end = 0;
    std::uint32_t actuator_begin = 0, actuator_end = 0;
    bool interface = false;
  };
  struct Actuator {
    std::string name;
    const ValueType* type = nullptr;
    std::size_t offset = 0;
  };
  struct State {
    std::string name;
    const ClassInfo* cls = nullptr;
  };
  struct Machine {
    std::string name;
    std::vector<State> states;
    std::size_t capacity = 0;     // the longest queue
    std::size_t most_params = 0;  // of any of its states' classes
  };
  std::vector<Layer> layers;
  std::vector<std::string> behaviours;
  /// Behaviour b's closed inhibitors: inhibitors[inhibitor_begin[b] .. inhibitor_begin[b + 1]).
  std::vector<std::uint32_t> inhibitor_begin;
  std::vector<std::uint32_t> inhibitors;
  std::vector<Actuator> actuators;
  std::size_t value_bytes = 0;
  /// Every actuator's value is a built-in number, vector or flag: the values copy as bytes.
  bool plain_values = true;
  std::vector<Machine> machines;
};

/// One step's values, as append_step_record() prints them. Sized for a layout by size_for();
/// capture() then allocates nothing (unless told it may grow).
class StepSnapshot {
 public:
  StepSnapshot() = default;
  ~StepSnapshot();
  StepSnapshot(const StepSnapshot&) = delete;
  StepSnapshot& operator=(const StepSnapshot&) = delete;

  /// Storage for every value of `layout`'s program, and `text_bytes` of reported text.
  void size_for(const StepLayout& layout, std::size_t text_bytes);
  /// The behaviours' levels and active flags, the bulk of a big graph's step.
  struct Levels {
    std::vector<double> requested;
    std::vector<double> activation;
    std::vector<char> active;
  };
  /// Behaviours per block of levels that a chained capture copies or skips as one.
  static constexpr std::size_t kLevelBlock = 8;

  /// Copies the manager's last step (or safe pass). False when something does not fit the
  /// storage (reported text, a string value longer than its reserve) and `grow` is false: the
  /// snapshot is then incomplete and must not be formatted. With `grow`, it makes room.
  /// With `last` (the levels as the previous snapshot left them, kept up to date here) and
  /// `chained` (that snapshot will be formatted just before this one), only the blocks of levels
  /// that changed are copied (levels_full false): a reader brings its own levels up to date
  /// with apply_levels(), in order.
  bool capture(const Manager& manager, const StepLayout& layout, bool grow = false,
               Levels* last = nullptr, bool chained = false);
  /// Brings `current` (a reader's levels, of the snapshots before this one) up to this one's.
  void apply_levels(Levels& current) const;
  /// Exchanges the snapshot's levels with `levels`: after apply_levels(), so that the snapshot
  /// holds all of them to be formatted; again after, to give them back.
  void swap_levels(Levels& levels) {
    requested.swap(levels.requested);
    activation.swap(levels.activation);
    active.swap(levels.active);
  }

  struct Machine {
    std::uint64_t cycle = 0;
    ControllerStatus status = ControllerStatus::kRunning;
    std::uint32_t current = kNoState;  // state index
    const std::vector<Param>* planned = nullptr;
    std::uint32_t args_begin = 0, args_count = 0;  // into current_args
    std::uint32_t queue_begin = 0, queue_count = 0;
    std::uint32_t events_begin = 0, events_count = 0;
  };
  struct Report {
    std::uint32_t source = 0;
    std::uint32_t text_begin = 0, text_size = 0;
  };

  std::uint64_t step = 0;
  bool safe = false;
  bool timed = false;
  double t = 0.0;
  double duration = 0.0;
  std::vector<double> requested;
  std::vector<double> activation;
  std::vector<char> active;
  /// False: requested, activation and active hold only the blocks in changed_blocks.
  bool levels_full = true;
  std::vector<std::uint32_t> changed_blocks;
  std::size_t changed_count = 0;
  std::vector<char> written;
  std::vector<Machine> machines;
  std::vector<std::pair<std::uint32_t, ArgValue>> current_args;
  std::vector<std::uint32_t> queue;
  std::vector<Controller::Event> events;  // args_begin rebased into event_args
  std::vector<Controller::EventArg> event_args;
  std::size_t report_count = 0;
  std::vector<Report> reports;
  std::string texts;

  const void* value(const StepLayout& layout, std::uint32_t actuator) const {
    return values_.get() + layout.actuators[actuator].offset;
  }

 private:
  void release();
  std::unique_ptr<std::byte[]> values_;
  // What values_ holds when the values are not plain: constructed per type, destroyed here.
  std::vector<std::pair<const ValueType*, std::size_t>> constructed_;
};

/// The step record of a snapshot, without the newline.
void append_step_record(const StepLayout& layout, const StepSnapshot& step, std::string& out);
/// The `/arbiter/inputs` message of a snapshot (see append_inputs_record in recording.hpp).
void append_inputs_record(const StepLayout& layout, const StepSnapshot& step, std::string& out);

/// Why a state ended, from a deactivation event and a function naming a state index.
template <typename Name>
StateEnd make_state_end(const Controller::Event& event, Name name) {
  const auto named = [&](std::uint32_t state) {
    return state == kNoState ? std::string() : std::string(name(state));
  };
  StateEnd end;
  end.state = named(event.state);
  end.cause = cause_name(event.cause);
  if (event.cause == Controller::EndCause::kTerminated) {
    end.by = named(event.other);
  } else {
    end.to = named(event.other);
  }
  if (event.preempt != kUnbound) end.preempt = event.preempt;
  end.proceeded = event.proceeded;
  return end;
}

/// "activate", "execute" or "deactivate".
const char* event_verb(Controller::Event::Kind kind);

/// A param's value as JSON; not `exact`: numbers to 4 significant digits (short_number()).
void append_param_json(const ParamValue& value, bool exact, std::string& out);

/// Per-instance params of a state of class `cls`: those `planned` in the config, then `args`
/// (param index, value) from Plan calls; see event_params() in trace.hpp.
template <typename Args, typename ValueOf>
ParamTexts merged_params(const ClassInfo& cls, const std::vector<Param>* planned, const Args& args,
                         ValueOf value_of, bool exact) {
  ParamTexts out;
  const auto set = [&](const std::string& name, const ParamValue& value) {
    std::string json;
    append_param_json(value, exact, json);
    for (auto& [known, text] : out) {
      if (known == name) {
        text = std::move(json);
        return;
      }
    }
    out.emplace_back(name, std::move(json));
  };
  if (planned != nullptr) {
    for (const auto& param : *planned) set(param.name, param.value);
  }
  for (const auto& arg : args) set(cls.params[arg.first].name, value_of(arg.second));
  return out;
}

}  // namespace arbiter::detail
